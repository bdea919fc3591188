"""The orbit scene tables: what they accept, and the errors that name the field."""

from __future__ import annotations

import copy
import re

import numpy as np
import pytest

from cayley_heyoka import Scene, SceneError
from cayley_heyoka.core.families import FAMILIES


def scene(**changes) -> dict:
    """Reference case R1 (J2, fixed plane); ``changes`` maps 'table.key' to a value (None: drop)."""
    d = {
        "orbit": {
            "mu": "1",
            "position": ["0.9", "0.2", "0.1"],
            "velocity": ["-0.25", "0.85", "0.45"],
        },
        "perturbations": {"zonal": {"J2": "0.0010826", "radius": "0.8"}},
        "output": {"times": {"start": "0", "stop": "1", "count": 2}},
    }
    d = copy.deepcopy(d)
    for path, value in changes.items():
        *head, last = path.split(".")
        table = d
        for key in head:
            table = table.setdefault(key, {})
        if value is None:
            table.pop(last, None)
        else:
            table[last] = value
    return d


def test_valid_scene_parses_with_defaults():
    s = Scene.from_dict(scene())
    assert s.family == "orbit"
    assert s.model.formulation == "cayley"
    assert s.model.plane is None


@pytest.mark.parametrize(
    ("changes", "field", "text"),
    [
        ({"orbit.mu": "-1"}, "orbit.mu", "> 0"),
        ({"orbit.mu": None}, "orbit.mu", "required"),
        ({"orbit.position": ["nan", "0", "0"]}, "orbit.position[0]", "finite"),
        ({"orbit.velocity": ["0", "inf", "0"]}, "orbit.velocity[1]", "finite"),
        ({"orbit.velocity": ["0.9", "0.2", "0.1"]}, "orbit.velocity", "rectilinear"),
        ({"orbit.position": [0, 0, 0]}, "orbit.position", "origin"),
        ({"orbit.formulation": "kepler"}, "orbit.formulation", "one of"),
        ({"orbit.fomulation": "cayley"}, "orbit.fomulation", "did you mean 'formulation'"),
        ({"orbit.equatorial_limit": "1"}, "orbit.equatorial_limit", r"\[0, 1/4\]"),
        ({"orbit.equatorial_limit": "0.26"}, "orbit.equatorial_limit", r"\[0, 1/4\]"),
        ({"orbit.equatorial_limit": "1e-300"}, "orbit.equatorial_limit", "at least 1e-100"),
        ({"perturbations.zonal.radius": "-0.8"}, "perturbations.zonal.radius", "> 0"),
        ({"perturbations.zonal.J1": "0.1"}, "perturbations.zonal.J1", "degree"),
        ({"perturbations.zonal.axis": [0, 0, 0]}, "perturbations.zonal.axis", "nonzero"),
        (
            {"perturbations.third_body": {"gm": "0.01", "a": "4"}},
            "perturbations.third_body.n",
            "required",
        ),
        (
            {"perturbations.third_body": {"gm": "0.01", "a": "4", "n": "0.1", "eccentricity": "1"}},
            "perturbations.third_body.eccentricity",
            r"\[0, 1\)",
        ),
        (
            {"perturbations.third_body": {"gm": "-0.01", "a": "4", "n": "0.1"}},
            "perturbations.third_body.gm",
            "> 0",
        ),
        (
            {"perturbations.third_body": {"gm": "0.01", "a": "0.9", "n": "1", "degree": 4}},
            "perturbations.third_body.degree",
            "inside the perturber",
        ),
        ({"perturbations.drag": {}}, "perturbations.drag", "unknown key"),
        ({"reference_plane.theta_dot": "0.1"}, "reference_plane.theta_dot", "did you mean"),
    ],
)
def test_bad_input_names_the_field(changes, field, text):
    with pytest.raises(SceneError, match=text) as info:
        Scene.from_dict(scene(**changes))
    assert info.value.field == field


