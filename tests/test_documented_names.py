"""Every name the docs, README and printed summaries give a user imports.

A dotted ``cayley_heyoka.…`` name, or ``from cayley_heyoka… import a, b`` in a code block, is
resolved as a user would: the longest importable module prefix, then attributes."""

from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

from cayley_heyoka.workflows import members

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
DOTTED = re.compile(r"\bcayley_heyoka(?:\.[A-Za-z_]\w*)+")
FROM = re.compile(r"^\s*from (cayley_heyoka[\w.]*) import \(?([\w, ]+)\)?\s*$", re.M)
# File names, and dotted names that are not Python's: the entry-point group of family plugins
# and the format tags of our files.
NOT_NAMES = re.compile(r"\.(toml|h5|nc|json|csv|md|py)$")
NOT_PYTHON = {"cayley_heyoka.families", "cayley_heyoka.sweep", "cayley_heyoka.check"}


def resolve(name: str) -> object:
    """``name`` as ``import a.b`` then ``getattr``: the object, or ImportError/AttributeError."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:k]))
        except ModuleNotFoundError:
            continue
        for attr in parts[k:]:
            obj = getattr(obj, attr)
        return obj
    raise ImportError(name)


def _documented() -> list[tuple[str, str]]:
    found = set()
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        where = str(page.relative_to(ROOT))
        for m in DOTTED.finditer(text):
            if not NOT_NAMES.search(m.group()) and m.group() not in NOT_PYTHON:
                found.add((where, m.group()))
        for m in FROM.finditer(text):
            for name in m.group(2).split(","):
                if name.strip():
                    found.add((where, f"{m.group(1)}.{name.strip()}"))
    return sorted(found)


@pytest.mark.parametrize(("page", "name"), _documented())
def test_every_documented_name_imports(page: str, name: str) -> None:
    try:
        resolve(name)
    except (ImportError, AttributeError) as exc:
        pytest.fail(f"{page} names {name}, which does not import: {exc}")


def test_the_documented_submodules_import_as_modules() -> None:
    """``import cayley_heyoka.plots`` as well as ``from cayley_heyoka import plots``."""
    plots = importlib.import_module("cayley_heyoka.plots")
    from cayley_heyoka import plots as same

    assert plots is same
    assert callable(plots.drift)


@pytest.mark.parametrize("path", [members.PATH_LANES, members.PATH_RUN, members.PATH_ENSEMBLE])
def test_the_paths_a_sweep_summary_names_import(path: str) -> None:
    assert resolve(path) is not None


def test_pages_are_scanned() -> None:
    """The scan sees the names it is meant to check (a regex gone wrong checks nothing)."""
    names = {name for _, name in _documented()}
    assert {"cayley_heyoka.run", "cayley_heyoka.plots.drift"} <= names
