"""Orbit members' numbers computed at once (cayley_heyoka.orbit.tables, in double-double):
every row the table vouches for is the member's own ``numbers`` bit for bit, across the
formulations and the two ways of giving the start; a row it cannot vouch for — a value near a
rounding boundary or a branch, a member its scene would refuse or start tilted — is built
alone; fields and scenes it does not know get no table; and a sweep through the table is the
sweep built member by member."""

from __future__ import annotations

import copy
import dataclasses

import mpmath
import numpy as np
import pytest

from cayley_heyoka.core import ddouble as dd
from cayley_heyoka.core import structures
from cayley_heyoka.core.errors import SceneError
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows.members import tabulate
from cayley_heyoka.workflows.study import Study
from cayley_heyoka.workflows.sweep import run_sweep

TIMES = {"start": "0", "stop": "2", "count": 3}
CARTESIAN = {"mu": "1", "position": ["0.9", "0.2", "0.1"], "velocity": ["-0.25", "0.85", "0.45"]}
ELEMENTS = {
    "a": "1.2",
    "e": "0.25",
    "inclination": "0.5",
    "node": "0.3",
    "argument_of_pericentre": "0.4",
    "mean_anomaly": "0.2",
}
J2 = {"zonal": {"J2": "1.0826e-3", "radius": "0.8", "axis": ["0", "0", "1"]}}
FORMULATIONS = ["cayley", "quaternion", "cartesian"]
SPREAD = {
    "cartesian": {
        f"orbit.{kind}[{i}]": [-1.2, 1.2] for kind in ("position", "velocity") for i in range(3)
    },
    "elements": {
        "orbit.elements.a": [0.5, 3.0],
        "orbit.elements.e": [0.0, 0.9],
        "orbit.elements.inclination": [0.05, 3.0],
        "orbit.elements.node": [-7.0, 7.0],
        "orbit.elements.argument_of_pericentre": [-4.0, 4.0],
        "orbit.elements.mean_anomaly": [-20.0, 20.0],
    },
}


def _scene(formulation: str, start: str, perturbed: bool = True) -> dict:
    orbit: dict = {"mu": "1", "formulation": formulation}
    if start == "elements":
        orbit["elements"] = dict(ELEMENTS)
    else:
        orbit |= {k: list(v) for k, v in CARTESIAN.items() if k != "mu"}
    scene = {"orbit": orbit, "output": {"times": dict(TIMES)}}
    if perturbed:
        scene["perturbations"] = copy.deepcopy(J2)
    return scene


def _grid(scene: dict, parameters: dict) -> Study:
    return Study.from_dict({"scene": scene, "sweep": {"kind": "grid", "parameters": parameters}})


def _random(scene: dict, start: str, count: int = 40) -> Study:
    spread = {f: {"uniform": ab} for f, ab in SPREAD[start].items()}
    sweep = {"kind": "random", "count": count, "seed": 5, "parameters": spread}
    return Study.from_dict({"scene": scene, "sweep": sweep})


def _own_rows(study: Study, members) -> tuple[np.ndarray, np.ndarray]:
    """Each member's numbers built alone (its scene validated, its model built in full)."""
    structures.clear()
    models = [FAMILIES[s.family].build(s) for s in (study.member_scene(*m) for m in members)]
    initial = np.array([np.asarray(m.initial_state, dtype=float) for m in models])
    pars = np.array([np.asarray(m.pars.values, dtype=float) for m in models])
    return initial, pars


def _assert_trusted_rows_are_own(study: Study, members, table) -> None:
    trusted = np.flatnonzero(~table.suspect)
    initial, pars = _own_rows(study, [members[k] for k in trusted])
    got_initial, got_pars = table.initial[trusted], table.pars[trusted]
    assert (got_initial.view(np.int64) == initial.view(np.int64)).all()
    assert (got_pars.view(np.int64) == pars.view(np.int64)).all()


def _with_table(monkeypatch, table) -> None:
    """The orbit family with another ``table`` hook, for the test."""
    family = FAMILIES["orbit"]
    monkeypatch.setitem(FAMILIES._found().loaded, "orbit", dataclasses.replace(family, table=table))


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("start", ["cartesian", "elements"])
@pytest.mark.parametrize("numbers", ["doubles", "decimals"])
def test_every_trusted_row_is_the_members_own_build_bit_for_bit(formulation, start, numbers):
    study = _random(_scene(formulation, start), start)
    members = list(enumerate(study.members()))
    if numbers == "decimals":  # not doubles: the table takes each number's rest as well
        members = [(i, tuple(f"{v:.12g}" for v in values)) for i, values in members]
    tabled = tabulate(study, members)
    assert tabled is not None
    assert (~tabled.table.suspect).sum() >= len(members) - 2
    _assert_trusted_rows_are_own(study, members, tabled.table)


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_one_swept_number_of_the_terminal_rows_orbit(formulation):
    """users_engine's terminal row: one velocity component in six-digit decimals."""
    study = _grid(
        _scene(formulation, "cartesian"),
        {"orbit.velocity[1]": [f"{0.85 * (1 + 0.05 * k / 64):.6f}" for k in range(64)]},
    )
    members = list(enumerate(study.members()))
    table = tabulate(study, members).table
    assert not table.suspect.any()
    _assert_trusted_rows_are_own(study, members, table)


