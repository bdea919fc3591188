"""Orbit scenes end to end: reference values, the three formulations, monitors, events, files.

Every scene here is compiled with ``integrator.compact_mode = true``. The equations, the Taylor
order and the tolerance are those of the default code generation; only the layout of the
compiled code differs (loops over arrays instead of unrolled code), and it compiles about five
times faster: the twelve reference structures take ~10 s instead of ~55 s on a cold heyoka
cache. The default code generation of orbit scenes is run by ``tests/test_cli.py`` (the bundled
``orbit_moving_plane.toml``) and by :func:`test_reference_values_default_codegen` here.

Error scales used throughout (ε = 2⁻⁵² in double, S = the run's own step count, N = orbits):

* *slow* quantities (h, Θ, Σ, Φ and the monitors): each step commits a local error ≲ ε
  (heyoka's tolerance) plus the round-off of the update; S such errors add like a random walk,
  ~ε√S. We allow 4ε√S for the variables and 10ε√S for monitors, which also carry the round-off
  of their own evaluation (a few terms of the size of the result).
* *phase* quantities (x, v, r, ṙ, ρ): an error δ in the semi-major axis changes the mean motion
  by (3/2)δ n, so over N orbits the Kepler shear turns the random walk ε√S of the energy into an
  along-track error 3πN·ε√S. We allow four times that, relative to |x| for positions and r, to
  |v| for velocities and ṙ, and in radians for ρ.
"""

from __future__ import annotations

import copy
import math

import mpmath
import numpy as np
import orbit_cases
import pytest

from cayley_heyoka import Scene, load_result, run
from cayley_heyoka.core.families import FAMILIES

EPS = 2.0**-52
FORMULATIONS = ("cayley", "quaternion", "cartesian")
POSITION, VELOCITY = ("x", "y", "z"), ("vx", "vy", "vz")
SLOW = ("h", "Theta", "Sigma", "Phi")

# --------------------------------------------------------------------- the reference cases
# The orbit test cases R1–R4, shared with the validation report
# (validation/orbit_cases.py): inputs, and the state at time t to 20 significant digits. The
# cases' third body x₃ = a₃R₃(Ω₃)R₁(i₃)(cos λ₃, sin λ₃, 0), λ₃ = n₃t + λ₃,₀, is a circular orbit
# with node = Ω₃, inclination = i₃, argument_of_pericentre = 0 and mean_anomaly0 = λ₃,₀.
CASES = {c.name: c.scene for c in orbit_cases.REFERENCE}
REFERENCE = {c.name: (c.t, c.values) for c in orbit_cases.REFERENCE}


def orbit_scene(
    case: str,
    formulation: str,
    times,
    events=(),
    precision: str = "double",
    compact: bool = True,
) -> dict:
    """Reference case ``case`` as a scene dictionary in the given formulation."""
    d = copy.deepcopy(CASES[case])
    d["orbit"]["formulation"] = formulation
    if formulation in ("cartesian", "encke"):
        del d["orbit"]["sigma0"]
    d["integrator"] = {"precision": precision, "compact_mode": compact}
    d["output"] = {"times": times, "events": list(events)}
    return d


def orbits(case: str, t: float) -> float:
    """Number of revolutions in time t, from the initial osculating semi-major axis (vis-viva)."""
    orbit = CASES[case]["orbit"]
    x = np.array([float(c) for c in orbit["position"]])
    v = np.array([float(c) for c in orbit["velocity"]])
    mu = float(orbit["mu"])
    a = 1 / (2 / np.linalg.norm(x) - v @ v / mu)
    return t / (2 * math.pi * math.sqrt(a**3 / mu))


def phase_scale(case: str, t: float, steps: int) -> float:
    """4·3πN·ε√S: the allowance for along-track quantities (module docstring)."""
    return 4 * 3 * math.pi * orbits(case, t) * EPS * math.sqrt(steps)


