"""Hostile cases of the planner (``cayley-heyoka plan``, :func:`cayley_heyoka.plan`) and of
``check`` on the scenes the planner's pilots used to mangle: every pilot must be the user's
scene in a route's formulation, precision and tolerance, and a recommended route must be one
that ``run`` carries through. Each case ends as conftest.py requires; the spans are tiny, so a
pilot runs the whole span and its numbers are those of the run it predicts.
"""

from __future__ import annotations

import re
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows import planner

#: A heavy top reduced by Euler–Poisson, its whole attitude by the azimuth's quadrature.
AZIMUTH = {
    "body": {"inertia": [1.0, 1.6, 2.3]},
    "initial": {"rates": [0.3, 1.0, 0.5]},
    "forces": {
        "heavy_top": {"weight": 1.0, "center_of_mass": [0.1, -0.05, 0.3], "up": [0.0, 0.0, 1.0]}
    },
    "attitude": {"formulation": "poisson"},
    "output": {"times": {"start": 0.0, "stop": 2.0, "count": 11}, "azimuth": True},
}
#: A free body, rates only (its own formulation is 'none').
RATES = {
    "body": {"inertia": [1, 2, 3]},
    "initial": {"rates": [0.75, -0.5, 0.625]},
    "output": {"times": {"start": 0, "stop": 2, "count": 11}},
}
#: A Cayley orbit with its gauge Σ(0).
GAUGED = {
    "orbit": {
        "mu": 1.0,
        "position": [0.5, -0.8, 0.3],
        "velocity": [0.9, 0.45, 0.2],
        "formulation": "cayley",
        "sigma0": 0.7,
    },
    "output": {"times": {"start": 0.0, "stop": 1.0, "count": 5}},
}
#: An orbit that conserves nothing: a tilted J₂ and a third body on its own orbit.
UNCONSERVED = {
    "orbit": {"mu": 1.0, "position": [0.9, 0.2, 0.1], "velocity": [-0.25, 0.85, 0.45]},
    "perturbations": {
        "zonal": {"J2": 1e-3, "radius": 0.8, "axis": [0.1, -0.2, 1.0]},
        "third_body": {
            "gm": 0.005,
            "a": 3.5,
            "n": 0.15,
            "inclination": 0.4,
            "node": -0.3,
            "mean_longitude0": 2.0,
        },
    },
    "output": {"times": {"start": 0.0, "stop": 1.0, "count": 3}},
}


def _id(value: object) -> str:
    """A short test id (Python refuses to print an integer of more than 4300 digits)."""
    if isinstance(value, int) and abs(value).bit_length() > 1000:
        return f"int of {value.bit_length()} bits"
    return f"{value!r:.40}"


def _row(stdout: str, formulation: str, precision: str) -> list[str]:
    """The table row of one route, split on blanks."""
    for line in stdout.splitlines():
        words = line.split()
        if words[:2] == [formulation, precision]:
            return words
    raise AssertionError(f"no {formulation} {precision} route in\n{stdout}")


@pytest.mark.covers("verb:plan", "option:plan --formulation", "key:output.azimuth", "class:3")
def test_the_pilots_keep_the_azimuth(hostile):
    """The reduction's pilot integrates the azimuth as the scene does: its predicted steps are
    the run's (the span is shorter than a pilot: measured, not extrapolated)."""
    scene = hostile.scene(AZIMUTH)
    out = hostile.run(
        ["plan", str(scene), "--error", "1e-8", "--formulation", "poisson"], expect="done"
    )
    steps = int(_row(out.stdout, "poisson", "double")[3].replace(",", ""))
    assert steps == ch.run(ch.load_scene(scene)).counters["steps"]


@pytest.mark.covers("api:plan", "key:attitude.formulation", "class:3")
def test_the_other_formulations_carry_the_same_motion():
    """From a reduced body with its azimuth, the quaternion and Rodrigues pilots integrate the
    whole attitude (the azimuth option, theirs already, is dropped); from a quaternion scene the
    reduction's pilot adds the azimuth; a rates-only body plans its own 'none' and refuses the
    formulations that would add an attitude."""
    family = FAMILIES["rotation"]
    reduced = ch.Scene.from_dict(AZIMUTH)
    whole = ch.Scene.from_dict(family.in_formulation(reduced, "quaternion"))
    assert "azimuth" not in whole.output.options and whole.model.formulation == "quaternion"
    back = ch.Scene.from_dict(family.in_formulation(whole, "poisson"))
    assert back.output.options["azimuth"] is True
    p = planner.plan(ch.Scene.from_dict(RATES), 1e-9)
    assert {r.formulation for r in p.routes} == {"none"}
    assert all("rates alone" in p.refused[f] for f in ("quaternion", "rodrigues", "poisson"))
    assert p.recommended is not None and p.recommended.formulation == "none"