def test_elements_input_checks_the_eccentricity():
    el = {
        "a": "1",
        "e": "1",
        "inclination": "0.3",
        "node": "0",
        "argument_of_pericentre": "0",
        "mean_anomaly": "0",
    }
    d = scene(**{"orbit.position": None, "orbit.velocity": None, "orbit.elements": el})
    with pytest.raises(SceneError, match=r"elliptic element set") as info:
        Scene.from_dict(d)
    assert info.value.field == "orbit.elements.e"
    d["orbit"]["elements"]["e"] = "0.1"
    d["orbit"]["position"] = ["1", "0", "0"]
    with pytest.raises(SceneError, match="not both"):
        Scene.from_dict(d)


def test_cayley_starts_near_the_reference_plane_on_the_tilted_frame():
    """Below the limit the run starts on the tilted working frame (orbit/tilt.py); without a
    limit, an orbit exactly in the plane is refused (0/0 in dΘ/dt)."""
    d = scene(**{"orbit.velocity": ["-0.2", "0.9", "1e-5"], "orbit.position": ["1", "0", "0"]})
    model = FAMILIES["orbit"].build(Scene.from_dict(d))
    assert model.variant == "tilted" and model.pars.values[model.pars.index("orbit.frame_sin")]
    d = scene(**{"orbit.velocity": ["-0.2", "0.9", "0"], "orbit.position": ["1", "0", "0"]})
    d["orbit"]["equatorial_limit"] = "0"
    with pytest.raises(SceneError, match="quaternion") as info:
        Scene.from_dict(d)
    assert info.value.field == "orbit.formulation"
    d["orbit"]["formulation"] = "quaternion"
    Scene.from_dict(d)


def test_sigma0_has_no_meaning_for_cartesian():
    with pytest.raises(SceneError, match="no meaning"):
        Scene.from_dict(scene(**{"orbit.formulation": "cartesian", "orbit.sigma0": "0.1"}))


def test_only_the_terms_named_are_compiled():
    """No perturbation, plane-rate or departure terms appear unless the scene turns them on."""
    build = FAMILIES["orbit"].build
    kepler = build(Scene.from_dict(scene(**{"perturbations": None})))
    # μ and the revolutions of ρ (orbit/revolutions.py) only; Φ is constant: no equatorial stop.
    assert kepler.pars.names == ["mu", "orbit.two_pi", "orbit.rho_offset", "orbit.rho_phase"]
    assert [str(rhs) for _, rhs in kepler.system[3:]] == ["0.0000000000000000"] * 4
    assert [t.counter for t in kepler.terminal] == ["revolutions"]
    j2 = build(Scene.from_dict(scene()))
    assert not any(n.startswith(("third_body", "reference_plane")) for n in j2.pars.names)
    at_rest = build(Scene.from_dict(scene(reference_plane={"theta0": "0.3", "phi0": "0.2"})))
    assert not any("rate" in n for n in at_rest.pars.names)
    assert not any(re.search(r"\bt\b", str(rhs)) for _, rhs in at_rest.system)  # no time
    turning = build(Scene.from_dict(scene(reference_plane={"theta_rate": "0.01", "phi0": "0.4"})))
    assert "reference_plane.theta_rate" in turning.pars.names
    assert "reference_plane.phi_rate" not in turning.pars.names
    assert "reference_plane.sigma_rate" not in turning.pars.names


@pytest.mark.parametrize("formulation", ["cayley", "quaternion"])
def test_rho_is_reduced_in_the_state_and_continuous_in_the_output(formulation):
    """ρ grows ~2π per orbit; the state keeps it in [0, 2π) and the output adds the turns.

    R1 over ~10 orbits: ρ goes from 0.233 to 63.5, so about ten revolutions are moved out of the
    state; the reported ρ must be continuous and increasing on a dense grid (ρ̇ = h/r² ≥ 0.9)
    and equal the integrated ρ̇ = h/r² to round-off.
    """
    from cayley_heyoka import run

    d = scene(**{"orbit.formulation": formulation, "output.times.stop": "50"})
    d["output"]["times"]["count"] = 2001
    res = run(Scene.from_dict(d))
    assert res.counters["revolutions"] == 10
    rho = res["rho"]
    steps = np.diff(rho)
    dt = float(res.t[1] - res.t[0])
    # Increments between grid points: h/r² · dt within [0.5, 2] · dt for this orbit, never a
    # jump of ±2π at a revolution.
    assert np.all(steps > 0.5 * dt) and np.all(steps < 2.0 * dt)
    # Trapezoidal integral of h/r² (second order in dt = 0.025: error ~1e-4·|ρ̈|·t).
    rate = res["h"] / res["r"] ** 2
    integral = rho[0] + np.concatenate([[0], np.cumsum((rate[1:] + rate[:-1]) / 2 * dt)])
    assert np.max(np.abs(integral - rho)) < 1e-3


