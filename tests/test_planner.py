"""The speed–accuracy planner (workflows/planner.py): routes, recommendation, refusals, CLI.

Its predictions against whole runs over 10⁴–10⁵ steps are in validation/planner.py; here one
free body over ~10 pilots' worth of steps checks the extrapolation against the runs it predicts.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.cli import main
from cayley_heyoka.workflows import planner

BODY = {
    "body": {"inertia": ["1", "2", "3"]},
    "initial": {"rates": ["0.75", "-0.5", "0.625"]},
    "output": {"times": {"start": "0", "stop": "8000", "count": 41}},
}


@pytest.fixture(scope="module")
def body_plan():
    return planner.plan(ch.Scene.from_dict(BODY), 1e-11)


def test_every_allowed_formulation_in_double_and_quad(body_plan):
    """The rates alone ('none', the scene's own) in double and quad; the formulations that
    would integrate another motion are refused, each with the reason."""
    routes = {(r.formulation, r.precision) for r in body_plan.routes}
    assert routes == {("none", p) for p in ("double", "quad")}
    for other in ("quaternion", "rodrigues", "poisson"):
        assert "rates alone" in body_plan.refused[other]
    assert [r.seconds for r in body_plan.routes] == sorted(r.seconds for r in body_plan.routes)
    for r in body_plan.routes:
        quad = next(
            q for q in body_plan.routes if q.formulation == r.formulation and q.precision == "quad"
        )
        assert quad.state < 1e-12 * r.state or r.precision == "quad"


def test_the_recommendation_is_the_cheapest_route_meeting_the_error(body_plan):
    best = body_plan.recommended
    meeting = [r for r in body_plan.routes if r.state <= 1e-11]
    assert best is not None and best is min(meeting, key=lambda r: r.seconds)
    assert "recommended" in body_plan.message and "<-" in body_plan.text()


def test_the_extrapolation_meets_the_runs_it_predicts(body_plan):
    """The span is ~10 pilots: the double route's steps, state error and drift against the
    whole run (its quad twin as the truth), within the planner's bar."""
    route = next(r for r in body_plan.routes if (r.formulation, r.precision) == ("none", "double"))
    run = ch.run(ch.Scene.from_dict(BODY))
    truth = ch.run(ch.Scene.from_dict({**BODY, "integrator": {"precision": "quad"}}))
    assert abs(route.steps / run.counters["steps"] - 1) < 0.05
    state = float(np.max(planner._state_error(run, truth, ("lambda", "mu", "nu"))))
    assert 0.1 <= route.state / state <= 10, (route.state, state)
    drift = max(float(np.max(np.abs(np.asarray(run.drift(k))))) for k in run.conserved)
    assert 0.1 <= route.invariants / drift <= 10, (route.invariants, drift)


def test_an_error_no_route_reaches_names_the_closest_and_the_bits(body_plan):
    p = body_plan.for_error(1e-40)
    assert p.recommended is None and p.routes is body_plan.routes
    assert "no route reaches 1e-40" in p.message and "bits" in p.message
    bits = int(p.message.split("about ")[-1].split(" bits")[0])
    assert 130 < bits < 200


def test_another_request_on_the_same_routes_recommends_afresh(body_plan):
    loose = body_plan.for_error(1.0, "invariants")
    assert loose.quantity == "invariants" and loose.recommended is body_plan.routes[0]
    again = loose.for_error(body_plan.error, "state")
    assert again.recommended is body_plan.recommended and again.message == body_plan.message
    with pytest.raises(ValueError, match="error: must be a number > 0"):
        body_plan.for_error(0)
    with pytest.raises(ValueError, match="quantity: must be one of"):
        body_plan.for_error(1e-9, "phase")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"error": 0}, "error: must be a number > 0"),
        ({"error": -1e-9}, "error: must be a number > 0"),
        ({"error": math.nan}, "error: must be a finite number: "),
        ({"error": math.inf}, "error: must be a finite number: "),
        ({"error": True}, "error: must be a number"),
        ({"error": 1e-9, "quantity": "energy"}, "quantity: must be one of"),
        ({"error": 1e-9, "formulations": ["euler"]}, "formulations: .* not among"),
    ],
)
def test_bad_requests_are_refused_naming_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        planner.plan(ch.Scene.from_dict(BODY), **kwargs)


def test_cli_plan_exits_0_with_a_route_1_without_and_2_on_bad_input(tmp_path, capsys):
    scene = tmp_path / "body.toml"
    scene.write_text(
        "[body]\ninertia = [1, 2, 3]\n[initial]\nrates = [0.75, -0.5, 0.625]\n"
        '[attitude]\nformulation = "quaternion"\n'
        "[output]\ntimes = { start = 0, stop = 100, count = 11 }\n"
    )
    args = ["plan", str(scene), "--formulation", "quaternion"]
    assert main([*args, "--error", "1e-9"]) == 0
    out = capsys.readouterr().out
    assert "recommended: quaternion in double" in out
    assert main([*args, "--error", "1e-40"]) == 1
    assert "no route reaches" in capsys.readouterr().out
    assert main([*args, "--error", "-1"]) == 2
    assert "error: --error: must be a number > 0" in capsys.readouterr().err


def test_a_span_shorter_than_a_pilot_is_measured_whole():
    """~260 steps: the pilot runs the whole span, so the double route's steps are the run's and
    its error is measured against quad, not extrapolated (a projectile of 2 steps is planned,
    not refused)."""
    short = {**BODY, "output": {"times": {"start": "0", "stop": "100", "count": 11}}}
    p = planner.plan(ch.Scene.from_dict(short), 1e-9, formulations=["none"])
    route = next(r for r in p.routes if r.precision == "double")
    run = ch.run(ch.Scene.from_dict(short))
    truth = ch.run(ch.Scene.from_dict({**short, "integrator": {"precision": "quad"}}))
    assert route.steps == run.counters["steps"]
    measured = float(np.max(planner._state_error(run, truth, ("lambda", "mu", "nu"))))
    # The pilot's 65 output times include the scene's 11: its largest error is at least theirs.
    assert measured <= route.state <= 10 * measured, (route.state, measured)
    projectile = ch.load_scene(Path(__file__).parents[1] / "examples" / "projectile.toml")
    assert planner.plan(projectile, 1e-12).recommended is not None