def error_scales(values: dict) -> dict:
    """What each quantity's error is measured against: |x|, |v|, h, or 1 (angles, radians)."""
    norm_x = math.sqrt(sum(float(values[k]) ** 2 for k in POSITION))
    norm_v = math.sqrt(sum(float(values[k]) ** 2 for k in VELOCITY))
    scale = dict.fromkeys((*POSITION, "r"), norm_x) | dict.fromkeys((*VELOCITY, "rdot"), norm_v)
    return scale | {"h": float(values["h"]), "Theta": 1, "Sigma": 1, "Phi": 1, "rho": 1}


def check_reference(res, case: str, formulation: str) -> dict:
    """Scaled errors at t against the 20-digit values and their bounds (double runs)."""
    t, values = REFERENCE[case]
    assert float(res.t[-1]) == float(t)
    steps = res.counters["steps"]
    scale = error_scales(values)
    names = [k for k in values if formulation != "cartesian" or k in (*POSITION, *VELOCITY)]
    report = {}
    for name in names:
        err = abs(float(res[name][-1]) - float(values[name])) / scale[name]
        if name in SLOW:
            bound = 4 * EPS * math.sqrt(steps)
        else:
            bound = phase_scale(case, float(t), steps)
        report[name] = (err, bound)
    return report


@pytest.mark.parametrize("formulation", ["cayley", "quaternion", "encke"])
def test_output_times_do_not_perturb_the_revolutions_or_rectifications(formulation):
    """ρ's revolutions and Encke's rectifications are handled inside heyoka's one call over
    the grid: with outputs sparser and denser than the events, the same steps, the same
    counts and the same last state, bit for bit; the outputs between events are continuous
    (ρ, reported with the revolutions added back, never steps back by 2π)."""
    sparse = run(Scene.from_dict(orbit_scene("R1", formulation, ["0", "60"])))
    times = {"start": "0", "stop": "60", "count": 997}
    dense = run(Scene.from_dict(orbit_scene("R1", formulation, times)))
    counter = "rectifications" if formulation == "encke" else "revolutions"
    assert dense.counters[counter] >= 10
    assert dense.counters == sparse.counters
    for name in dense.variables:
        assert dense[name][-1] == sparse[name][-1], name
    if formulation != "encke":
        assert np.all(np.diff(dense["rho"]) > 0)


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("case", sorted(CASES))
def test_reference_values_double(case, formulation):
    t = REFERENCE[case][0]
    res = run(Scene.from_dict(orbit_scene(case, formulation, ["0", t])))
    report = check_reference(res, case, formulation)
    bad = {k: (f"{e:.2e}", f"{b:.2e}") for k, (e, b) in report.items() if not e < b}
    assert not bad, bad
    # the bounds are not vacuous: they sit far below a visible error (≲ 1e-11)
    assert max(b for _, b in report.values()) < 1e-11


@pytest.mark.parametrize("formulation", ["cayley", "cartesian"])
def test_reference_values_default_codegen(formulation):
    """R1 compiled the default way (unrolled code), as a scene without compact_mode gets it."""
    d = orbit_scene("R1", formulation, ["0", "50"])
    del d["integrator"]["compact_mode"]
    res = run(Scene.from_dict(d))
    report = check_reference(res, "R1", formulation)
    bad = {k: (f"{e:.2e}", f"{b:.2e}") for k, (e, b) in report.items() if not e < b}
    assert not bad, bad


@pytest.fixture(scope="module")
def quad_r1() -> dict:
    """R1 to t = 50 in real128 (cayley and cartesian), with node and apsis events."""
    times = {"start": "0", "stop": "50", "count": 6}
    return {
        f: run(Scene.from_dict(orbit_scene("R1", f, times, ("node", "apsis"), "quad")))
        for f in ("cayley", "cartesian")
    }


@pytest.mark.parametrize("formulation", ["cayley", "cartesian"])
def test_reference_values_quad(quad_r1, formulation):
    """In real128 the run is good to ~1e-28; the 20 printed digits limit the check to
    their own resolution, ≤ 5e-20 relative for every value of R1."""
    res = quad_r1[formulation]
    assert str(res.t[-1]) == str(res.precision.number("50"))
    _, values = REFERENCE["R1"]
    with mpmath.workdps(40):
        for name, text in values.items():
            if name not in res.variables:
                continue
            got = mpmath.mpf(str(res[name][-1]))
            rel = abs(got - mpmath.mpf(text)) / abs(mpmath.mpf(text))
            assert rel < 1e-19, (name, float(rel))