def test_mean_longitude_is_node_plus_pericentre_plus_mean_anomaly():
    from cayley_heyoka import run

    body = {"gm": "0.01", "a": "4", "n": "0.125", "inclination": "0.2", "node": "0.5"}
    body |= {"eccentricity": "0.1", "argument_of_pericentre": "0.4"}
    by_anomaly = scene(**{"perturbations.third_body": {**body, "mean_anomaly0": "1.1"}})
    by_longitude = scene(**{"perturbations.third_body": {**body, "mean_longitude0": "2.0"}})
    for d in (by_anomaly, by_longitude):
        d["output"]["times"]["stop"] = "20"
    a, b = run(Scene.from_dict(by_anomaly)), run(Scene.from_dict(by_longitude))
    # The same third-body orbit up to the rounding of L₀ − node − ω (a few ulps of the phase).
    for k in ("x", "y", "z"):
        assert abs(a[k][-1] - b[k][-1]) < 1e-13
    both = {**body, "mean_anomaly0": "1.1", "mean_longitude0": "2.0"}
    with pytest.raises(SceneError, match="not both") as info:
        Scene.from_dict(scene(**{"perturbations.third_body": both}))
    assert info.value.field == "perturbations.third_body.mean_longitude0"


@pytest.mark.parametrize("formulation", ["cayley", "quaternion", "cartesian"])
def test_kepler_orbit_closes_after_whole_periods(formulation):
    """No perturbation: only μ and the revolution parameters, some used by outputs alone.

    After 5 periods T = 2π a^{3/2}/√μ the body is back where it started; the phase error of a
    double run grows like ε·n (a few hundred steps): 1e-12 leaves a margin of ~50.
    """
    from cayley_heyoka import run

    x0, v0 = np.array([1.0, 0.0, 0.1]), np.array([0.0, 1.1, 0.2])
    a = 1 / (2 / np.linalg.norm(x0) - v0 @ v0)
    period = 2 * np.pi * a**1.5
    d = {
        "orbit": {"mu": 1, "position": list(x0), "velocity": list(v0)},
        "output": {"times": [0.0, 5 * period]},
    }
    d["orbit"]["formulation"] = formulation
    res = run(Scene.from_dict(d))
    end = np.array([res[k][-1] for k in ("x", "y", "z")])
    assert np.max(np.abs(end - x0)) < 1e-12
    assert max(abs(res.drift("energy"))) < 1e-14


def test_kepler_on_the_reference_plane_runs_in_cayley_form():
    """No Ω and a fixed plane: Θ, Σ, Φ are constant, no cosec Φ is compiled, Φ = 0 is fine."""
    from cayley_heyoka import run

    d = scene(**{"perturbations": None, "orbit.velocity": ["0", "1.1", "0"]})
    d["orbit"]["position"] = ["0.9", "0.2", "0"]
    res = run(Scene.from_dict(d))
    assert np.all(res["Phi"] == 0) and abs(res["z"][-1]) == 0


def test_equatorial_event_needs_a_positive_limit():
    d = scene(**{"orbit.equatorial_limit": "0", "output.events": ["equatorial"]})
    with pytest.raises(SceneError, match="limit > 0") as info:
        run_scene(d)
    assert info.value.field == "output.events"


def test_zonal_degree_is_written_without_leading_zeros():
    with pytest.raises(SceneError, match="unknown key") as info:
        Scene.from_dict(scene(**{"perturbations.zonal.J02": "0.001"}))
    assert info.value.field == "perturbations.zonal.J02"


def run_scene(d: dict):
    from cayley_heyoka import run

    return run(Scene.from_dict(d))
