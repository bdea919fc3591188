"""What the hostile suite must cover, read from the code itself: the command line's verbs and
options (from its argparse parsers) and the keys of scene and study files (from their parsers,
:func:`cayley_heyoka.core.scene.recording_keys`, while the corpus of ``corpus.py`` is parsed).

A key is named by its dotted path with user-chosen names and list positions generalised:
``orbit.elements.e``, ``events.*.expression``, ``hamiltonian.bodies[*].mass``,
``sweep.parameters.*.start``.
"""

from __future__ import annotations

import argparse
import functools
import re
from collections.abc import Iterator
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path
from typing import Any

import corpus

from cayley_heyoka.cli import VERBS
from cayley_heyoka.core.scene import Scene, recording_keys
from cayley_heyoka.workflows.study import Study

_TOKEN = re.compile(r'"[^"]*"|\[\d+\]|[^.\[\]]+')


def cli_surface() -> list[str]:
    """``verb:NAME`` for each verb and ``option:NAME --OPTION`` (its longest spelling) or
    ``option:NAME ARGUMENT`` for each of its arguments, help excepted."""
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    for verb in VERBS:
        import_module(f"cayley_heyoka.cli.{verb}").add_parser(sub)
    out = []
    for verb, p in sub.choices.items():
        out.append(f"verb:{verb}")
        for action in p._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            name = max(action.option_strings, key=len) if action.option_strings else action.dest
            out.append(f"option:{verb} {name}")
    return out


@dataclass(frozen=True)
class Key:
    """A key the parsers allow, and where a corpus document sets it."""

    kind: str  # "scene" or "study"
    name: str  # the generalised dotted path
    document: str | None  # the corpus document that sets it (None: none does)
    path: tuple[Any, ...] | None  # its concrete path there (keys and list indices)

    @property
    def coverage(self) -> str:
        return f"{'key' if self.kind == 'scene' else 'study-key'}:{self.name}"


def _tokens(where: str) -> list[str]:
    return _TOKEN.findall(where)


class _Tables:
    """The tables the parsers checked, by generalised path, and the keys each allows."""

    def __init__(self) -> None:
        self.allowed: dict[str, set[str]] = {}

    def add(self, calls: list[tuple[str, tuple[str, ...]]]) -> None:
        # Parents are checked before their children, so each call generalises with what the
        # calls before it recorded.
        for where, allowed in calls:
            self.allowed.setdefault(self.general(_tokens(where)), set()).update(allowed)

    def general(self, tokens: list[Any]) -> str:
        """The generalised path of a concrete one (tokens: keys, and ``[i]`` or int indices)."""
        out = ""
        for token in tokens:
            if isinstance(token, int) or (
                isinstance(token, str) and re.fullmatch(r"\[\d+\]", token)
            ):
                out += "[*]"
                continue
            key = token[1:-1] if token.startswith('"') else token
            fixed = key in self.allowed.get(out, ())
            out = f"{out}.{key if fixed else '*'}" if out else (key if fixed else "*")
        return out

    def keys(self) -> set[str]:
        return {f"{t}.{k}" if t else k for t, allowed in self.allowed.items() for k in allowed}


def _set_paths(data: Any, path: tuple = ()) -> Iterator[tuple]:
    """Every key path a document sets (descending into lists of tables only)."""
    if isinstance(data, dict):
        for key, value in data.items():
            yield (*path, key)
            yield from _set_paths(value, (*path, key))
    elif isinstance(data, list) and data and all(isinstance(v, dict) for v in data):
        for i, value in enumerate(data):
            yield from _set_paths(value, (*path, i))


def study_scene(doc: dict[str, Any]) -> dict[str, Any]:
    """A corpus study with its ``scene`` resolved: a corpus scene's name becomes that scene
    (a table in the study); anything else (a hostile value) stays."""
    scene = doc.get("scene")
    if isinstance(scene, str) and scene in corpus.scenes():
        doc = {**doc, "scene": corpus.scenes()[scene]}
    return doc


def parse(kind: str, doc: dict[str, Any]) -> Any:
    """Parse a corpus document as ``kind`` does (bundled studies relative to their folder)."""
    if kind == "scene":
        return Scene.from_dict(doc)
    return Study.from_dict(study_scene(doc))


@functools.cache
def keys() -> tuple[Key, ...]:
    """Every key the parsers allow, with a corpus document that sets it where one does."""
    found: list[Key] = []
    for kind, docs in (("scene", corpus.scenes()), ("study", corpus.studies())):
        tables = _Tables()
        for doc in docs.values():
            with recording_keys() as calls:
                parse(kind, doc)
            if kind == "study":
                # The study's own tables: its root (checked first) and what lies below it;
                # the base scene's calls are the scene schema's.
                calls = calls[:1] + [
                    c for c in calls[1:] if c[0] and c[0].split(".")[0] in calls[0][1]
                ]
            tables.add(calls)
        where_set: dict[str, tuple[str, tuple]] = {}
        for name, doc in docs.items():
            for path in _set_paths(doc):
                where_set.setdefault(tables.general(list(path)), (name, path))
        for name in sorted(tables.keys()):
            document, path = where_set.get(name, (None, None))
            found.append(Key(kind, name, document, path))
    return tuple(found)


def document(key: Key) -> dict[str, Any]:
    """A fresh copy of the corpus document that sets ``key``."""
    docs = corpus.scenes() if key.kind == "scene" else corpus.studies()
    assert key.document is not None, f"no corpus document sets {key.name}"
    return docs[key.document]


ROOT = Path(__file__).resolve().parents[2]
