"""The tutorials are notebooks that the docs build executes, and fails on.

The docs build (README, "Documentation"; docs/conf.py) runs every tutorial in docs/tutorials
as a MyST-NB notebook, regenerating its outputs and failing on a command that exits with an
unexpected status or on an assertion about the prose; so the tutorials are not run a second
time here. These checks are structural and take no time: each tutorial is a notebook the
build executes, in a scratch directory, with no output pasted into its source, and the
``%%shell`` cells they rely on fail when a command does.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"
TUTORIALS = sorted((DOCS / "tutorials").glob("*.md"))
_FENCE = re.compile(r"^```(?P<info>[^\n`]*)$", re.MULTILINE)


def _fences(text: str) -> list[str]:
    """The info string of each opening fence (the closing ones are dropped in pairs)."""
    return [m["info"].strip() for m in _FENCE.finditer(text)][::2]


def _module(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_there_are_tutorials():
    assert len(TUTORIALS) >= 4, TUTORIALS


@pytest.mark.parametrize("tutorial", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_is_an_executed_notebook(tutorial):
    text = tutorial.read_text()
    front = text.split("---\n")[1] if text.startswith("---\n") else ""
    assert "file_format: mystnb" in front, f"{tutorial.name}: not a MyST-NB notebook"
    assert "kernelspec:" in front, f"{tutorial.name}: names no kernel"
    fences = _fences(text)
    cells = [f for f in fences if f.startswith("{code-cell}")]
    assert cells, f"{tutorial.name}: has no code cell"
    # The first cell moves into a scratch copy of examples/, so that the build writes nothing
    # into the repository.
    first = text.split("```{code-cell}", 2)[1]
    assert "remove-cell" in first and "start()" in first, f"{tutorial.name}: no setup cell first"
    # Outputs come from the build; a fence without a language (or `text`) would be one pasted
    # in, and go stale unseen.
    stored = [f for f in fences if f in ("", "text", "output")]
    assert not stored, f"{tutorial.name}: output blocks pasted into the source: {stored}"


def test_every_tutorial_is_in_the_table_of_contents():
    index = (DOCS / "index.md").read_text()
    for tutorial in TUTORIALS:
        assert f"tutorials/{tutorial.stem}\n" in index, f"{tutorial.name} is in no toctree"


def test_the_build_executes_the_notebooks_and_fails_on_an_error():
    conf = _module(DOCS / "conf.py", "docs_conf")
    assert conf.nb_execution_mode == "force"
    assert conf.nb_execution_raise_on_error is True
    assert not getattr(conf, "nb_execution_allow_errors", False)
    assert not getattr(conf, "nb_execution_excludepatterns", ())


@pytest.fixture
def shell(monkeypatch):
    """The ``%%shell`` magic of docs/tutorials/tutorial_setup.py, outside a notebook."""
    IPython = pytest.importorskip("IPython")  # installed with the docs extra (ipykernel)
    namespace: dict = {}
    monkeypatch.setattr(IPython, "get_ipython", lambda: type("Shell", (), {"user_ns": namespace}))
    setup = _module(DOCS / "tutorials" / "tutorial_setup.py", "tutorial_setup")
    return lambda line, cell: (setup.shell(line, cell), namespace["shell_output"])[1]


def test_shell_cells_print_and_keep_the_output(shell, capsys):
    assert shell("", "echo one; echo two >&2") == "one\ntwo\n"
    assert capsys.readouterr().out == "one\ntwo\n"


@pytest.mark.parametrize(
    "cell",
    [
        "exit 3",
        "false; echo not reached",
        "false | cat",
        f"{sys.executable} -c 'raise SystemExit(2)'",
    ],
)
def test_shell_cells_fail_on_a_failing_command(shell, cell):
    with pytest.raises(RuntimeError, match="expected 0"):
        shell("", cell)


def test_shell_cells_expect_the_status_they_name(shell):
    assert shell("--exit 2", "echo refused; exit 2") == "refused\n"
    with pytest.raises(RuntimeError, match="exited 0, expected 2"):
        shell("--exit 2", "true")
