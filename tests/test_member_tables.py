"""Members' numbers computed at once (core.structures.table_for, the rotation family's
``table``): every row is the member's own ``numbers`` bit for bit, a row the table cannot
vouch for is built alone, and a sweep through tables is the sweep built member by member."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cayley_heyoka.core import structures
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows.members import tabulate
from cayley_heyoka.workflows.study import Study
from cayley_heyoka.workflows.sweep import run_sweep

TIMES = {"start": 0.0, "stop": 3.0, "count": 4}


def _scene(formulation: str, events: bool) -> dict:
    attitude = {"rodrigues": [0.1, 0.2, -0.3]} if formulation == "rodrigues" else {}
    if formulation == "quaternion":
        attitude = {"quaternion": [0.9, 0.3, -0.3, 0.1]}
    output = {"times": TIMES, "events": ["invariable_plane"] if events else []}
    return {
        "body": {"inertia": [1.0, 1.5, 2.25]},
        "initial": {"rates": [0.3, 1.0, 0.5], **attitude},
        "attitude": {"formulation": formulation},
        "output": output,
    }


def _with_table(monkeypatch, table) -> None:
    """The rotation family with another ``table`` hook, for the test."""
    family = FAMILIES["rotation"]  # loaded, so that the registry holds it
    monkeypatch.setitem(
        FAMILIES._found().loaded, "rotation", dataclasses.replace(family, table=table)
    )


def _random_study(scene: dict, fields: list[str], count: int = 40) -> Study:
    spread = {f: {"uniform": [0.9, 1.6]} for f in fields}
    return Study.from_dict(
        {
            "scene": scene,
            "sweep": {"kind": "random", "count": count, "seed": 3, "parameters": spread},
        }
    )


def _rows_alone(study: Study, members) -> tuple[np.ndarray, np.ndarray]:
    structures.clear()
    models = [
        structures.FAMILIES[s.family].build(s) for s in (study.member_scene(*m) for m in members)
    ]
    initial = np.array([np.asarray(m.initial_state, dtype=float) for m in models])
    pars = np.array([np.asarray(m.pars.values, dtype=float) for m in models])
    return initial, pars


FIELDS = {
    "rates": ["initial.rates[0]", "initial.rates[2]"],
    "moments": ["body.inertia[0]", "body.inertia[2]"],
    "both": ["initial.rates[1]", "body.inertia[1]", "body.inertia[2]"],
}


@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues", "none"])
@pytest.mark.parametrize("events", [False, True])
@pytest.mark.parametrize("fields", list(FIELDS))
def test_every_row_is_the_members_own_build_bit_for_bit(formulation, events, fields):
    # The rates alone cross the plane ⊥ L too: their events watch the rates, holding no number.
    study = _random_study(_scene(formulation, events), FIELDS[fields])
    members = list(enumerate(study.members()))
    tabled = tabulate(study, members)
    assert tabled is not None
    initial, pars = _rows_alone(study, members)
    trusted = ~tabled.table.suspect
    assert trusted.sum() > len(members) // 2
    assert (tabled.table.initial[trusted].view(np.int64) == initial[trusted].view(np.int64)).all()
    assert (tabled.table.pars[trusted].view(np.int64) == pars[trusted].view(np.int64)).all()


def _grid(scene: dict, parameters: dict) -> Study:
    return Study.from_dict({"scene": scene, "sweep": {"kind": "grid", "parameters": parameters}})


def test_rows_the_table_cannot_vouch_for_are_suspects():
    scene = _scene("quaternion", True)
    study = _grid(
        scene,
        {
            "body.inertia[2]": [2.25, 2.5, "0.1", -1.0],  # 2.5 = 1 + 1.5: the edge
            "initial.rates[0]": [0.0, 0.3],
        },
    )
    scene["initial"]["rates"] = [0.0, 0.0, 0.0]
    at_rest = _grid(scene, {"initial.rates[0]": [0.0, 0.5]})
    members = list(enumerate(study.members()))
    table = tabulate(study, members).table
    moments = [v[0] for _, v in members]
    expected = [m != 2.25 for m in moments]
    assert table.suspect.tolist() == expected
    assert tabulate(at_rest, list(enumerate(at_rest.members()))).table.suspect.tolist() == [
        True,
        False,
    ]


def test_doubles_says_which_numbers_a_double_holds_and_which_it_is():
    x, exact, held = structures.doubles([[0.5, "0.1", 3, "1e-320", "1e400", "0"]])
    assert x[0, :3].tolist() == [0.5, 0.1, 3.0]
    assert exact.tolist() == [[True, False, True, False, False, True]]
    assert held.tolist() == [[True, True, True, False, False, True]]


@pytest.mark.parametrize(
    "parameters",
    [
        {"attitude.max_chart_angle": [90, 120]},
        {"initial.quaternion[1]": [0.3, 0.3]},
        {"integrator.tolerance": [1e-10, 1e-12]},
    ],
)
def test_fields_the_table_does_not_know_are_built_member_by_member(parameters):
    study = _grid(_scene("quaternion", False), parameters)
    assert tabulate(study, list(enumerate(study.members()))) is None


def test_no_table_for_decimal_moments_beside_a_swept_one_nor_in_quad():
    scene = _scene("quaternion", False)
    scene["body"]["inertia"] = ["0.1", 1.5, 1.5]
    study = _grid(scene, {"body.inertia[2]": [1.5, 1.25]})
    assert tabulate(study, list(enumerate(study.members()))) is None
    quad = {**_scene("quaternion", False), "integrator": {"precision": "quad"}}
    study = _grid(quad, {"initial.rates[0]": [0.1, 0.2]})
    assert tabulate(study, list(enumerate(study.members()))) is None


def test_a_table_that_disagrees_with_its_family_numbers_is_a_fault_of_the_family(monkeypatch):
    family = FAMILIES["rotation"]
    honest = family.table

    def off_by_an_ulp(*args):
        t = honest(*args)
        t.pars[-1, 0] = np.nextafter(t.pars[-1, 0], np.inf)
        return t

    _with_table(monkeypatch, off_by_an_ulp)
    study = _grid(_scene("quaternion", False), {"body.inertia[0]": [1.0, 1.25, 1.125]})
    structures.clear()  # a structure's tables are checked once: the first one, here
    with pytest.raises(RuntimeError, match="table disagrees with its numbers for row 2"):
        tabulate(study, list(enumerate(study.members())))


def test_a_structure_s_table_is_checked_against_full_builds_once(monkeypatch):
    study = _grid(_scene("quaternion", False), {"body.inertia[0]": [1.0, 1.25, 1.125]})
    indexed = list(enumerate(study.members()))
    structures.clear()
    built = []
    full = structures.model_for
    monkeypatch.setattr(structures, "model_for", lambda scene: built.append(scene) or full(scene))
    first = tabulate(study, indexed)
    checks = len(built)
    again = tabulate(study, indexed)
    # The first: the template's model, and its last row's built in full (its first row is
    # the template's own); the second: the template's model alone.
    assert (checks, len(built) - checks) == (2, 1)
    assert np.array_equal(first.table.pars, again.table.pars)


@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues"])
def test_a_sweep_through_tables_is_the_sweep_member_by_member(monkeypatch, formulation):
    scene = _scene(formulation, True)
    scene["output"]["times"] = {"start": 0.0, "stop": 30.0, "count": 7}
    study = _grid(
        scene,
        {"initial.rates[0]": [0.0, 0.3, 2.0], "body.inertia[2]": [2.25, 2.5, 1.0, 2.0]},
    )
    assert tabulate(study, list(enumerate(study.members()))) is not None
    tabled = run_sweep(study)
    structures.clear()
    _with_table(monkeypatch, None)
    alone = run_sweep(study)
    assert tabled.status.tolist() == alone.status.tolist()
    assert tabled.steps.tolist() == alone.steps.tolist()
    assert tabled.message.tolist() == alone.message.tolist()
    np.testing.assert_array_equal(tabled.final_state, alone.final_state)
    for name in alone.drift:
        np.testing.assert_array_equal(tabled.drift[name], alone.drift[name])
    for name in alone.events:
        np.testing.assert_array_equal(tabled.events[name], alone.events[name])
