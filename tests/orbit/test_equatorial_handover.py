"""Cayley's orbit through Φ = 0: the hand-over to a tilted working frame and back (orbit/tilt.py).

The scene: a Kepler orbit of inclination i = 0.5, node 0, against a reference plane tilting
about its x-axis, φ′ = 0.05 t. Both normals stay in the y-z plane, so Φ(t) = |i − φ′ t|
exactly, 0 at t = 10: sin Φ falls to ε = 10⁻³ at t* = (i − asin ε)/φ̇′ = 9.98 (hand-over), rises
through ε at (i + asin ε)/φ̇′ and through 2ε at (i + asin 2ε)/φ̇′ = 10.04 (hand-back).
"""

from __future__ import annotations

import json
import math

import mpmath
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.engine import Propagation
from cayley_heyoka.orbit import tilt
from cayley_heyoka.workflows.members import PATH_LANES, PATH_RUN
from cayley_heyoka.workflows.sweep import OK, Study, run_sweep

INCLINATION, PHI_RATE, LIMIT = "0.5", "0.05", "1e-3"
EPS = 2.0**-52
PRECISIONS = {"double": "double", "quad": "quad", "real128": {"bits": 128}}


def scene(formulation: str = "cayley", precision="double", **orbit) -> dict:
    elements = {
        "a": "1",
        "e": "0.1",
        "inclination": INCLINATION,
        "node": "0",
        "argument_of_pericentre": "0.3",
        "mean_anomaly": "0",
    }
    return {
        "orbit": {
            "mu": "1",
            "elements": elements,
            "formulation": formulation,
            "equatorial_limit": LIMIT,
            **orbit,
        },
        "reference_plane": {"phi_rate": PHI_RATE},
        "integrator": {"precision": precision},
        "output": {
            "times": {"start": "0", "stop": "20", "count": 41},
            "events": ["equatorial", "node"],
        },
    }


def run(d: dict) -> ch.Result:
    return ch.run(ch.Scene.from_dict(d))


def analytic(t: np.ndarray) -> dict[str, float]:
    """Φ on the grid and the crossing times, at 40 digits."""
    with mpmath.workdps(40):
        i, w, eps = (mpmath.mpf(v) for v in (INCLINATION, PHI_RATE, LIMIT))
        phi = [abs(i - w * mpmath.mpf(str(x))) for x in t]
        times = [(i - mpmath.asin(eps)) / w, (i + mpmath.asin(eps)) / w]
    return {"phi": phi, "approach": times[0], "recede": times[1]}


# The event function |L|²(1 − ε²) − (k̂·L)² = |L|²(sin²Φ − ε²) is evaluated with round-off
# ≲ 6ε|L|² (two terms of size |L|², each with a few roundings) while it changes at the rate
# 2|L|² sin Φ cos Φ Φ̇: its zeros are located to 3ε/(sin Φ cos Φ Φ̇) ≈ 1.3e-11 here (10⁻³ · 0.05
# is a slow crossing).
EQUATORIAL_DT = 3 * EPS / (float(LIMIT) * float(PHI_RATE))


def eps_of(result: ch.Result) -> float:
    return float(result.precision.epsilon)


@pytest.mark.parametrize("precision", PRECISIONS, ids=list(PRECISIONS))
def test_cayley_runs_through_phi_zero_in_every_precision(precision):
    """The run reaches every output time, handing over at ε and back at 2ε; Φ = |i − φ′ t| on
    every row (Φ = 0 at t = 10 included); the position is the Cartesian formulation's, in the
    same precision, to round-off; Θ and Σ are NaN exactly on the tilted rows."""
    res = run(scene(precision=PRECISIONS[precision]))
    cart = run(scene("cartesian", PRECISIONS[precision]))
    eps = eps_of(res)
    assert res.success and len(res.t) == 41
    assert res.counters["equatorial_handovers"] == 2
    exact = analytic(np.asarray(res.t, dtype=float))
    # Φ read off the tilted frame near Φ = 0 is atan2 of a √ of O(ε) rounded terms: an
    # absolute error of a few ε; untilted, Φ is integrated, its error ε√N.
    with mpmath.workdps(40):
        errors = [
            abs(mpmath.mpf(str(p)) - e) for p, e in zip(res["Phi"], exact["phi"], strict=True)
        ]
    assert float(max(errors)) < 16 * eps * math.sqrt(res.counters["steps"]), float(max(errors))
    t = np.asarray(res.t, dtype=float)
    tilted = (t > float(exact["approach"])) & (t < 10.04)
    assert list(t[tilted]) == [10.0]
    for name in ("Theta", "Sigma"):
        values = np.array([float(v) for v in res[name]])
        assert np.all(np.isnan(values[tilted])) and np.all(np.isfinite(values[~tilted]))
    scale = max(1.0, float(np.max(np.abs(np.asarray(cart["x"], dtype=float)))))
    for k in ("x", "y", "z", "vx", "vy", "vz"):
        d = np.abs(np.asarray(res[k] - cart[k], dtype=float))
        assert np.max(d) < 64 * eps * math.sqrt(res.counters["steps"]) * scale, (k, np.max(d))
    energy = np.asarray(res.drift("energy"), dtype=float)
    assert np.max(np.abs(energy)) < 16 * eps * math.sqrt(res.counters["steps"])


