"""Ψ = 2 tan⁻¹ν₀ integrated with the motion (``output.invariable_angle``), against Cayley's
closed form in every precision and formulation; its turns; its refusals."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.reference import FreeRigidBody
from cayley_heyoka.workflows.study import Study

EPS = {"double": 2.0**-52, "quad": 2.0**-112, "mpfr160": 2.0**-159}
SPEC = {"double": "double", "quad": "quad", "mpfr160": {"bits": 160}}


def scene(inertia, rates, formulation="quaternion", precision="double", stop=100, **output):
    return ch.Scene.from_dict(
        {
            "body": {"inertia": list(inertia)},
            "initial": {"rates": list(rates)},
            "attitude": {"formulation": formulation},
            "integrator": {"precision": SPEC[precision]},
            "output": {
                "times": {"start": 0, "stop": stop, "count": 11},
                "invariable_angle": True,
                **output,
            },
        }
    )


def psi_error(result, body) -> tuple[float, float]:
    """Largest |Ψ − Ψ_closed form| and largest |Ψ| over the outputs."""
    with mpmath.workdps(60):
        pairs = zip(result.t, result["psi"], strict=True)
        errors = [abs(mpmath.mpf(str(x)) - body.at(t).psi) for t, x in pairs]
        return float(max(errors)), float(max(abs(mpmath.mpf(str(x))) for x in result["psi"]))


@pytest.mark.parametrize("precision", list(SPEC))
@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues", "none"])
def test_psi_follows_the_closed_form(precision, formulation):
    """Over ~14 turns of Ψ, the error stays within Brouwer's 10 ε √N of |Ψ|: round-off, in
    each precision (a double constant in a quad system would leave ~1e-17 of |Ψ|)."""
    body = FreeRigidBody([1, 2, 3], [0.75, -0.5, 0.625], dps=60)
    result = ch.run(scene((1, 2, 3), (0.75, -0.5, 0.625), formulation, precision))
    error, size = psi_error(result, body)
    steps = result.counters["steps"]
    assert result.counters["psi_turns"] == 14
    assert error < 10 * EPS[precision] * math.sqrt(steps) * size, (error, size, steps)
    assert type(result["psi"][-1]) is type(result["p"][-1])


def test_psi_turns_backwards_where_its_rate_is_negative():
    """dΨ/dt = (h + kr)/(k + Cr) < 0 for a slender body spun against its third axis: Ψ falls
    through hundreds of turns, still on the closed form (to the conditioning of k + Cr ≈ k/200,
    which amplifies the rates' rounding in dΨ/dt)."""
    inertia, rates = (1, 1, 0.1), (0.1, 0, -10)
    body = FreeRigidBody(inertia, rates, dps=40)
    result = ch.run(scene(inertia, rates, stop=100))
    error, size = psi_error(result, body)
    assert float(result["psi"][-1]) < -700 and result.counters["psi_turns"] > 100
    assert error < 500 * EPS["double"] * size


def test_psi_leaves_the_rates_alone():
    """The reduced state keeps |u| < 0.8, so heyoka's error control (scaled by the largest
    state component) keeps the rates' tolerance: their error against the closed form stays at
    the size it has without Ψ."""
    inertia, rates = (1, 1.5, 2.5), (0.125, 0.25, 1.0)
    body = FreeRigidBody(inertia, rates, dps=30)
    errors = {}
    for psi in (False, True):
        result = ch.run(scene(inertia, rates, stop=300, invariable_angle=psi))
        errors[psi] = max(
            abs(float(result[n][i]) - float(getattr(body.at(t), n)))
            for i, t in enumerate(result.t)
            for n in "pqr"
        )
    assert errors[True] < 10 * errors[False] + 1e-14


def test_psi_in_a_sweep_matches_a_run():
    base = scene((1, 2, 3), (0.75, -0.5, 0.625)).to_dict()
    study = Study.from_dict(
        {"scene": base, "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": [0.75, 0.7]}}}
    )
    sweep = ch.run_sweep(study)
    alone = ch.run(ch.Scene.from_dict(base))
    psi = list(sweep.final_names).index("psi")
    assert abs(sweep.final_state[0][psi] - float(alone["psi"][-1])) < 1e-12


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"forces": {"heavy_top": {"weight": 1, "center_of_mass": [0, 0, 0.1]}}}, "torque-free"),
        ({"initial": {"rates": [0, 0, -1]}}, "undefined"),
        ({"initial": {"rates": [0, 0, 0]}}, "undefined"),
        ({"output": {"times": [0, 1], "invariable_angle": "yes"}}, "true or false"),
    ],
)
def test_psi_is_refused_where_it_is_undefined(change, message):
    data = scene((1, 2, 3), (0.75, -0.5, 0.625)).to_dict()
    data.update(change)
    if "invariable_angle" not in data["output"]:
        data["output"]["invariable_angle"] = True
    with pytest.raises(ch.SceneError) as info:
        ch.run(ch.Scene.from_dict(data))
    assert info.value.field == "output.invariable_angle"
    assert message in str(info.value)


def test_steady_rotation_about_the_third_axis_has_psi_equal_to_rt():
    """p = q = 0, r > 0: the body spins about L, Ψ = r t exactly (up to the rounding of rt)."""
    result = ch.run(scene((1, 2, 3), (0, 0, 0.5), stop=100))
    expected = 0.5 * np.asarray(result.t, dtype=float)
    assert np.max(np.abs(np.asarray(result["psi"], dtype=float) - expected)) < 1e-12
