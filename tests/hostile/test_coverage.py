"""The hostile suite knows what it must cover: every verb and option of the command line (from
its parsers), every key of scene and study files (from theirs: ``schema.py``), and every class
of issue 32's findings. A hostile case says what it covers with ``@pytest.mark.covers(...)``
(on the test, or on one of its ``pytest.param`` cases): ``"verb:run"``,
``"option:reference --tolerance"``, ``"key:orbit.elements.e"``, ``"study-key:run.scheduler"``,
``"class:6"``. An option or key added to a parser fails here until a case covers it.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import schema

HERE = Path(__file__).resolve().parent
#: The classes of bad outcomes of issue 32 (each one root cause, each with cases here).
CLASSES = [f"class:{n}" for n in range(1, 13)]


def _marks(obj: Any) -> Iterator[Any]:
    for mark in getattr(obj, "pytestmark", []):
        yield mark
        if mark.name == "parametrize":
            for value in mark.args[1] if len(mark.args) > 1 else mark.kwargs.get("argvalues", []):
                yield from getattr(value, "marks", ())


def declared() -> dict[str, list[str]]:
    """What each hostile test module's cases say they cover: coverage → test names."""
    found: dict[str, list[str]] = {}
    for path in sorted(HERE.glob("test_*.py")):
        module = importlib.import_module(path.stem)
        owners = [(path.stem, module)] + [
            (f"{path.stem}::{name}", obj)
            for name, obj in vars(module).items()
            if name.startswith("test") and callable(obj)
        ]
        for owner, obj in owners:
            for mark in _marks(obj):
                if mark.name == "covers":
                    for what in mark.args:
                        found.setdefault(what, []).append(owner)
    return found


def test_every_verb_and_option_has_a_hostile_case():
    covered = declared()
    missing = [what for what in schema.cli_surface() if what not in covered]
    assert not missing, "no hostile case covers: " + ", ".join(missing)


def test_every_key_the_parsers_allow_is_set_by_the_corpus():
    """The corpus reaches every key (so the generated cases try it): a key added to a parser
    needs a document in corpus.py that sets it."""
    unset = [k.coverage for k in schema.keys() if k.document is None]
    assert not unset, "no corpus document sets: " + ", ".join(unset)


def test_every_key_has_a_hostile_case():
    covered = declared()
    missing = [k.coverage for k in schema.keys() if k.coverage not in covered]
    assert not missing, "no hostile case covers: " + ", ".join(missing)


def test_every_class_of_the_findings_has_hostile_cases():
    covered = declared()
    missing = [c for c in CLASSES if c not in covered]
    assert not missing, "no hostile case covers: " + ", ".join(missing)


def test_declarations_name_what_exists():
    """A covers mark names a verb, option, key or class that exists (a renamed option must not
    leave its cases claiming what is gone)."""
    real = {*schema.cli_surface(), *(k.coverage for k in schema.keys()), *CLASSES}
    checked = ("verb:", "option:", "key:", "study-key:", "class:")
    stale = sorted(w for w in declared() if w.startswith(checked) and w not in real)
    assert not stale, "covers marks naming nothing that exists: " + ", ".join(stale)
