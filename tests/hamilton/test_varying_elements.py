"""Hamilton's varying elements: H = H₁ + H₂ with the flow of H₁, Hamilton's (G′.)."""

from __future__ import annotations

import copy

import heyoka as hy
import mpmath
import numpy as np
import pytest
from helpers import ANHARMONIC_SPLIT

from cayley_heyoka import Scene, SceneError, run
from cayley_heyoka.hamilton.elements import lagrange_brackets

PROJECTILE = {
    "hamiltonian": {"model": "projectile", "g": "0.5", "mu": "1.3", "nu": "0.7"},
    "initial": {"eta": ["-1.1", "0.6", "0.25"], "varpi": ["-0.4", "1.9", "0.8"]},
}


def projectile(formulation: str, precision: str = "double", times=None) -> dict:
    d = {k: dict(v) for k, v in PROJECTILE.items()}
    d["hamiltonian"]["formulation"] = formulation
    d["integrator"] = {"precision": precision}
    d["output"] = {"times": times or ["0", "7.1"], "principal_function": True}
    return d


def rigorous_elements(t: str) -> list[mpmath.mpf]:
    """(171.)–(172.): χ and λ of the projectile in closed form (R3's data), 40 digits."""
    g, mu, nu = (mpmath.mpf(v) for v in ("0.5", "1.3", "0.7"))
    e = [mpmath.mpf(v) for v in PROJECTILE["initial"]["eta"]]
    p = [mpmath.mpf(v) for v in PROJECTILE["initial"]["varpi"]]
    t = mpmath.mpf(t)
    chi, lam = [], []
    for i, w in ((0, mu), (1, mu), (2, nu)):
        c, s = mpmath.cos(w * t), mpmath.sin(w * t)
        lam.append(p[i] * c - w * e[i] * s)
        chi.append(e[i] * (c + w * t * s) + p[i] * (s / w - t * c))
    lam[2] += g * (t - mpmath.sin(nu * t) / nu)
    c, s = mpmath.cos(nu * t), mpmath.sin(nu * t)
    chi[2] += g * (t * s / nu - (1 - c) / nu**2 - t * t / 2)
    return chi + lam


def test_projectile_elements_follow_hamiltons_rigorous_solution():
    """real128 against (171.)–(172.) at every output time (~8 periods of the fast mode)."""
    times = [str(k) for k in range(0, 41, 5)]
    res = run(Scene.from_dict(projectile("elements", "quad", times)))
    names = ("chi1", "chi2", "chi3", "lambda1", "lambda2", "lambda3")
    with mpmath.workdps(40):
        for i, t in enumerate(times):
            exact = rigorous_elements(t)
            scale = max(1, *(abs(v) for v in exact))
            for name, value in zip(names, exact, strict=True):
                err = abs(mpmath.mpf(str(res[name][i])) - value)
                assert err < 1e-30 * scale, (t, name, err)


def test_elements_and_canonical_formulations_agree():
    """The same motion two ways: η, ϖ through the flow, and S, to round-off in double."""
    times = {"start": "0", "stop": "20", "count": 21}
    a = run(Scene.from_dict(projectile("elements", times=times)))
    b = run(Scene.from_dict(projectile("canonical", times=times)))
    for name in ("eta1", "eta2", "eta3", "varpi1", "varpi2", "varpi3", "S"):
        scale = max(1.0, float(np.max(np.abs(b[name]))))
        assert np.max(np.abs(a[name] - b[name])) < 1e-12 * scale, name
    # H = H₁ + H₂ along the elements solution is constant (Hamilton's theorem, Second Essay §14–15).
    assert np.max(np.abs(a.drift("energy"))) < 1e-13


ANHARMONIC = {
    "hamiltonian": copy.deepcopy(ANHARMONIC_SPLIT),
    "initial": {"eta": ["0.8"], "varpi": ["-0.3"]},
    "output": {"times": {"start": "0", "stop": "30", "count": 31}},
}


def test_a_user_split_with_its_flow():
    """An anharmonic oscillator by its harmonic elements, against the canonical equations."""
    a = run(Scene.from_dict(ANHARMONIC))
    d = {**ANHARMONIC, "hamiltonian": {"H": "(varpi1**2 + eta1**2)/2 + 0.05*eta1**4"}}
    b = run(Scene.from_dict(d))
    for name in ("eta1", "varpi1"):
        assert np.max(np.abs(a[name] - b[name])) < 1e-12, name
    assert a.conserved == ("energy",)


@pytest.mark.parametrize(
    ("flow", "text"),
    [
        # sign error: not the motion of H₁
        (
            {"eta1": "chi1*cos(t) - lambda1*sin(t)", "varpi1": "lambda1*cos(t) - chi1*sin(t)"},
            "not the motion of H1",
        ),
        # H₁'s motion, but from (λ, −χ): it does not start at the elements
        (
            {"eta1": "lambda1*cos(t) - chi1*sin(t)", "varpi1": "-lambda1*sin(t) - chi1*cos(t)"},
            "start at the elements",
        ),
    ],
)
def test_a_wrong_flow_is_refused(flow, text):
    d = {**ANHARMONIC, "hamiltonian": {**ANHARMONIC["hamiltonian"], "flow": flow}}
    with pytest.raises(SceneError, match=text) as info:
        run(Scene.from_dict(d))
    assert info.value.field == "hamiltonian.flow"


def test_brackets_of_initial_data_are_canonical_and_free_of_t():
    """Hamilton's theorem (§4.3–4.4) on the free-fall flow (149.); scaling λ breaks it."""
    chi = list(hy.make_vars("c1", "c2", "c3"))
    lam = list(hy.make_vars("l1", "l2", "l3"))
    t, g = hy.time, 0.5
    eta = [chi[0] + lam[0] * t, chi[1] + lam[1] * t, chi[2] + lam[2] * t - 0.5 * g * t * t]
    varpi = [lam[0], lam[1], lam[2] - g * t]
    J = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    L = lagrange_brackets(eta, varpi, chi, lam)
    cf = hy.cfunc([e for row in L for e in row], [*chi, *lam])
    point = np.array([0.3, -1.2, 0.7, 0.5, 2.0, -0.4])
    for time in (0.0, 2.7, 11.3, 40.1):
        assert np.max(np.abs(cf(point, time=time).reshape(6, 6) - J)) < 1e-14
    # Elements (χ, 2λ) are not canonical: [χᵢ, λᵢ] = 1/2.
    half = [e / 2 for e in lam]
    eta2 = [chi[i] + half[i] * t for i in range(3)]
    L2 = lagrange_brackets(eta2, [h for h in half], chi, lam)
    cf2 = hy.cfunc([e for row in L2 for e in row], [*chi, *lam])
    assert abs(cf2(point, time=1.0).reshape(6, 6)[0, 3] - 0.5) < 1e-15


def test_elements_need_the_split_and_start_at_zero():
    d = {**ANHARMONIC, "hamiltonian": {"H": "varpi1**2/2", "formulation": "elements"}}
    with pytest.raises(SceneError, match="split") as info:
        Scene.from_dict(d)
    assert info.value.field == "hamiltonian.formulation"
    d = {**ANHARMONIC, "output": {"times": ["1", "2"]}}
    with pytest.raises(SceneError, match="t = 0") as info:
        run(Scene.from_dict(d))
    assert info.value.field == "output.times"
    d = {
        **ANHARMONIC,
        "hamiltonian": {k: v for k, v in ANHARMONIC["hamiltonian"].items() if k != "flow"},
    }
    with pytest.raises(SceneError, match="required") as info:
        Scene.from_dict(d)
    assert info.value.field == "hamiltonian.flow"