@pytest.mark.covers("verb:plan", "option:plan --error", "key:integrator.tolerance", "class:3")
def test_a_route_is_its_precision_and_its_tolerance(hostile):
    """A scene's tolerance of 1e-12 cannot reach 1e-20 in quad: the route says it runs with
    quad's own tolerance, in the text and in the Route, and its scene is built so."""
    scene = hostile.scene({**RATES, "integrator": {"tolerance": 1e-12}})
    out = hostile.run(["plan", str(scene), "--error", "1e-20"], expect="done")
    assert "recommended: none in quad with integrator.tolerance = 'auto'" in out.stdout
    assert "not the scene's tolerance 1e-12" in out.stdout
    p = planner.plan(ch.load_scene(scene), 1e-20)
    assert p.recommended is not None and p.recommended.tolerance == "auto"
    variant = p.scene_for(p.recommended)
    assert variant.integrator.tolerance is None and variant.integrator.precision.name == "quad"


@pytest.mark.covers("verb:plan", "key:integrator.max_steps", "class:3")
def test_a_route_beyond_the_step_budget_is_not_recommended(hostile):
    """300 steps of budget for a span that needs ~500: no route is recommended (exit 1), each
    is marked, and the advice names the budget; with the budget raised the same plan
    recommends, and ``run`` carries the route through."""
    tight = {**RATES, "output": {"times": {"start": 0, "stop": 200, "count": 3}}}
    tight["integrator"] = {"max_steps": 300}
    out = hostile.run(
        ["plan", str(hostile.scene(tight)), "--error", "1e-6"], expect="stopped", seconds=120
    )
    assert "over integrator.max_steps" in out.stdout
    assert "raise integrator.max_steps" in out.stdout and "300" in out.stdout
    p = planner.plan(ch.Scene.from_dict(tight), 1e-6)
    assert p.recommended is None and not any(r.runnable for r in p.routes)
    assert ch.run(ch.Scene.from_dict(tight), raise_on_failure=False).status != 0
    roomy = {**tight, "integrator": {"max_steps": 2000}}
    q = planner.plan(ch.Scene.from_dict(roomy), 1e-6, formulations=["none"])
    assert q.recommended is not None and q.recommended.steps <= 2000
    assert ch.run(q.scene_for(q.recommended)).status == 0


@pytest.mark.covers("verb:plan", "option:plan --formulation", "key:orbit.sigma0", "class:3")
def test_a_cartesian_pilot_of_a_gauged_cayley_orbit(hostile):
    """σ₀ is the Cayley angles' gauge: the Cartesian pilot drops it and plans the same orbit."""
    scene = hostile.scene(GAUGED)
    out = hostile.run(
        ["plan", str(scene), "--error", "1e-8", "--formulation", "cartesian"], expect="done"
    )
    assert "recommended: cartesian in double" in out.stdout


@pytest.mark.covers("verb:plan", "key:output.times.start", "key:output.times.stop", "class:3")
def test_a_span_far_from_zero_is_planned_as_run_runs_it(hostile):
    """[1e15, 1.0000000000001e15] runs in double (a span of 100): the plan's pilots are
    computed from the scene's times, not from a stretch of 1e-4 that 1e15 cannot hold."""
    far = {**RATES, "output": {"times": {"start": 1e15, "stop": 1.0000000000001e15, "count": 11}}}
    scene = hostile.scene(far)
    hostile.run(["run", str(scene)], expect="done")
    out = hostile.run(["plan", str(scene), "--error", "1e-6"], expect="done")
    assert "over t = 100" in out.stdout
    steps = int(_row(out.stdout, "none", "double")[3].replace(",", ""))
    assert steps == ch.run(ch.load_scene(scene)).counters["steps"]


@pytest.mark.covers("verb:plan", "key:integrator.max_step", "class:3")
def test_a_scene_with_a_max_step_is_piloted(hostile):
    """max_step = 0.001 makes 500 steps of t = 0.5: the probe of the rate of steps stays within
    what its budget can cover (a longer one is refused by the engine), and the plan predicts
    the run's steps."""
    short = {"times": {"start": 0, "stop": 0.5, "count": 3}}
    scene = hostile.scene({**RATES, "output": short, "integrator": {"max_step": 0.001}})
    out = hostile.run(["plan", str(scene), "--error", "1e-8"], expect="done")
    steps = int(_row(out.stdout, "none", "double")[3].replace(",", ""))
    assert abs(steps / ch.run(ch.load_scene(scene)).counters["steps"] - 1) < 0.01


@pytest.mark.covers("verb:check", "key:output.azimuth", "key:attitude.formulation", "class:3")
def test_check_of_a_reduced_body_with_its_azimuth(hostile):
    """The quaternion twin carries the whole attitude: the reduction's rates, γ and its
    azimuth's quaternion and Rodrigues parameters are compared with it."""
    out = hostile.run(["check", str(hostile.scene(AZIMUTH))], expect="done")
    assert "qw, qx, qy, qz − the quaternion twin" in out.stdout
    assert "γ₁, γ₂, γ₃" in out.stdout and "passed" in out.stdout


