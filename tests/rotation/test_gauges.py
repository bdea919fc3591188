"""Norms that are gauges: the quaternion's, the chart base's and the Euler–Poisson γ's.

q and c·q are one attitude, and γ and c·γ one direction, and nothing physical may read c.
Truncation drifts the integrated |q| or |γ| one way step after step in a steady rotation
(measured in validation/BENCHMARKS.md, "Long-time conservation"); R(q) or γ alone would carry
that drift into L in space, the forces and the monitors. These runs start from a state scaled
by 1.5: everything but the monitor of the norm itself must be what the unit state gives.
"""

from __future__ import annotations

import heyoka as hy
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.families import FAMILIES

SCALE = 1.5


def scene(forced: bool) -> ch.Scene:
    data = {
        "body": {"inertia": [1.0, 1.6, 2.3]},
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
        "attitude": {"formulation": "quaternion"},
        "output": {"times": [0.0, 5.0]},
    }
    if forced:
        data["forces"] = {
            "heavy_top": {"weight": 1.0, "center_of_mass": [0.1, -0.05, 0.3], "up": [0, 0, 1]}
        }
    return ch.Scene.from_dict(data)


def integrate(
    model, scale: float, names=("qw", "qx", "qy", "qz")
) -> tuple[np.ndarray, list[hy.expression]]:
    """The state at t = 5 from the scene's start with the variables ``names`` scaled, and the
    state's variables."""
    variables = [v for v, _ in model.system]
    state = np.array(model.initial_state, dtype=float)
    scaled = [variables.index(hy.expression(n)) for n in names]
    state[scaled] *= scale
    ta = hy.taylor_adaptive(model.system, state, pars=np.array(model.pars.values, dtype=float))
    status, *_ = ta.propagate_until(5.0)
    assert status == hy.taylor_outcome.time_limit
    return ta.state.copy(), variables


def evaluate(model, expressions, state, variables) -> np.ndarray:
    f = hy.cfunc(expressions, vars=variables)
    pars = np.array(model.pars.values, dtype=float)[: f.nparams]
    return np.asarray(f(state, pars=pars))


@pytest.mark.parametrize("forced", [False, True], ids=["free body", "heavy top"])
def test_a_scaled_quaternion_is_the_same_motion(forced):
    model = FAMILIES["rotation"].build(scene(forced))
    unit, variables = integrate(model, 1.0)
    scaled, _ = integrate(model, SCALE)
    # The rates: the heavy top's torque reads the normalised attitude (R(q) would be 2.25×).
    np.testing.assert_allclose(scaled[:3], unit[:3], rtol=0, atol=1e-13)
    names = ["qw", "qx", "qy", "qz", "lambda", "mu", "nu"]
    outputs = [model.outputs[n] for n in names]
    monitors = [model.monitors["energy"], *model.monitors["momentum_space"]]
    for exprs in (outputs, monitors):
        np.testing.assert_allclose(
            evaluate(model, exprs, scaled, variables),
            evaluate(model, exprs, unit, variables),
            rtol=0,
            atol=1e-13,
        )
    # The integrated frame's defect still shows the norm: |q|⁴ − 1 on the diagonal.
    defect = evaluate(model, [model.monitors["orthogonality"]], scaled, variables)[0]
    assert defect == pytest.approx(np.sqrt(3) * (SCALE**4 - 1), rel=1e-12)


def test_a_scaled_chart_base_is_the_same_motion():
    """The Rodrigues chart's base quaternion is normalised at each fold only to a rounding: the
    forces must read its rotation, not R(qb) = |qb|² × rotation."""
    data = {
        "body": {"inertia": [1.0, 1.6, 2.3]},
        # A rotation by ~169°: outside the identity chart (160°), so the run starts in a chart
        # based at the initial attitude.
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [10.0, 1.0, 0.0]},
        "forces": {
            "heavy_top": {"weight": 1.0, "center_of_mass": [0.1, -0.05, 0.3], "up": [0, 0, 1]}
        },
        "attitude": {"formulation": "rodrigues"},
        "output": {"times": [0.0, 1.0]},
    }
    model = FAMILIES["rotation"].build(ch.Scene.from_dict(data))
    base = [model.pars.names.index(f"chart.base[{i}]") for i in range(4)]
    pars = np.array(model.pars.values, dtype=float)
    assert abs(pars[base[0]]) < 0.2  # the base is the initial attitude, not the identity
    ends = []
    for scale in (1.0, SCALE):
        scaled = pars.copy()
        scaled[base] *= scale
        ta = hy.taylor_adaptive(model.system, np.array(model.initial_state, float), pars=scaled)
        status, *_ = ta.propagate_until(1.0)  # no fold: κ stays below its limit over t = 1
        assert status == hy.taylor_outcome.time_limit
        ends.append(ta.state.copy())
    np.testing.assert_allclose(ends[1], ends[0], rtol=0, atol=1e-13)


@pytest.mark.parametrize(
    "forces",
    [
        {"heavy_top": {"weight": 1.0, "center_of_mass": [0.1, -0.05, 0.3], "up": [0, 0, 1]}},
        # Not linear in γ: the gradient itself must be taken at γ/|γ|.
        {"potential": {"V": "-(0.1 * R31 + 0.3 * R33) + 0.2 * R31 * R32 - 0.1 * R33**3"}},
    ],
    ids=["heavy top", "cubic V"],
)
def test_a_scaled_direction_is_the_same_motion(forces):
    """The Euler–Poisson reduction's γ: Poisson's equations are linear in γ, so 1.5·γ must give
    the same rates, the same unit direction and the same energy and area integral."""
    data = {
        "body": {"inertia": [1.0, 1.6, 2.3]},
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
        "forces": forces,
        "attitude": {"formulation": "poisson"},
        "output": {"times": [0.0, 5.0]},
    }
    model = FAMILIES["rotation"].build(ch.Scene.from_dict(data))
    names = ("gamma1", "gamma2", "gamma3")
    unit, variables = integrate(model, 1.0, names)
    scaled, _ = integrate(model, SCALE, names)
    # γ × ∇V(γ) would be 1.5× (linear V) or worse: the torque must read γ/|γ|.
    np.testing.assert_allclose(scaled[:3], unit[:3], rtol=0, atol=1e-13)
    np.testing.assert_allclose(scaled[3:6], SCALE * unit[3:6], rtol=0, atol=1e-13)
    exprs = [*(model.outputs[n] for n in names), model.monitors["energy"]]
    exprs.append(model.monitors["momentum_vertical"])
    np.testing.assert_allclose(
        evaluate(model, exprs, scaled, variables),
        evaluate(model, exprs, unit, variables),
        rtol=0,
        atol=1e-13,
    )
    norm2 = evaluate(model, [model.monitors["direction_norm"]], scaled, variables)[0]
    assert norm2 == pytest.approx(SCALE**2, rel=1e-12)
