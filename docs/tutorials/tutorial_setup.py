"""The hidden first cell of every tutorial: a scratch directory, ``%%shell`` and ``show``.

The tutorials are MyST-NB notebooks executed at every docs build (docs/conf.py). Each runs as
a reader following it from the repository's root would, but in a temporary directory holding
a copy of ``examples/``, so that the build writes no result file into the repository; the
directory is removed when the notebook's kernel exits.

``%%shell`` runs its cell with bash and prints what the commands print (standard error
merged, in order). IPython's own ``!cmd`` ignores a command's exit status; here a command
that exits non-zero fails the cell — and the build — unless the cell names the status it
expects (``%%shell --exit 2``, for a command shown failing). What the last ``%%shell`` cell
printed is kept in ``shell_output`` (as plain text), for the cells that check the prose
against it.
"""

from __future__ import annotations

import atexit
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
#: Terminal colour codes: the kernel asks for colour (pytest obliges), which the page renders,
#: but the checks of the prose read the plain text.
_COLOUR = re.compile(r"\x1b\[[0-9;]*m")


def start() -> Path:
    """Move into a fresh scratch copy of ``examples/`` and register ``%%shell``."""
    import matplotlib
    from IPython import get_ipython

    scratch = Path(tempfile.mkdtemp(prefix="cayley_heyoka_tutorial_"))
    atexit.register(shutil.rmtree, scratch, ignore_errors=True)
    shutil.copytree(ROOT / "examples", scratch / "examples")
    os.chdir(scratch)
    # The interpreter running the notebook, and its console scripts (cayley-heyoka), first.
    os.environ["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), os.environ["PATH"]])
    # Figures are shown from the files the tutorial writes (show()), where the text refers to
    # them, not a second time wherever a cell happens to draw one.
    matplotlib.use("agg")
    get_ipython().register_magic_function(shell, "cell")
    return scratch


def shell(line: str, cell: str) -> None:
    """``%%shell [--exit N]``: run the cell with bash; fail unless it exits with N (0)."""
    from IPython import get_ipython

    words = line.split()
    expected = int(words[words.index("--exit") + 1]) if "--exit" in words else 0
    # -e: any failing command ends the cell with its status; pipefail: `cmd | tail` too.
    proc = subprocess.run(
        ["bash", "-e", "-o", "pipefail", "-c", cell],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        encoding="utf-8",
        errors="replace",
    )
    print(proc.stdout, end="")
    get_ipython().user_ns["shell_output"] = _COLOUR.sub("", proc.stdout)
    if proc.returncode != expected:
        raise RuntimeError(f"the commands exited {proc.returncode}, expected {expected}")


def show(path: str | Path):
    """The PNG at ``path``, displayed as the cell's output."""
    from IPython.display import Image

    return Image(filename=str(path))
