"""The rotation engine end to end: forces, the chart atlas, events, caching, failures, files."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PRECISIONS, free_body

from cayley_heyoka import IntegrationError, Result, Scene, run
from cayley_heyoka.core import compiler
from cayley_heyoka.core.families import FAMILIES

HEAVY_TOP = {"heavy_top": {"weight": "1", "center_of_mass": ["0.1", "-0.05", "0.3"]}}


@pytest.mark.parametrize("formulation", ["rodrigues", "quaternion"])
@pytest.mark.parametrize("prec_name", ["double", "quad"])
def test_heavy_top_conserves_energy_and_vertical_momentum(formulation, prec_name):
    prec = PRECISIONS[prec_name]
    stop = "100" if prec_name == "double" else "10"
    data = free_body(
        body={"inertia": ["1", "1.6", "2.3"]},
        initial={"rates": ["0.3", "1", "0.5"]},
        forces=HEAVY_TOP,
        attitude={"formulation": formulation},
        integrator={"precision": prec.to_spec()},
        output={"times": {"start": "0", "stop": stop, "count": 101}},
    )
    result = run(Scene.from_dict(data))
    assert set(result.conserved) == {"energy", "momentum_vertical"}
    bound = 30 * prec.epsilon * np.sqrt(result.counters["steps"])
    for name in result.conserved:
        assert float(np.max(np.abs(result.drift(name)))) < bound, name
    # the torque is real: |L|² is not conserved
    assert float(np.max(np.abs(result.drift("momentum_squared")))) > 1e-3


@pytest.mark.parametrize("formulation", ["rodrigues", "quaternion"])
def test_gravity_gradient_conserves_energy(formulation):
    data = free_body(
        forces={
            "gravity_gradient": {"gm": "4", "distance": "1.5", "direction": ["0", "0.6", "0.8"]}
        },
        attitude={"formulation": formulation},
        output={"times": {"start": "0", "stop": "100", "count": 101}},
    )
    result = run(Scene.from_dict(data))
    assert result.conserved == ("energy",)
    assert float(np.max(np.abs(result.drift("energy")))) < 30 * 2.0**-52 * np.sqrt(
        result.counters["steps"]
    )
    assert float(np.max(np.abs(result.drift("momentum_squared")))) > 1e-3


def test_rodrigues_atlas_matches_quaternions_through_many_half_turns():
    """≥ 100 passages of the rotation angle through π, counted by an event on w = cos(θ/2)."""
    data = free_body(
        body={"inertia": ["1", "1.6", "2.3"]},
        initial={"rates": ["0.4", "3", "0.6"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        output={"times": {"start": "0", "stop": "250", "count": 51}, "events": ["half_turn"]},
        events={"half_turn": {"expression": "qw"}},
        attitude={"formulation": "rodrigues"},
    )
    atlas = run(Scene.from_dict(data))
    data["attitude"] = {"formulation": "quaternion"}
    quat = run(Scene.from_dict(data))
    passages = len(atlas.events["half_turn"])
    assert passages >= 100
    assert atlas.counters["rebasings"] >= passages
    assert len(quat.events["half_turn"]) == passages
    for name in ("p", "q", "r", "qw", "qx", "qy", "qz"):
        assert np.max(np.abs(atlas[name] - quat[name])) < 1e-11, name
    # the reported quaternion is continuous: no sign flips at re-basings
    dense_data = {**data, "attitude": {}, "events": {}}
    dense_data["output"] = {"times": {"start": "0", "stop": "20", "count": 4001}}
    dense = run(Scene.from_dict(dense_data))
    steps = np.abs(np.diff(np.array([dense[k] for k in ("qw", "qx", "qy", "qz")]), axis=1))
    assert np.max(steps) < 0.02


@pytest.mark.parametrize("formulation", ["rodrigues", "quaternion"])
def test_invariable_plane_crossings_are_the_zeros_of_the_rates(formulation):
    data = free_body(
        initial={"rates": ["0.6", "0.5", "0.9"]},
        attitude={"formulation": formulation},
        output={
            "times": {"start": "0", "stop": "60", "count": 2},
            "events": ["invariable_plane", "p_zero", "q_zero", "r_zero"],
        },
        events={f"{c}_zero": {"expression": c} for c in "pqr"},
    )
    result = run(Scene.from_dict(data))
    plane = result.events["invariable_plane"]
    assert len(plane) > 20
    for axis, rate in (("x1", "p_zero"), ("y1", "q_zero"), ("z1", "r_zero")):
        mine = plane.where(axis)
        theirs = result.events[rate].time
        assert len(mine) == len(theirs), axis
        if len(mine):
            assert np.max(np.abs(mine - theirs)) < 1e-12, axis
            assert np.array_equal(
                plane.direction[plane.label == axis], result.events[rate].direction
            )
    # near the major axis the dn-component r never vanishes: z1 never crosses the plane
    assert len(result.events["r_zero"]) == 0


@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues"])
def test_a_half_turn_is_an_attitude_like_any_other(formulation):
    """λ, μ, ν = tan(θ/2) n are infinite (0/0 across the axis) at a half-turn: a start there
    is run, not refused as a non-finite output, in either formulation, and they are finite
    again once the body has turned on."""
    data = free_body(
        initial={"rates": ["0.125", "0.25", "1"], "quaternion": ["0", "1", "0", "0"]},
        attitude={"formulation": formulation},
    )
    del data["initial"]["rodrigues"]
    result = run(Scene.from_dict(data))
    assert result.success and len(result.t) == 11
    assert np.isinf(result["lambda"][0]) and np.isnan(result["mu"][0])
    for name in ("lambda", "mu", "nu"):
        assert np.all(np.isfinite(result[name][1:])), name
    # The same attitude as the quaternion's, through the λ, μ, ν that stay finite.
    assert np.allclose(result["lambda"][1:] * result["qw"][1:], result["qx"][1:], atol=1e-12)


def test_only_the_needed_terms_are_compiled():
    build = FAMILIES["rotation"].build
    data = free_body()
    del data["initial"]["rodrigues"]
    rates_only = build(Scene.from_dict(data))
    assert rates_only.state_names == ["p", "q", "r"]
    # An attitude is integrated as a quaternion unless the scene names the chart.
    free = build(Scene.from_dict(free_body()))
    assert free.state_names == ["p", "q", "r", "qw", "qx", "qy", "qz"]
    assert not free.terminal
    chart = build(Scene.from_dict(free_body(attitude={"formulation": "rodrigues"})))
    assert chart.state_names == ["p", "q", "r", "lambda", "mu", "nu"]
    assert "lambda" not in str(chart.system[0][1])
    top = build(Scene.from_dict(free_body(forces=HEAVY_TOP, attitude={"formulation": "rodrigues"})))
    assert "lambda" in str(top.system[0][1])
    top = build(Scene.from_dict(free_body(forces=HEAVY_TOP)))
    assert "qw" in str(top.system[0][1]) and "lambda" not in str(top.system[0][1])


@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues"])
def test_euler_equations_divide_by_the_moment_instead_of_rounding_a_quotient(formulation):
    """Issue 20: ``((B − C)(q r)) / A``, the differences exact and the division compiled — not
    ``((B − C)/A) q r`` with the quotient rounded once, whose rounding made the energy drift
    of the generic body lean one way (validation/drift_bias.py); and the difference times the
    product of two rates, not ``((C − A) r) p``, whose first product rounds alike at every step
    where r hardly changes (a nearly symmetric body's shared drift)."""
    data = free_body(attitude={"formulation": formulation})
    data["body"]["inertia"] = ["1", "2", "3"]  # the generic body: (A − B)/C = −1/3 is inexact
    model = FAMILIES["rotation"].build(Scene.from_dict(data))
    names = model.pars.names
    par = {name: f"p{names.index(name)}" for name in ("A", "B", "C", "B-C", "C-A", "A-B")}
    rhs = {str(var): str(expr) for var, expr in model.system[:3]}
    assert rhs["p"] == f"(({par['B-C']} * (q * r)) / {par['A']})"
    assert rhs["q"] == f"(({par['C-A']} * (r * p)) / {par['B']})"
    assert rhs["r"] == f"(({par['A-B']} * (p * q)) / {par['C']})"
    values = dict(zip(names, model.pars.values, strict=True))
    assert [float(values[k]) for k in ("B-C", "C-A", "A-B")] == [-1.0, 2.0, -1.0]


def test_compiled_integrators_are_reused():
    compiler.clear_cache()
    first = run(Scene.from_dict(free_body()))
    again = run(Scene.from_dict(free_body()))
    other_numbers = run(
        Scene.from_dict(free_body(body={"inertia": [2, 3, 4]}, initial={"rates": [1, 1, 1]}))
    )
    assert not first.metadata["compiled_from_cache"]
    assert again.metadata["compiled_from_cache"] and other_numbers.metadata["compiled_from_cache"]
    assert compiler.cache_size() == 1
    assert np.array_equal(first["p"], again["p"])
    assert not np.array_equal(first["p"], other_numbers["p"])


def test_max_step_caps_steps_without_recompiling():
    """A step cap is a runtime argument: same compiled integrator, more and shorter steps."""
    free = run(Scene.from_dict(free_body()))
    capped = run(Scene.from_dict(free_body(integrator={"max_step": "0.05"})))
    assert capped.metadata["compiled_from_cache"]
    assert capped.counters["steps"] >= 10 / 0.05 > free.counters["steps"]
    assert np.allclose(capped["qw"], free["qw"], rtol=0, atol=1e-13)


@pytest.mark.parametrize("prec_name", ["double", "quad"])
def test_output_times_do_not_perturb_a_run_with_terminal_events(prec_name):
    """Outputs come from dense output even between chart re-basings (terminal events): with
    outputs sparser and denser than the re-basings, the step count and the last state are the
    same. Reaching each output with propagate_until would end a step there — one rounding
    kick per output, and a cost that grew with the remaining grid at every output."""
    prec = PRECISIONS[prec_name]
    stop = "200" if prec_name == "double" else "20"

    def scene(count):
        return Scene.from_dict(
            free_body(
                integrator={"precision": prec.to_spec()},
                output={"times": {"start": "0", "stop": stop, "count": count}},
                attitude={"formulation": "rodrigues"},
            )
        )

    sparse, dense = run(scene(2)), run(scene(401))
    assert dense.counters["rebasings"] > 5
    assert dense.counters == sparse.counters
    for name in ("p", "q", "r", "qw", "qx", "qy", "qz"):
        assert dense[name][-1] == sparse[name][-1], name


def test_a_run_that_blows_up_keeps_what_it_computed():
    data = free_body(
        forces={"potential": {"V": "exp(100 * (t - 6)) * lambda"}},
        output={"times": {"start": "0", "stop": "20", "count": 21}},
    )
    with pytest.raises(IntegrationError, match="non-finite") as info:
        run(Scene.from_dict(data))
    partial = info.value.result
    assert not partial.success
    assert 6 <= len(partial.t) < 21
    assert np.all(np.isfinite(partial["p"]))


def test_user_potential_in_rodrigues_matches_heavy_top():
    cosines = "-(0.1 * R31 - 0.05 * R32 + 0.3 * R33)"
    user = run(Scene.from_dict(free_body(forces={"potential": {"V": cosines}})))
    top = run(Scene.from_dict(free_body(forces=HEAVY_TOP)))
    assert np.max(np.abs(user["p"] - top["p"])) < 1e-13


@pytest.mark.parametrize("prec_name", ["double", "quad", "real256"])
def test_result_files_round_trip_exactly(tmp_path, prec_name):
    prec = PRECISIONS[prec_name]
    data = free_body(
        integrator={"precision": prec.to_spec()},
        output={"times": {"start": "0", "stop": "3", "count": 4}, "events": ["invariable_plane"]},
    )
    result = run(Scene.from_dict(data))
    path = tmp_path / "r.h5"
    result.save(path)
    back = Result.load(path)
    assert back.precision == prec
    assert back.scene == result.scene and back.counters == result.counters
    for name in result.variables:
        assert all(a == b for a, b in zip(result[name], back[name], strict=True)), name
    assert np.all(back["momentum_space"] == result["momentum_space"])
    ev, ev2 = result.events["invariable_plane"], back.events["invariable_plane"]
    assert len(ev) > 0 and all(a == b for a, b in zip(ev.time, ev2.time, strict=True))
    assert list(ev.label) == list(ev2.label)
    assert Scene.from_dict(back.scene).integrator.precision == prec


@pytest.mark.slow
@pytest.mark.parametrize("formulation", ["rodrigues", "quaternion"])
def test_long_run_drift_follows_brouwer(formulation):
    """10⁵+ steps in double: the invariants' drift stays within a small multiple of ε √steps."""
    data = free_body(
        body={"inertia": ["1", "1.6", "2.3"]},
        initial={"rates": ["0.3", "1", "0.5"]},
        attitude={"formulation": formulation},
        output={"times": {"start": "0", "stop": "50000", "count": 201}},
    )
    result = run(Scene.from_dict(data))
    steps = result.counters["steps"]
    assert steps > 1e5
    for name in result.conserved:
        worst = float(np.max(np.abs(result.drift(name))))
        assert worst < 30 * 2.0**-52 * np.sqrt(steps), (name, worst)


# A rebasing just before an output time whose double is coarse (ulp 0.125 near 1e15) has that
# time as its high part: the row comes after the handler, so it must take the new chart base.
_LATE = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.125", "0.25", "1"], "rodrigues": ["0.1", "0.2", "-0.3"]},
    "attitude": {"formulation": "rodrigues"},
    "output": {"times": {"start": "1e15", "stop": "1000000000000100", "count": 65}},
}


def test_rows_beside_a_rebasing_at_a_coarse_time_take_the_right_chart_base():
    result = run(Scene.from_dict(_LATE))
    assert result.counters["rebasings"] > 10
    assert np.max(np.abs(result.drift("momentum_space"))) < 1e-13


def test_sweep_members_beside_a_rebasing_at_a_coarse_time_take_the_right_chart_base():
    from cayley_heyoka.workflows.study import Study
    from cayley_heyoka.workflows.sweep import run_sweep

    study = Study.from_dict(
        {
            "scene": _LATE,
            "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": ["0.125", "0.126"]}},
        }
    )
    sweep = run_sweep(study, workers=1)
    assert np.all(sweep.status == 0)
    assert np.max(np.abs(sweep.drift["momentum_space"])) < 1e-13