CARTESIAN_SUSPECTS = [
    # (position, velocity, why the row is a suspect for a Cayley run)
    (["1", "0", "0"], ["0", "1", "0"], "in the reference plane (Θ undefined)"),
    (["1", "0", "0"], ["0", "0.7", "0.7"], "at the node: u = 0 exactly"),
    (["1", "0", "0"], ["0", "-0.7", "0.7"], "Θ = π exactly (a branch)"),
    (["1", "0.5", "0"], ["2", "1", "0"], "rectilinear: refused"),
    (["1", "0.5", "0"], ["2", "1.0000000000000000000001", "1e-30"], "nearly rectilinear"),
    (["0", "0", "0"], ["0.3", "1", "0.2"], "at the origin: refused"),
    (["1e200", "0", "0.1"], ["0", "1", "0.2"], "beyond the range of the products"),
    (["1e-200", "0", "0.1"], ["0", "1", "0.2"], "below it"),
    (["1", "1e400", "0"], ["0", "1", "0.2"], "not a double: refused"),
    (["0.9", "0.2", "0"], ["-0.25", "0.85", "0.0005"], "sin Φ below the limit: tilted"),
]


def test_rows_the_table_cannot_vouch_for_are_suspects():
    scene = _scene("cayley", "cartesian")
    orbit = scene["orbit"]
    study = _grid(
        scene,
        {f"orbit.{k}[{i}]": [orbit[k][i]] for k in ("position", "velocity") for i in range(3)},
    )
    good = (tuple(CARTESIAN["position"]), tuple(CARTESIAN["velocity"]))
    rows = [good] + [(tuple(p), tuple(v)) for p, v, _ in CARTESIAN_SUSPECTS] + [good]
    members = [(k, (*p, *v)) for k, (p, v) in enumerate(rows)]
    table = tabulate(study, members).table
    expected = [False] + [True] * len(CARTESIAN_SUSPECTS) + [False]
    assert table.suspect.tolist() == expected, [w for *_, w in CARTESIAN_SUSPECTS]
    refused = [k for k, (_, _, why) in enumerate(CARTESIAN_SUSPECTS, 1) if "refused" in why]
    for k in refused:
        with pytest.raises(SceneError, match=f"member {k} "):
            study.member_scene(*members[k])


ELEMENT_SUSPECTS = [
    ({"node": "0"}, False, "Θ = 0 (mpmath's a rounding residue)"),
    ({"mean_anomaly": "0"}, False, "at pericentre: ṙ = 0"),
    ({"inclination": "0"}, False, "in the reference plane"),
    ({"inclination": "3.14159265358979323846264338327950288"}, False, "π: beyond its range"),
    ({"e": "0.99999999999999999999"}, False, "e rounds to 1"),
    ({"e": "1.00000000000000000001"}, True, "e ≥ 1: refused"),
    ({"e": "0.9999"}, False, "Kepler's equation too ill-conditioned"),
    ({"a": "-1"}, True, "a ≤ 0: refused"),
    ({"node": "3.14159265358979323846264338327950288"}, False, "Θ at π (a branch)"),
]


def test_element_sets_the_table_cannot_vouch_for_are_suspects():
    scene = _scene("cayley", "elements")
    keys = list(ELEMENTS)
    study = _grid(scene, {f"orbit.elements.{k}": [ELEMENTS[k]] for k in keys})
    rows = [dict(ELEMENTS)] + [{**ELEMENTS, **change} for change, _, _ in ELEMENT_SUSPECTS]
    members = [(k, tuple(row[key] for key in keys)) for k, row in enumerate(rows)]
    table = tabulate(study, members).table
    assert table.suspect.tolist() == [False] + [True] * len(ELEMENT_SUSPECTS)
    for k, (_, refused, _) in enumerate(ELEMENT_SUSPECTS, 1):
        if refused:
            with pytest.raises(SceneError, match=f"member {k} "):
                study.member_scene(*members[k])
        else:
            study.member_scene(*members[k])