# --------------------------------------------------------------------- formulations agree
def test_formulations_agree_on_a_grid():
    """R3 (tilted J2, third body, moving plane) over ~3 orbits: x, y, z of the three
    formulations agree at every output time within the sum of their phase allowances; ρ is the
    same continuous, increasing angle in the two Cayley forms."""
    times = {"start": "0", "stop": "20", "count": 41}
    res = {f: run(Scene.from_dict(orbit_scene("R3", f, times))) for f in FORMULATIONS}
    steps = max(r.counters["steps"] for r in res.values())
    bound = 2 * phase_scale("R3", 20.0, steps)
    x = {f: np.array([r[k] for k in POSITION]) for f, r in res.items()}
    radius = np.linalg.norm(x["cartesian"], axis=0)
    for f in ("cayley", "quaternion"):
        diff = np.max(np.linalg.norm(x[f] - x["cartesian"], axis=0) / radius)
        assert diff < bound, (f, diff, bound)
    assert np.max(np.abs(res["cayley"]["rho"] - res["quaternion"]["rho"])) < bound
    rho = res["cayley"]["rho"]
    # ρ̇ = h/r² ≈ 1: each 0.5 step of output adds a fraction of a turn, never a jump of 2π
    assert np.all(np.diff(rho) > 0) and np.all(np.diff(rho) < math.pi)
    assert rho[-1] - rho[0] > 4 * math.pi  # ~3 turns: the wrap of ρ is exercised
    # the orbit really is perturbed: the plane angles move by far more than the allowance
    assert abs(res["cayley"]["Phi"][-1] - res["cayley"]["Phi"][0]) > 1e-3


# --------------------------------------------------------------------- monitors
def build_conserved(d: dict) -> set:
    return set(FAMILIES["orbit"].build(Scene.from_dict(d)).conserved)


def with_perturbations(perturbations: dict, plane: dict | None = None) -> dict:
    d = orbit_scene("R1", "cayley", ["0", "1"])
    d["perturbations"] = copy.deepcopy(perturbations)
    if plane is not None:
        d["reference_plane"] = plane
    return d


ZONAL = CASES["R1"]["perturbations"]["zonal"]
CIRCULAR = CASES["R2"]["perturbations"]["third_body"]
ECCENTRIC = {**CIRCULAR, "eccentricity": "0.2"}


@pytest.mark.parametrize(
    ("perturbations", "plane", "expected"),
    [
        ({}, None, {"energy", "angular_momentum"}),
        ({"zonal": ZONAL}, None, {"energy", "polar_momentum"}),
        ({"zonal": ZONAL}, CASES["R4"]["reference_plane"], {"energy", "polar_momentum"}),
        ({"third_body": CIRCULAR}, None, {"jacobi"}),
        ({"third_body": ECCENTRIC}, None, set()),
        ({"third_body": {**CIRCULAR, "n": "0"}}, None, {"energy", "jacobi"}),  # at rest
        ({"zonal": ZONAL, "third_body": CIRCULAR}, None, set()),
        ({"potential": {"Omega": "0.001 * x * y / r**5"}}, None, {"energy"}),
        ({"potential": {"Omega": "0.001 * cos(t) * z / r**3"}}, None, set()),
        ({"zonal": ZONAL, "potential": {"Omega": "0.001 * x / r**3"}}, None, {"energy"}),
    ],
)
def test_conserved_lists_what_the_physics_conserves(perturbations, plane, expected):
    """Energy needs a time-independent Ω (the reference plane only changes the coordinates);
    k̂·(x × v) needs Ω axisymmetric about k̂ (the zonal field alone); the Jacobi constant needs
    the circular perturber alone; x × v needs no perturbation at all."""
    for formulation in FORMULATIONS:
        d = with_perturbations(perturbations, plane)
        d["orbit"]["formulation"] = formulation
        if formulation == "cartesian":
            del d["orbit"]["sigma0"]
        assert build_conserved(d) == expected, formulation