def test_angles_after_the_passage_are_those_of_the_orbit():
    """Back on the reference plane Θ, Σ are the orbit's (against the quaternion formulation,
    whose Θ, Σ are read off its frame, modulo whole turns), and Θ − Σ, the one angle defined
    through Φ = 0, is continuous across the passage."""
    res, quat = run(scene()), run(scene("quaternion"))
    t = np.asarray(res.t, dtype=float)
    after = t > 10.04
    for name in ("Theta", "Sigma"):
        d = np.asarray(res[name] - quat[name], dtype=float)[after]
        d = (d + math.pi) % (2 * math.pi) - math.pi
        # ε/sin Φ near the plane: sin Φ ≥ 0.025 on these rows.
        assert np.max(np.abs(d)) < 1e-12, (name, np.max(np.abs(d)))
    # The passage flips the node by π (the plane went through the orbit): Θ − Σ keeps its
    # value modulo 2π.
    before, later = np.asarray(res["Theta"] - res["Sigma"], dtype=float)[[19, 21]]
    jump = (later - before + math.pi) % (2 * math.pi) - math.pi
    assert abs(jump) < 1e-9


def test_equatorial_events_are_found_once_each_across_the_handovers():
    res = run(scene())
    exact = analytic(np.asarray(res.t, dtype=float))
    ev = res.events["equatorial"]
    assert list(ev.label) == ["approach", "recede"]
    when = [float(exact["approach"]), float(exact["recede"])]
    assert np.max(np.abs(np.asarray(ev.time, dtype=float) - when)) < EQUATORIAL_DT
    # Nodes of the orbit on the reference plane: the Cartesian formulation's, one per half-turn.
    cart = run(scene("cartesian"))
    assert len(res.events["node"]) == len(cart.events["node"]) > 4
    d = np.asarray(res.events["node"].time - cart.events["node"].time, dtype=float)
    assert np.max(np.abs(d)) < 1e-10
    assert list(res.events["node"].label) == list(cart.events["node"].label)


def test_an_orbit_starting_in_the_reference_plane_starts_tilted():
    """Near-equatorial from the start (i = 5e-4 < ε, J₂): the run starts on the tilted frame,
    never hands back (J₂ keeps the inclination), and follows the Cartesian orbit."""
    d = {
        "orbit": {
            "mu": "1",
            "elements": {
                "a": "1",
                "e": "0.2",
                "inclination": "5e-4",
                "node": "0.4",
                "argument_of_pericentre": "0.3",
                "mean_anomaly": "0",
            },
            "formulation": "cayley",
        },
        "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.5"}},
        "output": {"times": {"start": "0", "stop": "30", "count": 31}},
    }
    runs = {}
    for formulation, precision in (
        ("cayley", "double"),
        ("quaternion", "double"),
        ("cartesian", "double"),
        ("cartesian", "quad"),
        ("quaternion", "quad"),
    ):
        d["orbit"]["formulation"] = formulation
        d["integrator"] = {"precision": precision}
        runs[formulation, precision] = run(d)
    res, truth = runs["cayley", "double"], runs["cartesian", "quad"]
    assert res.success and res.counters["equatorial_handovers"] == 0
    assert np.all(np.isnan(np.asarray(res["Theta"], dtype=float)))

    def error(r: ch.Result, names=("x", "y", "z")) -> float:
        return max(float(np.max(np.abs(np.asarray(r[k] - truth[k], dtype=float)))) for k in names)

    # As accurate as the regular formulations (measured: 4.7e-14 against 4.9e-14, 5.5e-14).
    regular = max(error(runs["quaternion", "double"]), error(runs["cartesian", "double"]))
    assert error(res) < 3 * regular, (error(res), regular)
    # Φ ≈ 5e-4 to the absolute round-off of the plane's orientation (measured 1.2e-15): the
    # tilted frame carries it as π/2 − Φ_W. (The quaternion, near the identity here, carries
    # it to relative round-off, 5e-19.)
    truth = runs["quaternion", "quad"]
    assert error(res, ["Phi"]) < 16 * EPS * math.sqrt(res.counters["steps"])


