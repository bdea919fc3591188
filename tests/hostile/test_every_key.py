"""Every key the parsers allow, given hostile values: generated from the schema itself
(``schema.py``), so that a key added to a parser is tried here from its first commit.

For each key, in the corpus document that sets it, each value of a palette chosen by the
kind of value the key holds (a number, text, a switch, a list, a table) replaces it. The scene
(or study) check must then refuse it with a :class:`SceneError` naming that key — itself, a
part of it, or the table holding it when the rule is about siblings (``stop`` beside
``start``) — or accept it. A value the check accepts is run by ``cayley-heyoka run`` (a scene)
or ``cayley-heyoka sweep`` (a study) and held to the runner's four outcomes (conftest.py): no
traceback, no hang, no NaN in a completed summary.
"""

from __future__ import annotations

from typing import Any

import pytest
import schema
from conftest import Raw, toml
from helpers import with_value

from cayley_heyoka.core.errors import SceneError

#: Values tried where a number stands (kept as typed where they are text: Raw).
NUMBERS = [
    "abc",
    True,
    {},
    [],
    "",
    Raw("nan"),
    Raw("-inf"),
    Raw("1e999999"),
    Raw("-1e-999999"),
    10**400,
    Raw("1e308"),
    Raw("4.9e-324"),
    Raw("-1"),
    Raw("0"),
    Raw("0.1000000000000000000000000000001"),
]
TEXTS = [42, True, [], {}, "", " ", "x" * 100_000, "\x1b[31mred\u202e", "nan", "\u00e9"]
SWITCHES = [1, "true", [], {}]
TABLES = [1, "x", [], {"zz_not_a_key": 1}]


def _lists(value: list) -> list:
    n = len(value)
    return [
        "abc",
        {},
        [],
        [Raw("nan")] * n,
        [[]] * n,
        list(range(1000)),
        [Raw("1e308")] * n,
        [*value, value[0]],
    ]


def palette(value: Any) -> list:
    if isinstance(value, bool):
        return SWITCHES
    if isinstance(value, Raw | int | float):
        return NUMBERS
    if isinstance(value, str):
        return TEXTS
    if isinstance(value, dict):
        return TABLES
    if isinstance(value, list):
        return _lists(value)
    raise AssertionError(f"no palette for {value!r}")


def _get(doc: Any, path: tuple) -> Any:
    for key in path:
        doc = doc[key]
    return doc


def _field(path: tuple) -> str:
    out = ""
    for key in path:
        if isinstance(key, int):
            out += f"[{key}]"
        else:
            text = key if key.replace("_", "").isalnum() else f'"{key}"'
            out = f"{out}.{text}" if out else text
    return out


#: Rules between keys of different tables, whose refusal names the other key: the message
#: says what the pair violates and which key to change.
ACROSS = {
    # The third body's Legendre expansion (degree) needs the orbit inside the perturber's.
    "orbit.elements.a": {"perturbations.third_body.degree"},
}


def names_key(field: str, path: tuple, key: str) -> bool:
    """Whether a refusal's field is the key at ``path``, a part of it, the table holding it
    (a rule between siblings) or a key it has a rule with (:data:`ACROSS`)."""
    field = field.split(": ")[-1]  # a study's scene errors: "scene (FILE): field"
    concrete, parent = _field(path), _field(path[:-1])
    return (
        field == concrete
        or field.startswith((f"{concrete}.", f"{concrete}["))
        or (bool(parent) and field == parent)
        or field in ACROSS.get(key, ())
    )


#: Accepted values run per key, the first in palette order (the palettes put the extremes
#: first): enough to try what the check lets through, within the test run's time.
RUNS_PER_KEY = 3


KEYS = [k for k in schema.keys() if k.document is not None]


@pytest.mark.covers(*(k.coverage for k in KEYS))
@pytest.mark.parametrize("key", KEYS, ids=[f"{k.kind}:{k.name}" for k in KEYS])
def test_hostile_values_of_every_key(hostile, tmp_path, key):
    base = schema.document(key)
    wrong, accepted = [], []
    for value in palette(_get(base, key.path)):
        doc = with_value(base, key.path, value)
        try:
            schema.parse(key.kind, doc)
        except SceneError as exc:
            if not names_key(exc.field, key.path, key.name):
                wrong.append(f"{value!r:.40}: refused naming {exc.field!r}: {exc.constraint}")
            continue
        except Exception as exc:  # noqa: BLE001 -- the case fails, naming what escaped
            wrong.append(f"{value!r:.40}: {type(exc).__name__}: {exc}")
            continue
        accepted.append((value, doc))
    assert not wrong, f"{key.name}: not refused by name:\n" + "\n".join(wrong)
    runnable = [(v, d) for v, d in accepted if not (isinstance(v, int) and v.bit_length() > 63)]
    for _, doc in runnable[:RUNS_PER_KEY]:  # (an integer beyond 64 bits has no TOML spelling)
        path = hostile.scene(toml(schema.study_scene(doc) if key.kind == "study" else doc))
        verb = ["run", str(path), "--no-progress"]
        if key.kind == "study":
            verb = ["sweep", str(path), "--no-progress"]
        hostile.run(verb, seconds=60)