def test_a_plane_orbit_in_cartesian_coordinates_keeps_its_zeros():
    """Elements in the reference plane: z and v_z are 0 exactly on both sides."""
    scene = _scene("cartesian", "elements")
    scene["orbit"]["elements"]["inclination"] = "0"
    study = _grid(scene, {"orbit.elements.a": ["1.1", "1.2", "1.3"]})
    members = list(enumerate(study.members()))
    table = tabulate(study, members).table
    assert not table.suspect.any()
    assert (table.initial[:, 2] == 0).all() and (table.initial[:, 5] == 0).all()
    _assert_trusted_rows_are_own(study, members, table)


@pytest.mark.parametrize(
    ("change", "parameters"),
    [
        ({}, {"orbit.mu": ["1", "2"]}),
        ({}, {"orbit.sigma0": ["0", "0.5"]}),
        ({}, {"perturbations.zonal.J2": ["1e-3", "2e-3"]}),
        ({"formulation": "encke"}, {"orbit.velocity[1]": ["0.85", "0.86"]}),
        ({"quad": True}, {"orbit.velocity[1]": ["0.85", "0.86"]}),
        ({"plane": True}, {"orbit.velocity[1]": ["0.85", "0.86"]}),
        ({"degree": True}, {"orbit.velocity[1]": ["0.85", "0.86"]}),
        ({"tilted": True}, {"orbit.velocity[1]": ["0.85", "0.86"]}),
    ],
)
def test_fields_and_scenes_the_table_does_not_know_are_built_member_by_member(change, parameters):
    scene = _scene(change.get("formulation", "cayley"), "cartesian")
    if change.get("quad"):
        scene["integrator"] = {"precision": "quad"}
    if change.get("plane"):
        scene["reference_plane"] = {"theta_rate": "0.01"}
    if change.get("degree"):
        scene["perturbations"] = {"third_body": {"gm": "0.01", "a": "40", "n": "0.01", "degree": 2}}
    if change.get("tilted"):  # starts on the tilted frame: sin Φ below the limit
        scene["orbit"]["velocity"] = ["-0.25", "0.85", "1e-5"]
        scene["orbit"]["position"] = ["0.9", "0.2", "0"]
    study = _grid(scene, parameters)
    assert tabulate(study, list(enumerate(study.members()))) is None


def test_double_double_functions_err_by_a_few_units_of_two_to_the_minus_100():
    rng = np.random.default_rng(7)
    x = dd.of(rng.uniform(-8, 8, 400), rng.uniform(-1, 1, 400) * 2.0**-54)
    y = dd.of(rng.uniform(-8, 8, 400), rng.uniform(-1, 1, 400) * 2.0**-54)
    sin, cos = dd.sincos(x)
    angle = dd.atan2(y, x)
    reduced = dd.reduce(dd.scale(x, 1024.0))
    with mpmath.workprec(200):

        def mp(v, k):
            return mpmath.mpf(float(v[0][k])) + mpmath.mpf(float(v[1][k]))

        for k in range(400):
            a, b = mp(x, k), mp(y, k)
            t = 1024 * a
            for got, want in (
                (sin, mpmath.sin(a)),
                (cos, mpmath.cos(a)),
                (angle, mpmath.atan2(b, a)),
                (reduced, t - 2 * mpmath.pi * mpmath.nint(t / (2 * mpmath.pi))),
            ):
                assert abs(mp(got, k) - want) < 2.0**-98


def test_gap_is_the_distance_to_the_nearest_rounding_boundary():
    one = np.array([1.0, 1.0, 1.5, 0.0])
    low = np.array([2.0**-60, -(2.0**-60), 0.0, 0.0])
    gap = dd.gap((one, low))
    # above 1 the doubles are 2⁻⁵² apart, below it 2⁻⁵³: the boundaries are half that
    assert gap.tolist() == [2.0**-53 - 2.0**-60, 2.0**-54 - 2.0**-60, 2.0**-53, 0.0]


@pytest.mark.parametrize("formulation", FORMULATIONS)
def test_a_sweep_through_tables_is_the_sweep_member_by_member(monkeypatch, formulation):
    scene = _scene(formulation, "cartesian")
    scene["output"]["times"] = {"start": "0", "stop": "30", "count": 7}
    scene["output"]["events"] = ["node", "apsis"]
    # The last one starts below the hand-over limit (a suspect, built alone: Cayley's run
    # starts it tilted, another structure).
    parameters = {
        "orbit.position[2]": ["0.1", "1e-4"],
        "orbit.velocity[2]": ["0.45", "-0.6", "5e-4"],
    }
    study = _grid(scene, parameters)
    tabled = tabulate(study, list(enumerate(study.members())))
    assert tabled.table.suspect.tolist() == [False] * 5 + [formulation == "cayley"]
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