@pytest.mark.covers("verb:plan", "option:plan --quantity", "class:12")
def test_invariants_of_a_scene_that_conserves_nothing(hostile):
    """Refused before any pilot, on the command line and by ``for_error`` of a plan of the
    state (whose routes have no drift to predict)."""
    hostile.run(
        ["plan", str(hostile.scene(UNCONSERVED)), "--error", "1e-8", "--quantity", "invariants"],
        expect="refused",
        field="--quantity: 'invariants' bounds the drift of the conserved quantities",
    )
    p = planner.plan(ch.Scene.from_dict(UNCONSERVED), 1e-8, formulations=["cartesian"])
    assert p.conserved == () and p.recommended is not None
    with pytest.raises(ValueError, match="^quantity: 'invariants' bounds"):
        p.for_error(1e-8, "invariants")


@pytest.mark.covers("verb:plan", "option:plan --error", "class:10")
@pytest.mark.parametrize(
    "error, why",
    [
        ("abc", "not a decimal number"),
        ("nan", "not a decimal number"),
        ("inf", "not a decimal number"),
        ("0", "must be a number > 0"),
        ("-1", "must be a number > 0"),
        ("1e400", "a double holds"),
        ("1e-400", "a double holds"),
        ("1" + "0" * 400, "a double holds"),
        ("1" + "0" * 5000, "more than 4000 digits"),
    ],
)
def test_bad_errors_are_refused_naming_the_option(hostile, error, why):
    out = hostile.run(
        ["plan", str(hostile.scene(RATES)), "--error", error], expect="refused", field="--error: "
    )
    assert why in out.error_line


@pytest.mark.covers("verb:plan", "option:plan --formulation")
def test_an_unknown_formulation_is_refused_naming_the_option(hostile):
    hostile.run(
        ["plan", str(hostile.scene(AZIMUTH)), "--error", "1e-8", "--formulation", "euler"],
        expect="refused",
        field="--formulation: ['euler'] are not among",
    )


@pytest.mark.covers("verb:plan")
def test_a_study_file_is_refused_naming_the_sweep_verb(hostile):
    study = hostile.scene({"title": "s", "scene": "x.toml", "sweep": {"kind": "grid"}})
    hostile.run(
        ["plan", str(study), "--error", "1e-8"], expect="refused", field="cayley-heyoka sweep"
    )


@pytest.mark.covers("verb:plan", "class:3")
def test_a_scene_whose_pilot_stops_is_refused_saying_so(hostile):
    """H = ϖ²/2 − η⁴ blows up at t ≈ 0.75: the pilot stops there, and the refusal says so."""
    blows = {
        "hamiltonian": {"H": "varpi1**2/2 - eta1**4"},
        "initial": {"eta": [1.0], "varpi": [1.0]},
        "output": {"times": {"start": 0.0, "stop": 3.0, "count": 4}},
    }
    out = hostile.run(
        ["plan", str(hostile.scene(blows)), "--error", "1e-6"],
        expect="refused",
        field="no formulation could be piloted",
    )
    assert re.search(r"\(scene\): the pilot stopped: the state became non-finite", out.error_line)


@pytest.fixture(scope="module")
def rates_plan():
    return planner.plan(ch.Scene.from_dict(RATES), 1e-9)


@pytest.mark.covers("api:plan", "class:10")
@pytest.mark.parametrize(
    "error",
    [
        Fraction(1, 10**9),
        Decimal("1e-9"),
        "1e-9",
        np.float32(1e-9),
        np.float64(1e-9),
        np.longdouble("1e-9"),
    ],
    ids=_id,
)
def test_any_number_type_asks_for_an_error(rates_plan, error):
    again = rates_plan.for_error(error)
    assert again.error == pytest.approx(1e-9, rel=1e-6) and again.recommended is not None


@pytest.mark.covers("api:plan", "class:10")
@pytest.mark.parametrize(
    "error, why",
    [
        (10**400, "a double holds"),
        (-(10**400), "must be a number > 0"),
        (10**5000, "beyond 1e±4000"),
        (Fraction(1, 10**400), "a double holds"),
        (Decimal("NaN"), "finite"),
        (np.float64("nan"), "finite"),
        (np.int64(0), "must be a number > 0"),
        (1e-9j, "must be a number"),
        (None, "must be a number"),
        (True, "must be a number"),
    ],
    ids=_id,
)
def test_bad_numbers_raise_value_error_naming_the_argument(rates_plan, error, why):
    with pytest.raises(ValueError, match=f"^error: .*{re.escape(why)}"):
        rates_plan.for_error(error)
    with pytest.raises(ValueError, match=f"^error: .*{re.escape(why)}"):
        planner.plan(ch.Scene.from_dict(RATES), error)


@pytest.mark.covers("api:plan")
@pytest.mark.parametrize(
    "formulations, why",
    [("none", "must be a list of names"), ([], "names none"), (["euler"], "not among")],
)
def test_bad_formulations_raise_value_error_naming_the_argument(formulations, why):
    with pytest.raises(ValueError, match=f"^formulations: .*{why}"):
        planner.plan(ch.Scene.from_dict(RATES), 1e-9, formulations=formulations)
