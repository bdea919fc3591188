"""The whole attitude of a reduced body: the azimuth about u by quadrature (rotation/azimuth.py).

A heavy top whose vertical u = (0, 0.6, 0.8) is not a coordinate axis, started away from the
identity, integrated by the Euler–Poisson reduction with ``output.azimuth = true``: its
attitude (qw ≥ 0, qx, qy, qz and λ, μ, ν) against the quaternion formulation run in a higher
precision — an independent formulation — in double, quad and MPFR, through chart switches
and turns of the azimuth.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.families import FAMILIES

EPS = 2.0**-52

TOP = {
    "body": {"inertia": ["1", "1.6", "2.3"]},
    "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0.3", "-0.2", "0.1"]},
    "forces": {
        "heavy_top": {
            "weight": "1",
            "center_of_mass": ["0.1", "-0.05", "0.3"],
            "up": ["0", "0.6", "0.8"],
        }
    },
    "attitude": {"formulation": "poisson"},
    "output": {"times": {"start": "0", "stop": "30", "count": 121}, "azimuth": True},
}
# Each precision and the one its reference runs in.
PRECISIONS = {
    "double": ("double", "quad"),
    "quad": ("quad", {"bits": 160}),
    "real128": ({"bits": 128}, {"bits": 192}),
}


def run(d: dict, precision, **attitude) -> ch.Result:
    d = copy.deepcopy(d)
    d["integrator"] = {"precision": precision}
    d["attitude"].update(attitude)
    if attitude.get("formulation") == "quaternion":
        del d["output"]["azimuth"]
    return ch.run(ch.Scene.from_dict(d))


def quaternion(result: ch.Result) -> np.ndarray:
    q = np.array([result[n] for n in ("qw", "qx", "qy", "qz")])
    return q * np.where(q[0] < 0, -1, 1)


@pytest.mark.parametrize("precision", PRECISIONS, ids=list(PRECISIONS))
def test_the_attitude_of_the_reduced_body_is_the_full_ones(precision):
    """Within the error of the quaternion formulation itself (both against a run in more
    bits), through at least one chart switch and turns of the azimuth."""
    mine, more = PRECISIONS[precision]
    reduced = run(TOP, mine)
    assert reduced.success
    assert reduced.counters["azimuth_charts"] >= 1 and reduced.counters["azimuth_turns"] >= 1
    full = run(TOP, mine, formulation="quaternion")
    truth = quaternion(run(TOP, more, formulation="quaternion"))
    eps = float(reduced.precision.epsilon)
    ours = np.abs(quaternion(reduced) - truth).astype(float).max()
    theirs = np.abs(quaternion(full) - truth).astype(float).max()
    assert ours < 3 * theirs + 64 * eps * math.sqrt(reduced.counters["steps"]), (ours, theirs)
    # λ, μ, ν are the quaternion's ratios, as the full formulation reports them.
    for name, i in (("lambda", 1), ("mu", 2), ("nu", 3)):
        ratio = np.asarray(reduced[name] * reduced["qw"] - reduced[["qx", "qy", "qz"][i - 1]])
        assert np.abs(ratio.astype(float)).max() < 8 * eps


def test_a_start_with_body_z_near_the_vertical_starts_on_another_axis():
    """γ₃ = cos 0.32 = 0.95, inside the switching cone: the first chart is another axis; the
    attitude starts exact to a few ulps and stays within the quaternion formulation's error."""
    d = copy.deepcopy(TOP)
    d["forces"]["heavy_top"]["up"] = ["0", "0", "1"]
    d["initial"]["rodrigues"] = ["0.16", "0", "0"]  # a tilt of 2 atan 0.16 = 0.317 rad
    model = FAMILIES["rotation"].build(ch.Scene.from_dict(d))
    assert model.pars.values[model.pars.index("azimuth.e3")] == 0
    reduced, full = run(d, "double"), run(d, "double", formulation="quaternion")
    truth = quaternion(run(d, "quad", formulation="quaternion"))
    ours = np.abs(quaternion(reduced) - truth).astype(float)
    theirs = np.abs(quaternion(full) - truth).astype(float)
    assert ours[:, 0].max() < 4 * EPS
    assert ours.max() < 3 * theirs.max() + 64 * EPS * math.sqrt(reduced.counters["steps"])


def test_azimuth_needs_the_reduced_formulation_and_a_boolean():
    d = copy.deepcopy(TOP)
    d["attitude"]["formulation"] = "quaternion"
    with pytest.raises(ch.SceneError, match="output.azimuth.*reports it already"):
        ch.run(ch.Scene.from_dict(d))
    d = copy.deepcopy(TOP)
    d["output"]["azimuth"] = "yes"
    with pytest.raises(ch.SceneError, match="output.azimuth.*true or false"):
        ch.run(ch.Scene.from_dict(d))


def test_sweep_members_with_the_azimuth_run_in_lanes_as_run_does():
    """The chart switches and turns act on each lane's own parameters: run()'s steps, its
    final states to a few ulps (SIMD arithmetic rounds differently)."""
    from cayley_heyoka.workflows.members import PATH_LANES
    from cayley_heyoka.workflows.sweep import OK, Study, run_sweep

    rates = {"initial.rates[0]": ["0.3", "0.35", "0.4"]}
    study = Study.from_dict({"scene": TOP, "sweep": {"kind": "grid", "parameters": rates}})
    result = run_sweep(study, workers=1)
    assert result.metadata["paths"] == {PATH_LANES: 3}
    for i, values in enumerate(study.members()):
        alone = ch.run(study.member_scene(i, values))
        assert result.status[i] == OK and result.steps[i] == alone.counters["steps"]
        expected = [alone.variables[k][-1] for k in result.final_names]
        np.testing.assert_allclose(result.final_state[i], expected, rtol=0, atol=1e-13)
