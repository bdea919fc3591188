"""Hamiltonian scenes: canonical equations from H, the principal function S, bad input.

Reference values: Hamilton's projectile (Second Essay, 1835, §24–27), closed form at 40 digits
printed to 20, as in tests/hamilton/test_projectile.py.
"""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

from cayley_heyoka import Scene, SceneError, run
from cayley_heyoka.core.families import FAMILIES

# (g, mu, nu, t, e, p) and (eta(t), varpi(t), S) of cases R1–R4.
CASES = {
    "R1": (
        ("1", "0.3", "0.45", "2.5", ("0.2", "-0.4", "1.5"), ("0.7", "0.3", "2.1")),
        (
            ("1.7368282138292105663", "0.38896321247380581221", "2.0483420256785479340"),
            ("0.47128388261027457041", "0.30130331186494636590", "-1.7085990387376795151"),
            "-6.0981388215878366413",
        ),
    ),
    "R2": (
        ("9.80665", "0.05", "0.08", "4.75", ("1", "2", "0"), ("10", "-3", "25")),
        (
            ("48.026637435211290111", "-12.172554081213560219", "6.6062480159921221683"),
            ("9.7075282766349387433", "-2.9393149402283906581", "-22.251974377697575248"),
            "-338.11481545921755076",
        ),
    ),
    "R3": (
        ("0.5", "1.3", "0.7", "7.1", ("-1.1", "0.6", "0.25"), ("-0.4", "1.9", "0.8")),
        (
            ("1.0196462901693942404", "-0.30577553354116324342", "-1.8018892697133725910"),
            ("0.66921090739393033682", "-2.0150402566743108742", "1.0637574201679436020"),
            "0.74666227596551578993",
        ),
    ),
    "R4": (
        ("2", "0.01", "0.02", "11", ("0", "0", "0"), ("3", "4", "12")),
        (
            ("32.933490251152442599", "43.911320334869923466", "10.425020501549039001"),
            ("2.9818682938700905511", "3.9758243918267874014", "-10.112192916119666122"),
            "-196.79868510670522129",
        ),
    ),
}
NAMES = ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S")


def projectile(case: str, precision: str = "double", **output) -> dict:
    (g, mu, nu, t, e, p), _ = CASES[case]
    return {
        "hamiltonian": {"model": "projectile", "g": g, "mu": mu, "nu": nu},
        "initial": {"eta": list(e), "varpi": list(p)},
        "integrator": {"precision": precision},
        "output": {"times": ["0", t], "principal_function": True, **output},
    }


def expected(case: str) -> list[str]:
    eta, varpi, S = CASES[case][1]
    return [*eta, *varpi, S]


@pytest.mark.parametrize("case", sorted(CASES))
def test_projectile_matches_the_closed_form_in_double(case):
    """A few steps of a smooth flow: each costs ~ε relative of the state's size; the bound
    16 ε (1 + steps) · max(1, |q|) leaves a factor of ~4 over what was measured."""
    res = run(Scene.from_dict(projectile(case)))
    steps = res.counters["steps"]
    scale = max(abs(float(v)) for v in expected(case))
    for name, value in zip(NAMES, expected(case), strict=True):
        err = abs(res[name][-1] - float(value))
        assert err < 16 * 2.0**-52 * (1 + steps) * scale, (name, err)


@pytest.mark.parametrize("case", sorted(CASES))
def test_projectile_matches_the_closed_form_in_quad(case):
    """The reference values' own 20 digits bound the comparison (real128 carries 34)."""
    res = run(Scene.from_dict(projectile(case, "quad")))
    with mpmath.workdps(40):  # compare at more digits than either side carries
        for name, value in zip(NAMES, expected(case), strict=True):
            got, ref = mpmath.mpf(str(res[name][-1])), mpmath.mpf(value)
            assert abs(got - ref) <= 1e-19 * max(1, abs(ref)), name


def test_user_hamiltonian_reproduces_the_projectile():
    """The same H written as text: the same equations, so the same numbers to round-off."""
    d = projectile("R3")
    text = (
        "(varpi1**2 + varpi2**2 + varpi3**2)/2 + 0.5*eta3"
        " + (1.69*(eta1**2 + eta2**2) + 0.49*eta3**2)/2"
    )
    d["hamiltonian"] = {"H": text}
    a, b = run(Scene.from_dict(d)), run(Scene.from_dict(projectile("R3")))
    for name in NAMES:
        assert abs(a[name][-1] - b[name][-1]) < 1e-13 * max(1, abs(b[name][-1])), name


def test_energy_is_the_hamiltonian_and_conserved():
    """Brouwer: the energy's round-off walks like ε√n; bound 10 ε √n relative, as for the other
    families (R3 over 500 time units, ~1000 steps, the state of order one)."""
    d = projectile("R3", times={"start": "0", "stop": "500", "count": 2001})
    res = run(Scene.from_dict(d))
    assert res.conserved == ("energy",)
    steps = res.counters["steps"]
    assert steps > 500
    assert np.max(np.abs(res.drift("energy"))) < 10 * 2.0**-52 * math.sqrt(steps)
    (g, mu, nu, _, e, p), _ = CASES["R3"]
    e, p = [float(v) for v in e], [float(v) for v in p]
    H0 = 0.5 * sum(v * v for v in p) + float(g) * e[2]
    H0 += 0.5 * (float(mu) ** 2 * (e[0] ** 2 + e[1] ** 2) + float(nu) ** 2 * e[2] ** 2)
    assert abs(res.monitors["energy"][0] - H0) < 1e-14 * abs(H0)