@pytest.mark.parametrize("formulation", FORMULATIONS)
@pytest.mark.parametrize("case", ["R1", "R2", "R4"])
def test_monitors_are_conserved(case, formulation):
    """~40 orbits (R1, R2) or ~16 (R4): each conserved monitor drifts less than 10ε√S; the
    monitors the physics does not conserve really change."""
    d = orbit_scene(case, formulation, {"start": "0", "stop": "200", "count": 101})
    res = run(Scene.from_dict(d))
    zonal_only = {"energy", "polar_momentum"}  # R1, and R4 whose plane motion is kinematic
    assert set(res.conserved) == ({"jacobi"} if case == "R2" else zonal_only)
    bound = 10 * EPS * math.sqrt(res.counters["steps"])
    for name in res.conserved:
        drift = float(np.max(np.abs(res.drift(name))))
        assert drift < bound, (name, drift, bound)
    # x × v turns under any of these perturbations (J2 precession, the third body's torque)
    assert float(np.max(np.abs(res.drift("angular_momentum")))) > 1e-4
    if case == "R2":
        # the perturber's time dependence exchanges energy: E moves, only E − n k̂₃·L stays
        assert float(np.max(np.abs(res.drift("energy")))) > 1e-6


# --------------------------------------------------------------------- events
def plane_normal(case: str, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """k̂ of the reference plane, (sin θ′ sin φ′, −cos θ′ sin φ′, cos φ′), and its time rate."""
    p = {k: float(v) for k, v in CASES[case]["reference_plane"].items()}
    th, dth = p["theta0"] + p["theta_rate"] * t, p["theta_rate"]
    ph, dph = p["phi0"] + p["phi_rate"] * t, p["phi_rate"]
    k = np.array([np.sin(th) * np.sin(ph), -np.cos(th) * np.sin(ph), np.cos(ph)])
    dk = np.array(
        [
            np.cos(th) * np.sin(ph) * dth + np.sin(th) * np.cos(ph) * dph,
            np.sin(th) * np.sin(ph) * dth - np.cos(th) * np.cos(ph) * dph,
            -np.sin(ph) * dph,
        ]
    )
    return k, dk


@pytest.fixture(scope="module")
def r4_events() -> dict:
    """R4 (eccentric retrograde orbit, J2, plane turning about z₀) over ~3 orbits."""
    times = {"start": "0", "stop": "40", "count": 5}
    return {
        f: run(Scene.from_dict(orbit_scene("R4", f, times, ("node", "apsis"))))
        for f in FORMULATIONS
    }


def cartesian_at(case: str, times: np.ndarray):
    """A Cartesian run of ``case`` that outputs at exactly ``times``."""
    d = orbit_scene(case, "cartesian", [0.0, *[float(t) for t in times]])
    res = run(Scene.from_dict(d))
    x = np.array([res[k][1:] for k in POSITION])
    v = np.array([res[k][1:] for k in VELOCITY])
    return res, x, v


def test_node_events_cross_the_moving_reference_plane(r4_events):
    """Ascending and descending nodes alternate; at each the position relative to the moving
    reference plane is zero (checked in an independent Cartesian run at the event times), and
    the crossing goes the labelled way."""
    nodes = r4_events["cayley"].events["node"]
    assert len(nodes) >= 6
    assert np.all(nodes.label[1:] != nodes.label[:-1])
    assert set(nodes.label) == {"ascending", "descending"}
    assert np.array_equal(nodes.direction, np.where(nodes.label == "ascending", 1, -1))
    res, x, v = cartesian_at("R4", nodes.time)
    k, dk = plane_normal("R4", np.asarray(nodes.time, dtype=float))
    # the event time carries the Cayley run's along-track error, the Cartesian run its own
    bound = 2 * phase_scale("R4", 40.0, res.counters["steps"])
    height = np.abs(np.sum(k * x, axis=0)) / np.linalg.norm(x, axis=0)
    assert np.max(height) < bound, (np.max(height), bound)
    rate = np.sum(k * v + dk * x, axis=0)  # d(k̂·x)/dt
    assert np.array_equal(np.sign(rate), nodes.direction)
    # two runs, each with a height error ≲ bound·|x|: their zeros differ by ≲ that over the rate
    dt_bound = 2 * bound * np.linalg.norm(x, axis=0) / np.abs(rate)
    for f in ("quaternion", "cartesian"):
        other = r4_events[f].events["node"]
        assert list(other.label) == list(nodes.label), f
        diff = np.abs(np.asarray(other.time - nodes.time, dtype=float))
        assert np.all(diff < dt_bound), (f, diff, dt_bound)


def test_apsis_events_are_where_rdot_vanishes(r4_events):
    """Pericentres and apocentres alternate, ṙ = 0 there, r is below a at pericentre and above
    it at apocentre, and the Cayley and Cartesian formulations find the same times."""
    apses = r4_events["cayley"].events["apsis"]
    assert len(apses) >= 6
    assert np.all(apses.label[1:] != apses.label[:-1])
    assert np.array_equal(apses.direction, np.where(apses.label == "pericentre", 1, -1))
    res, x, v = cartesian_at("R4", apses.time)
    r = np.linalg.norm(x, axis=0)
    speed = np.linalg.norm(v, axis=0)
    bound = 2 * phase_scale("R4", 40.0, res.counters["steps"])
    rdot = np.sum(x * v, axis=0) / r
    assert np.max(np.abs(rdot) / speed) < bound, (np.max(np.abs(rdot) / speed), bound)
    a = 1.57569  # osculating a of R4; e = 0.57, so r is 0.68 or 2.47 at the apses
    assert np.all(r[apses.label == "pericentre"] < 0.8 * a)
    assert np.all(r[apses.label == "apocentre"] > 1.2 * a)
    # ṙ of each run is off by ≲ bound·|v|; its zero moves by that over |r̈| = |h²/r³ − μ/r²|
    # (≈ eμ/r²: 1.2 at pericentre, 0.09 at apocentre), so the times agree to ≲ 5e-12.
    h2 = np.sum(np.cross(x.T, v.T) ** 2, axis=1)
    rddot = np.abs(h2 / r**3 - 1 / r**2)
    dt_bound = 2 * bound * speed / rddot
    assert np.max(dt_bound) < 1e-11
    for f in ("quaternion", "cartesian"):
        other = r4_events[f].events["apsis"]
        assert list(other.label) == list(apses.label), f
        diff = np.abs(np.asarray(other.time - apses.time, dtype=float))
        assert np.all(diff < dt_bound), (f, diff, dt_bound)


# --------------------------------------------------------------------- result files
def assert_same_result(back, res):
    assert back.precision == res.precision
    assert back.scene == res.scene and back.counters == res.counters
    assert back.conserved == res.conserved and back.status == res.status
    for group in ("variables", "monitors"):
        mine, theirs = getattr(res, group), getattr(back, group)
        assert list(mine) == list(theirs), group
        for name in mine:
            a, b = np.ravel(mine[name]), np.ravel(theirs[name])
            assert len(a) == len(b) and all(x == y for x, y in zip(a, b, strict=True)), name
    assert list(back.events) == list(res.events)
    for name, log in res.events.items():
        other = back.events[name]
        assert len(log) > 0
        assert all(x == y for x, y in zip(log.time, other.time, strict=True)), name
        assert list(log.label) == list(other.label) and np.array_equal(
            log.direction, other.direction
        )


def test_result_file_round_trips_double(tmp_path, r4_events):
    res = r4_events["cayley"]
    path = tmp_path / "orbit.h5"
    res.save(path)
    back = load_result(str(path))
    assert_same_result(back, res)
    assert set(back.monitors) >= {"energy", "angular_momentum", "polar_momentum"}
    assert Scene.from_dict(back.scene).model.formulation == "cayley"


@pytest.mark.parametrize("formulation", ["cayley", "cartesian"])
def test_result_file_round_trips_quad(tmp_path, quad_r1, formulation):
    res = quad_r1[formulation]
    path = tmp_path / "orbit_quad.h5"
    res.save(path)
    back = load_result(str(path))
    assert_same_result(back, res)
    assert Scene.from_dict(back.scene).integrator.precision == res.precision
