"""Norms that are gauges: the quaternion's and the Rodrigues chart base's.

q and c·q are one attitude, and nothing physical reads c.

Truncation drifts the integrated |q| one way step after step in a steady rotation (measured in
validation/BENCHMARKS.md, "Long-time conservation"); R(q) alone would carry that drift into L in
space and into the forces. These runs start from a quaternion scaled by 1.5: everything but the
orthogonality monitor must be what the unit quaternion gives.
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


def integrate(model, scale: float) -> tuple[np.ndarray, list[hy.expression]]:
    """The state at t = 5 from the scene's start with q scaled, and the state's variables."""
    variables = [v for v, _ in model.system]
    state = np.array(model.initial_state, dtype=float)
    quaternion = [variables.index(hy.expression(n)) for n in ("qw", "qx", "qy", "qz")]
    state[quaternion] *= scale
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
