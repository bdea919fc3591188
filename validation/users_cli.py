"""The command line's start against importing heyoka (issue 16): ``python validation/users_cli.py``.

Each row times one command in a fresh process — the console script ``cayley-heyoka`` beside
``sys.executable`` when it is installed there (what users run), else ``python -m
cayley_heyoka`` — against ``python -c "import heyoka"`` in a fresh process, interleaved
(validation/users_common.py). Both run with this source tree first on ``PYTHONPATH``, so the
code measured is this tree's. The ``info`` row reads the result of a short run of
examples/free_body.toml made first in a temporary directory.

Run:  python validation/users_cli.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path

from users_common import Row, interleaved, table

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: The command line should start in at most this fraction of heyoka's import.
TARGET = 0.5
FLOOR = 'python -c "import heyoka"'


def command() -> tuple[list[str], str]:
    """How the command is started, and that in words."""
    script = Path(sys.executable).parent / "cayley-heyoka"
    if script.exists():
        return [str(script)], "the console script `cayley-heyoka`"
    return [sys.executable, "-m", "cayley_heyoka"], "`python -m cayley_heyoka`"


def _env() -> dict[str, str]:
    path = os.environ.get("PYTHONPATH")
    return {**os.environ, "PYTHONPATH": str(ROOT) + (os.pathsep + path if path else "")}


def _process(argv: list[str], cwd: Path) -> Callable[[], None]:
    env = _env()

    def start() -> None:
        subprocess.run(argv, cwd=cwd, env=env, stdout=subprocess.DEVNULL, check=True)

    return start


def rows(quick: bool) -> list[Row]:
    """One row per command: wall of the command ÷ wall of importing heyoka, each in a fresh
    process; ``quick`` (a smoke run) takes 3 repeats, else 21."""
    repeats = 3 if quick else 21
    cli, how = command()
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        result = work / "free_body.h5"
        scene = ROOT / "examples" / "free_body.toml"
        _process([*cli, "run", str(scene), "--out", str(result), "--no-progress"], work)()
        floor = _process([sys.executable, "-c", "import heyoka"], work)
        for what, args in (
            ("`cayley-heyoka --help`", ["--help"]),
            ("`cayley-heyoka --version`", ["--version"]),
            ("`cayley-heyoka info RESULT.h5` (a double result)", ["info", str(result)]),
        ):
            ratios, ours_s, floor_s = interleaved(_process([*cli, *args], work), floor, repeats)
            out.append(
                Row(
                    what=what,
                    ratios=ratios,
                    target=TARGET,
                    floor=FLOOR,
                    note=f"{how}; fastest {ours_s:.3f} s against {floor_s:.3f} s",
                    seconds={"ours": ours_s, "floor": floor_s},
                )
            )
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 repeats instead of 21")
    print(table(rows(parser.parse_args().quick)))


if __name__ == "__main__":
    main()