def test_without_a_limit_an_orbit_in_the_plane_is_refused():
    d = scene()
    d["orbit"]["equatorial_limit"] = "0"
    d["orbit"]["elements"]["inclination"] = "0"
    d["output"]["events"] = ["node"]
    with pytest.raises(ch.SceneError, match="orbit.formulation.*equatorial_limit = 0"):
        ch.Scene.from_dict(d)


def test_a_run_interrupted_on_the_tilted_frame_resumes_bit_for_bit():
    """A snapshot at t = 10 (tilted: between 9.98 and 10.04) names its variant; a new
    propagation restored from it ends with the bits of the uninterrupted run."""
    sc = ch.Scene.from_dict(scene())
    whole = Propagation(sc)
    whole.advance(whole.precision.number("10"))
    whole.advance()
    expected = whole.result()
    first = Propagation(sc, keep=False)
    s1, p1 = first.advance(first.precision.number("10"))
    snap = json.loads(json.dumps(first.snapshot()))
    assert snap["variant"] == tilt.TILTED
    first.release()
    second = Propagation(sc, keep=False)
    second.restore(snap)
    s2, p2 = second.advance()
    got = second.result(np.concatenate([s1, s2]), np.concatenate([p1, p2]))
    for k in ("x", "y", "z", "Phi", "rho"):
        np.testing.assert_array_equal(got[k], expected[k])
    assert got.counters == expected.counters
    np.testing.assert_array_equal(got.events["equatorial"].time, expected.events["equatorial"].time)


def test_sweep_members_that_hand_over_run_as_run_does():
    """In a sweep, a member that reaches the plane leaves its batch lane for run() (the tilted
    variant is other code); one that does not stays in the lanes. Both rows equal run()'s."""
    study = Study.from_dict(
        {
            "scene": scene(),
            "sweep": {"kind": "grid", "parameters": {"orbit.elements.inclination": ["0.5", "1.2"]}},
        }
    )
    result = run_sweep(study, workers=1)
    assert result.metadata["paths"] == {PATH_LANES: 1, PATH_RUN: 1}
    for i, values in enumerate(study.members()):
        alone = ch.run(study.member_scene(i, values))
        assert result.status[i] == OK and result.steps[i] == alone.counters["steps"]
        expected = [alone.variables[k][-1] for k in result.final_names]
        np.testing.assert_allclose(result.final_state[i], expected, rtol=0, atol=1e-13)
        assert result.events["equatorial"][i] == len(alone.events["equatorial"])


@pytest.mark.parametrize("formulation", ["quaternion", "cartesian"])
def test_regular_formulations_pass_the_plane_with_the_same_events(formulation):
    """The regular formulations integrate through without a hand-over; the equatorial event
    records the approach and the recession at the analytic times."""
    res = run(scene(formulation))
    exact = analytic(np.asarray(res.t, dtype=float))
    assert res.success and len(res.t) == 41
    assert "equatorial_handovers" not in res.counters
    ev = res.events["equatorial"]
    assert list(ev.label) == ["approach", "recede"] and list(ev.direction) == [-1, 1]
    when = [float(exact["approach"]), float(exact["recede"])]
    assert np.max(np.abs(np.asarray(ev.time, dtype=float) - when)) < EQUATORIAL_DT
    if formulation == "quaternion":
        # Regular through Φ = 0: Φ = |i − φ′| on the whole grid. Without a perturbation q is
        # constant, and Φ = atan2(√(m₁₃² + m₂₃²), m₃₃) of M₀₁ᵀℛ(q) carries a few roundings of
        # O(1) products (at Φ = 0 too: the absolute error of √(m₁₃² + m₂₃²) is ~ε).
        expected = np.array([float(p) for p in exact["phi"]])
        assert np.max(np.abs(np.asarray(res["Phi"], dtype=float) - expected)) < 8 * EPS


def test_every_passage_is_logged_over_many_passages():
    """Over t = 330 the turning plane passes through the orbit six times (every π/φ̇′, near
    Φ = 0 and Φ = π alike): six approaches and six recessions, alternating, and two hand-overs
    each. (With the hand-over at ε itself, the tilted stretch started on the event's zero and
    the search lost the recession at t ≈ 198.5.)"""
    d = scene()
    d["output"] = {"times": {"start": "0", "stop": "330", "count": 661}, "events": ["equatorial"]}
    res = run(d)
    ev = res.events["equatorial"]
    assert list(ev.label) == ["approach", "recede"] * 6
    assert res.counters["equatorial_handovers"] == 12
