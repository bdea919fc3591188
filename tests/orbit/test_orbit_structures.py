"""Structure once, numbers many for orbits (cayley_heyoka.orbit.numbers): a scene of an orbit
structure already built takes that model with its own numbers, and that model is the one a full
build gives; scenes whose numbers decide a term are other structures; and members of one
structure run as they would alone, through every terminal handler (revolutions of ρ, Encke's
rectifications, the hand-overs between Cayley's variants)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from helpers import (
    assert_same_model,
    assert_second_scene_filled,
    runs_shared_and_alone,
    with_value,
    with_values,
)

import cayley_heyoka as ch
from cayley_heyoka.core import structures
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.structures import model_for, structure_of
from cayley_heyoka.orbit import tilt
from cayley_heyoka.workflows.members import PATH_LANES, PATH_RUN
from cayley_heyoka.workflows.sweep import OK, Study, run_sweep

TIMES = {"start": "0", "stop": "2", "count": 3}
ELEMENTS = {
    "a": "1",
    "e": "0.1",
    "inclination": "0.5",
    "node": "0.2",
    "argument_of_pericentre": "0.3",
    "mean_anomaly": "0",
}
CARTESIAN = {"mu": "1", "position": ["0.9", "0.2", "0.1"], "velocity": ["-0.25", "0.85", "0.45"]}
J2 = {"zonal": {"J2": "1e-3", "radius": "0.5"}}
MOON = {"gm": "0.01", "a": "4", "n": "0.125", "inclination": "0.1", "node": "0.3"}


def orbit(formulation: str, **tables) -> dict:
    """An orbit given by its elements in ``formulation``; ``tables`` added or replacing."""
    d = {
        "orbit": {"mu": "1", "elements": dict(ELEMENTS), "formulation": formulation},
        "perturbations": copy.deepcopy(J2),
        "output": {"times": TIMES},
    }
    d.update(copy.deepcopy(tables))
    return d


#: (structure, the fields whose numbers the second scene changes and their new values)
CASES = {
    "cartesian, J2, position and velocity": (
        {"orbit": {**CARTESIAN, "formulation": "cartesian"}, "perturbations": J2,
         "output": {"times": TIMES, "events": ["node", "apsis"]}},
        {("orbit", "mu"): "1.25", ("orbit", "velocity"): ["-0.2", "0.9", "0.4"],
         ("perturbations", "zonal", "J2"): "2e-3"},
    ),
    "cartesian, J2-J4 oblique axis, circular moon, quad": (
        orbit(
            "cartesian",
            perturbations={
                "zonal": {"J2": "1e-3", "J3": "-2e-6", "J4": "0", "radius": "0.5",
                          "axis": ["0.1", "0", "1"]},
                "third_body": MOON,
            },
            integrator={"precision": "quad"},
        ),
        {("perturbations", "zonal", "axis"): ["0", "-0.3", "2"],
         ("perturbations", "zonal", "J4"): "1e-7",
         ("perturbations", "third_body", "inclination"): "0.4",
         ("orbit", "elements", "e"): "0.3"},
    ),
    "cayley level, turning plane, events": (
        orbit(
            "cayley",
            reference_plane={"phi_rate": "0.05", "theta0": "0.1"},
            output={"times": TIMES, "events": ["equatorial", "node", "apsis"]},
        ),
        {("orbit", "elements", "inclination"): "0.7", ("orbit", "mu"): "2",
         ("reference_plane", "phi_rate"): "-0.02", ("orbit", "equatorial_limit"): "0.01",
         ("orbit", "sigma0"): "0.4"},
    ),
    "cayley tilted at the start": (
        with_value(
            orbit("cayley", output={"times": TIMES, "events": ["equatorial"]}),
            ("orbit", "elements", "inclination"),
            "5e-4",
        ),
        {("orbit", "elements", "inclination"): "4e-4", ("orbit", "elements", "node"): "1"},
    ),
    "cayley without a limit, a departure-free plane": (
        {**orbit("cayley", reference_plane={"theta_rate": "0.01", "sigma_rate": "0.02"}),
         "orbit": {"mu": "1", "elements": dict(ELEMENTS), "equatorial_limit": "0"}},
        {("reference_plane", "sigma_rate"): "-0.5", ("reference_plane", "theta_rate"): "0.3"},
    ),
    "cayley, Kepler": (
        {**orbit("cayley"), "perturbations": {}},
        {("orbit", "elements", "a"): "2", ("orbit", "elements", "mean_anomaly"): "3"},
    ),
    "quaternion, elliptic moon, moving plane, real128": (
        orbit(
            "quaternion",
            perturbations={"third_body": {**MOON, "eccentricity": "0.2",
                                          "argument_of_pericentre": "1"}},
            reference_plane={"theta_rate": "0.01", "phi_rate": "0.02", "phi0": "0.1"},
            integrator={"precision": {"bits": 128}},
        ),
        {("perturbations", "third_body", "eccentricity"): "0.05",
         ("perturbations", "third_body", "gm"): "0.02",
         ("reference_plane", "phi0"): "0.3", ("orbit", "elements", "mean_anomaly"): "4",
         ("output", "times"): {"start": "1", "stop": "3", "count": 3}},
    ),
    "quaternion, resting moon as a series": (
        orbit(
            "quaternion",
            perturbations={"third_body": {**MOON, "n": "0", "degree": 4,
                                          "mean_longitude0": "0.5"}},
        ),
        {("perturbations", "third_body", "mean_longitude0"): "2",
         ("perturbations", "third_body", "a"): "5"},
    ),
    "encke, J2 along -x": (
        orbit("encke", perturbations={"zonal": {"J2": "1e-3", "radius": "0.5",
                                                "axis": ["-2", "0", "0"]}}),
        {("orbit", "elements", "e"): "0.6", ("orbit", "mu"): "3",
         ("perturbations", "zonal", "axis"): ["-1", "0", "0"]},
    ),
    "encke, a potential, user events and monitors, quad": (
        orbit(
            "encke",
            perturbations={"potential": {"Omega": "1e-4*x*z/r**3 + 2e-5*mu*y"},
                           "third_body": MOON},
            events={"far": {"expression": "x*x + y*y - 0.81", "direction": "up"}},
            monitors={"z2": {"expression": "z*z + 0.25", "conserved": False}},
            output={"times": TIMES, "events": ["far", "apsis"],
                    "monitors": ["energy", "jacobi", "z2"]},
            integrator={"precision": "quad"},
        ),
        {("orbit", "elements", "a"): "1.5", ("perturbations", "third_body", "n"): "0.25"},
    ),
}  # fmt: skip


@pytest.mark.parametrize("case", CASES)
def test_a_second_orbit_of_a_structure_is_filled_with_its_own_numbers(case):
    assert_second_scene_filled(*CASES[case])


def test_the_variants_of_a_cayley_structure_are_its_own():
    # The variant a filled model hands over to is the structure's; its numbers are the run's.
    structures.clear()
    base, changes = CASES["cayley level, turning plane, events"]
    model_for(ch.Scene.from_dict(copy.deepcopy(base)))
    second = ch.Scene.from_dict(with_values(base, changes))
    filled, built = model_for(second), FAMILIES["orbit"].build(second)
    assert filled.variant == tilt.LEVEL
    other, own = filled.variants(tilt.TILTED), built.variants(tilt.TILTED)
    assert other.code_key == own.code_key and other.pars.names == own.pars.names
    assert [t.counter for t in other.terminal] == [t.counter for t in own.terminal]


#: (structure, a field and the value that makes it another structure)
OTHERS = [
    ("cayley level, turning plane, events", ("reference_plane", "phi_rate"), "0"),
    ("cayley level, turning plane, events", ("reference_plane", "sigma_rate"), "0"),
    ("cayley level, turning plane, events", ("reference_plane", "sigma_rate"), "0.1"),
    ("cayley level, turning plane, events", ("orbit", "elements", "inclination"), "1e-4"),
    ("cayley without a limit, a departure-free plane", ("orbit", "equatorial_limit"), "1e-3"),
    ("cayley without a limit, a departure-free plane", ("reference_plane", "sigma_rate"), "0"),
    ("cayley without a limit, a departure-free plane", ("reference_plane", "theta_rate"), "0"),
    ("cartesian, J2, position and velocity", ("perturbations", "zonal", "axis"), ["0", "0", "-1"]),
    ("cartesian, J2, position and velocity", ("perturbations", "zonal", "axis"), ["0", "2", "0"]),
    ("cartesian, J2, position and velocity", ("perturbations", "zonal", "axis"), ["0", "1", "1"]),
    ("cartesian, J2-J4 oblique axis, circular moon, quad",
     ("perturbations", "zonal", "axis"), ["0", "0", "3"]),
    ("cartesian, J2-J4 oblique axis, circular moon, quad",
     ("perturbations", "third_body", "eccentricity"), "0.1"),
    ("cartesian, J2-J4 oblique axis, circular moon, quad",
     ("perturbations", "third_body", "n"), "0"),
    ("cartesian, J2-J4 oblique axis, circular moon, quad", ("integrator", "precision"), "double"),
    ("quaternion, resting moon as a series", ("perturbations", "third_body", "degree"), 3),
    ("encke, a potential, user events and monitors, quad",
     ("perturbations", "potential", "Omega"), "1e-4*x*z/r**3 + 3e-5*mu*y"),
    ("encke, a potential, user events and monitors, quad",
     ("events", "far", "expression"), "x*x + y*y - 0.8"),
    ("encke, J2 along -x", ("orbit", "formulation"), "cartesian"),
]  # fmt: skip


@pytest.mark.parametrize(("case", "path", "value"), OTHERS)
def test_numbers_that_decide_a_term_name_another_structure(case, path, value):
    structures.clear()
    base, _ = CASES[case]
    a = ch.Scene.from_dict(copy.deepcopy(base))
    b = ch.Scene.from_dict(with_values(base, {path: value}))
    assert structure_of(a) != structure_of(b)
    model_for(a)
    assert_same_model(model_for(b), FAMILIES["orbit"].build(b))


def test_an_encke_start_the_precision_cannot_hold_is_refused_by_field():
    structures.clear()
    base, _ = CASES["encke, J2 along -x"]
    model_for(ch.Scene.from_dict(copy.deepcopy(base)))
    radial = with_values(base, {("orbit", "elements", "e"): "0.99999999999999999999"})
    with pytest.raises(ch.SceneError, match="orbit.elements.*eccentricity rounds to 1"):
        model_for(ch.Scene.from_dict(radial))


def _identical(a: ch.Result, b: ch.Result) -> None:
    assert a.counters == b.counters and a.status == b.status and a.message == b.message
    for name in a.variables:
        np.testing.assert_array_equal(a.variables[name], b.variables[name], err_msg=name)
    assert set(a.events) == set(b.events)
    for name in a.events:
        np.testing.assert_array_equal(a.events[name].time, b.events[name].time)
        assert list(a.events[name].label) == list(b.events[name].label)


PASSAGE = orbit(
    "cayley",
    perturbations={},
    reference_plane={"phi_rate": "0.05"},
    output={"times": {"start": "0", "stop": "20", "count": 9}, "events": ["equatorial", "node"]},
)
PASSAGE["orbit"]["equatorial_limit"] = "1e-3"
PASSAGE["orbit"]["elements"]["node"] = "0"  # Φ reaches 0 near t = 10


def test_cayley_members_of_one_structure_run_as_alone_through_revolutions_and_handovers():
    # The second member starts a revolution below (ρ₀ − k C with k = −1): a handler that kept
    # the first member's count would shift its ρ by 2π; the third passes the plane later.
    docs = [
        PASSAGE,
        with_value(PASSAGE, ("orbit", "elements", "mean_anomaly"), "3"),
        with_values(PASSAGE, {("orbit", "elements", "inclination"): "0.6", ("orbit", "mu"): "1.2"}),
    ]
    shared, alone = runs_shared_and_alone(docs)
    for a, b in zip(shared, alone, strict=True):
        _identical(a, b)
        assert a.counters["revolutions"] > 0 and a.counters["equatorial_handovers"] == 2
    numbers = FAMILIES["orbit"].numbers
    offsets = {numbers(ch.Scene.from_dict(d)).values["orbit.rho_offset"] for d in docs[:2]}
    assert len(offsets) == 2


def test_quaternion_members_in_multiprecision_run_as_alone():
    base = orbit("quaternion", integrator={"precision": {"bits": 128}})
    base["output"]["times"] = {"start": "0", "stop": "7", "count": 3}
    docs = [base, with_value(base, ("orbit", "elements", "mean_anomaly"), "4")]
    shared, alone = runs_shared_and_alone(docs)
    for a, b in zip(shared, alone, strict=True):
        _identical(a, b)
        assert a.counters["revolutions"] > 0


@pytest.mark.parametrize("precision", ["double", "quad"])
def test_encke_members_of_one_structure_run_as_alone_through_rectifications(precision):
    # μ differs: a rectification that read the first member's μ would put the second on
    # another ellipse.
    base = orbit("encke", integrator={"precision": precision})
    base["output"] = {"times": {"start": "0", "stop": "14", "count": 3}, "events": ["apsis"]}
    docs = [base, with_values(base, {("orbit", "mu"): "1.5", ("orbit", "elements", "e"): "0.4"})]
    shared, alone = runs_shared_and_alone(docs)
    for a, b in zip(shared, alone, strict=True):
        _identical(a, b)
        assert a.counters["rectifications"] >= 2


def test_a_sweep_through_one_structure_is_the_sweep_of_full_builds(monkeypatch):
    # Members in batch lanes and members handed over to run(), through the shared structure,
    # and again with every member built in full.
    study = Study.from_dict(
        {
            "scene": PASSAGE,
            "sweep": {
                "kind": "grid",
                "parameters": {
                    "orbit.elements.mean_anomaly": ["0", "3"],
                    "orbit.elements.inclination": ["0.5", "1.2"],
                },
            },
        }
    )
    structures.clear()
    shared = run_sweep(study, workers=1)
    assert list(shared.status) == [OK] * 4
    assert shared.metadata["paths"] == {PATH_LANES: 2, PATH_RUN: 2}  # lanes, and hand-overs
    monkeypatch.setattr(structures, "structure_of", lambda scene: None)
    full = run_sweep(study, workers=1)
    np.testing.assert_array_equal(shared.steps, full.steps)
    np.testing.assert_array_equal(shared.final_state, full.final_state)
    for name in shared.events:
        np.testing.assert_array_equal(shared.events[name], full.events[name])
