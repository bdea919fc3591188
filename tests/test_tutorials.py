"""Every tutorial in docs/tutorials runs as written.

A tutorial is Markdown whose fenced blocks run in order, in a scratch directory holding a copy
of ``examples/``, as a reader following it from the repository's root would:

* ``console`` blocks: each line starting with ``$ `` is a shell command (a trailing ``\\``
  continues it); the other lines are the output it printed when the tutorial was written.
  A command that exits non-zero fails the test unless the block is marked ``<!-- exit N -->``.
* ``python`` blocks run in one namespace per tutorial.
* A block preceded by ``<!-- not-run: reason -->`` is shown but not run (a scheduler address
  that exists only on the reader's cluster, say).
* ``<!-- file: NAME -->`` before a block writes the block's text to ``NAME`` instead of running
  it (a test module or a study file the tutorial goes on to use).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
TUTORIALS = sorted((ROOT / "docs" / "tutorials").glob("*.md"))

_FENCE = re.compile(
    r"(?:<!--\s*(?P<marker>[^>]*?)\s*-->\s*\n)?```(?P<lang>[\w-]*)\n(?P<body>.*?)\n```", re.DOTALL
)


def blocks(text: str) -> list[tuple[str, str, str]]:
    """(language, marker, body) of each fenced block, in order."""
    return [(m["lang"], m["marker"] or "", m["body"]) for m in _FENCE.finditer(text)]


def commands(console: str) -> list[str]:
    """The ``$ `` commands of a console block, continuation lines joined."""
    out: list[str] = []
    pending = ""
    for line in console.splitlines():
        if pending:
            pending += "\n" + line
        elif line.startswith("$ "):
            pending = line[2:]
        else:
            continue
        if not pending.endswith("\\"):
            out.append(pending)
            pending = ""
    return out


@pytest.mark.parametrize("tutorial", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_runs_as_written(tutorial, tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    env = dict(os.environ)
    # The interpreter running the tests, and its console scripts, come first on PATH.
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    namespace: dict = {"__name__": f"tutorial_{tutorial.stem}"}
    ran = 0
    for lang, marker, body in blocks(tutorial.read_text()):
        if marker.startswith("not-run"):
            continue
        if marker.startswith("file:"):
            target = tmp_path / marker.split(":", 1)[1].strip()
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_text(body + "\n")
            continue
        if lang == "python":
            exec(compile(body, f"{tutorial.name} (python block)", "exec"), namespace)
            ran += 1
        elif lang == "console":
            expected = int(marker.split()[1]) if marker.startswith("exit") else 0
            for command in commands(body):
                proc = subprocess.run(
                    ["bash", "-c", command], env=env, capture_output=True, text=True
                )
                assert proc.returncode == expected, (
                    f"{tutorial.name}: `{command}` exited {proc.returncode} "
                    f"(expected {expected})\n{proc.stdout}\n{proc.stderr}"
                )
                ran += 1
    assert ran, f"{tutorial.name} has nothing to run"
