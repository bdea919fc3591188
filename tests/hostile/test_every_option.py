"""Every option of every verb, given hostile values: generated from the command line's own
parsers (``schema.cli_surface``), so that an option added to a verb is tried here from its
first commit.

Each verb runs on a tiny input (a three-step scene, a small result file, a study of two
members); each option of it gets the values of a palette chosen by what the option takes (a
number, a choice, a path, text), and a flag is given twice. Every case must end as the runner
requires (conftest.py), and a refusal must name the option (or, for a positional argument, the
value given).
"""

from __future__ import annotations

import argparse
from importlib import import_module
from pathlib import Path
from typing import Any

import pytest
from conftest import toml
from corpus import scenes

from cayley_heyoka.cli import VERBS

NUMBERS = ["", "junk", "-1", "0", "1e400", "nan", "9" * 400]
TEXTS = ["", "junk", "-1", "1e400", "nan", "x" * 5000]
PATHS = ["", "/nonexistent-directory/x", "x" * 300, "."]


def _parsers() -> dict[str, argparse.ArgumentParser]:
    parser = argparse.ArgumentParser()
    sub = parser.add_subparsers()
    for verb in VERBS:
        import_module(f"cayley_heyoka.cli.{verb}").add_parser(sub)
    return dict(sub.choices)


def _name(action: argparse.Action) -> str:
    return max(action.option_strings, key=len) if action.option_strings else action.dest


def _values(action: argparse.Action) -> list[str] | None:
    """The palette of ``action`` (None: a flag, which takes no value)."""
    if action.nargs == 0:
        return None
    if action.choices:
        return ["", "junk", str(next(iter(action.choices))).upper()]
    if action.type is Path:
        return PATHS
    if action.type in (int, float) or getattr(action.type, "__name__", "").startswith("_pos"):
        return NUMBERS
    return TEXTS


def _cases() -> list[Any]:
    cases = []
    for verb, parser in _parsers().items():
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            name = _name(action)
            covers = pytest.mark.covers(f"verb:{verb}", f"option:{verb} {name}")
            values = _values(action)
            for i, value in enumerate(values if values is not None else [None]):
                ident = f"{verb}-{name}-{'twice' if value is None else i}"
                cases.append(pytest.param(verb, action, value, id=ident, marks=covers))
    return cases


@pytest.fixture(scope="module")
def inputs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, list[str]]:
    """The verbs' base command lines on tiny inputs (each runs in well under a second)."""
    d = tmp_path_factory.mktemp("inputs")
    free = scenes()["free_body_quad"]
    free["integrator"]["precision"] = "double"
    scene = d / "scene.toml"
    scene.write_text(toml(free))
    study = d / "study.toml"
    study.write_text(
        toml(
            {
                "scene": str(scene),
                "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": [1, 2]}},
            }
        )
    )
    from cayley_heyoka.cli import main

    result = d / "result.h5"
    assert main(["run", str(scene), "--out", str(result), "--no-progress"]) == 0
    return {
        "run": ["run", str(scene), "--no-progress"],
        "info": ["info", str(result)],
        "check": ["check", str(scene)],
        "reference": ["reference", str(scene), "--digits", "8", "--out", str(d / "ref.h5")],
        "plot": ["plot", str(result), "--kind", "drift", "--out", str(d / "p.png")],
        "sweep": ["sweep", str(study), "--no-progress"],
        "plan": ["plan", str(scene), "--error", "1e-8"],
    }


def _argv(base: list[str], action: argparse.Action, value: str | None) -> list[str]:
    """``base`` with ``action`` given ``value`` (a flag: twice; a positional: in its place)."""
    verb, positional, rest = base[0], base[1], base[2:]
    if not action.option_strings:
        return [verb, value, *rest]
    name = _name(action)
    if value is None:
        return [*base, name, name]
    # Drop the option's own value from the base (--digits, --out, --kind, --error).
    kept, skip = [], False
    for item in rest:
        if skip:
            skip = False
            continue
        if item == name:
            skip = True
            continue
        kept.append(item)
    return [verb, positional, *kept, f"{name}={value}"]


@pytest.mark.parametrize(("verb", "action", "value"), _cases())
def test_hostile_values_of_every_option(hostile, tmp_path, inputs, verb, action, value):
    if value == ".":
        value = str(tmp_path)  # a directory
    argv = _argv(inputs[verb], action, value)
    o = hostile.run(argv, seconds=60)
    if o.kind == "refused":
        # A refusal names the option; one of a path, the path as given ("error: PATH: ...").
        names = [_name(action), action.dest]
        if value is not None and (action.type is Path or not action.option_strings):
            names.append(f"{str(Path(value))[:200]}:")
        last = o.stderr.strip().splitlines()[-1]
        assert any(name in last for name in names), (
            f"{' '.join(argv)[:300]}: the refusal names none of {names}: {last[:300]}"
        )