def test_time_dependent_hamiltonian_is_not_listed_as_conserved():
    d = {
        "hamiltonian": {"H": "varpi1**2/2 + eta1**2/2 - 0.1*sin(t)*eta1"},
        "initial": {"eta": ["1"], "varpi": ["0"]},
        "output": {"times": ["0", "3"]},
    }
    res = run(Scene.from_dict(d))
    assert res.conserved == ()
    assert "S" not in res.variables  # principal_function defaults to false
    # Forced oscillator, exact: η = cos t + 0.05 (sin t − t cos t).
    t = 3.0
    assert abs(res["eta1"][-1] - (math.cos(t) + 0.05 * (math.sin(t) - t * math.cos(t)))) < 1e-14


def test_principal_function_is_the_integral_of_t_plus_u():
    """S against the trapezoid rule of Σϖη̇ − H = T + U on a fine output grid (second order in
    dt = 1e-3: error ~ t dt² max|S'''|/12 ≈ 1e-6 here)."""
    d = projectile("R1", times={"start": "0", "stop": "2.5", "count": 2501})
    res = run(Scene.from_dict(d))
    varpi = np.stack([res[f"varpi{i}"] for i in (1, 2, 3)])
    T = 0.5 * np.sum(varpi**2, axis=0)
    integrand = 2 * T - res.monitors["energy"]
    dt = float(res.t[1] - res.t[0])
    S = np.concatenate([[0], np.cumsum((integrand[1:] + integrand[:-1]) / 2 * dt)])
    assert np.max(np.abs(S - res["S"])) < 1e-6


def test_only_what_is_asked_is_integrated():
    build = FAMILIES["hamiltonian"].build
    without = build(Scene.from_dict({**projectile("R1"), "output": {"times": ["0", "1"]}}))
    assert without.state_names == ["eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3"]
    assert build(Scene.from_dict(projectile("R1"))).state_names[-1] == "S"


@pytest.mark.parametrize(
    ("change", "field", "text"),
    [
        (
            {"hamiltonian": {"model": "projectile", "H": "varpi1**2", "g": 1}},
            "hamiltonian",
            "one of",
        ),
        ({"hamiltonian": {"model": "kepler"}}, "hamiltonian.model", "one of"),
        (
            {"hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3"}},
            "hamiltonian.nu",
            "required",
        ),
        ({"hamiltonian": {"H": "varpi1**2", "g": "1"}}, "hamiltonian.g", "projectile"),
        ({"initial": {"eta": ["1", "2", "3"], "varpi": ["1", "2"]}}, "initial.varpi", "3 numbers"),
        (
            {"initial": {"eta": ["1", "nan", "3"], "varpi": ["1", "2", "3"]}},
            "initial.eta[1]",
            "finite",
        ),
        ({"initial": {"eta": ["1", "2", "3"]}}, "initial.varpi", "required"),
        (
            {"hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3", "nu": "x"}},
            "hamiltonian.nu",
            "number",
        ),
    ],
)
def test_bad_input_names_the_field(change, field, text):
    d = {**projectile("R1"), **change}
    with pytest.raises(SceneError, match=text) as info:
        Scene.from_dict(d)
    assert info.value.field == field


def test_bad_expression_and_options_are_refused_when_built():
    d = {**projectile("R1"), "hamiltonian": {"H": "varpi1**2 + lambda_"}}
    with pytest.raises(SceneError) as info:
        run(Scene.from_dict(d))
    assert info.value.field == "hamiltonian.H"
    d = projectile("R1")
    d["output"]["principal_function"] = "yes"
    with pytest.raises(SceneError, match="true or false") as info:
        run(Scene.from_dict(d))
    assert info.value.field == "output.principal_function"


def test_principal_function_belongs_to_the_hamiltonian_family():
    scene = {
        "body": {"inertia": ["1", "1.5", "2.5"]},
        "initial": {"rates": ["0.1", "0.2", "1"]},
        "output": {"times": ["0", "1"], "principal_function": True},
    }
    with pytest.raises(SceneError, match="unknown key") as info:
        Scene.from_dict(scene)
    assert info.value.field == "output.principal_function"


def test_whole_trajectory_against_the_closed_form_in_quad():
    """Every output time of a real128 run of R3 (~8 oscillations of the fast mode) against
    ``projectile_solution`` at 40 digits: phase errors grow like ε n; 1e-30 relative to the
    state's scale leaves ~50 over ε·(steps) here."""
    from cayley_heyoka.hamilton import projectile_solution

    (g, mu, nu, _, e, p), _ = CASES["R3"]
    times = [str(k) for k in range(0, 41, 4)]
    d = projectile("R3", "quad", times=times)
    res = run(Scene.from_dict(d))
    for i, t in enumerate(times[1:], start=1):
        ref = projectile_solution(g, mu, nu, e, p, t, dps=40)
        with mpmath.workdps(40):  # compare at more digits than either side carries
            values = [*ref.eta, *ref.varpi, ref.S]
            scale = max(1, *(abs(v) for v in values))
            for name, value in zip(NAMES, values, strict=True):
                err = abs(mpmath.mpf(str(res[name][i])) - value)
                assert err < 1e-30 * scale, (t, name, err)
