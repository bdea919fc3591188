"""Cayley's equations as built by the model, against independent statements of them.

* the *literal* form of Cayley's system (docs/orbits.md): Ω composed with the frame tables into a
  function of (r, ρ, Θ, Σ, Φ, t) and differentiated symbolically in those variables — not through
  the Cartesian gradient and the chain rule the model uses;
* the quaternion form and the Cartesian form: the same physical acceleration.
"""

from __future__ import annotations

import copy

import heyoka as hy
import numpy as np
import orbit_cases
import pytest

from cayley_heyoka import Scene
from cayley_heyoka.core import vectors
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.model import ParTable
from cayley_heyoka.mechanics import frames
from cayley_heyoka.orbit.disturbing import Context, disturbing_function
from cayley_heyoka.orbit.model import CAYLEY


def _r3_extended() -> dict:
    """Reference case R3 (validation/orbit_cases.py) with more terms switched on: J3 beside J2
    and an eccentric perturber with a pericentre argument, so every Ω branch is exercised."""
    d = copy.deepcopy(next(c for c in orbit_cases.REFERENCE if c.name == "R3").scene)
    d["perturbations"]["zonal"]["J3"] = "-0.0004"
    d["perturbations"]["third_body"] |= {"eccentricity": "0.2", "argument_of_pericentre": "0.4"}
    d["output"] = {"times": [0, 1]}
    return d


R3 = _r3_extended()


def build(scene_dict: dict, formulation: str):
    d = {**scene_dict, "orbit": {**scene_dict["orbit"], "formulation": formulation}}
    if formulation == "cartesian":
        d["orbit"].pop("sigma0", None)
    scene = Scene.from_dict(d)
    return scene, FAMILIES["orbit"].build(scene)


def rhs_function(model):
    """The right-hand side as a function of (state, t), with the model's parameters."""
    variables = [v for v, _ in model.system]
    cf = hy.cfunc([e for _, e in model.system], variables)
    pars = np.array([float(v) for v in model.pars.values])[: cf.nparams]
    return lambda s, t: cf(s, pars=pars, time=t)


def output_function(model, names):
    cf = hy.cfunc([model.outputs[k] for k in names], [v for v, _ in model.system])
    pars = np.array([float(v) for v in model.pars.values])[: cf.nparams]
    return lambda s, t: cf(s, pars=pars, time=t)


def literal_rhs(scene):
    """§6.3 as printed (corrected), partials by hy.diff of Ω composed in Cayley's variables.

    Returns the right-hand sides and the parameter values they use (their own table).
    """
    orbit = scene.model
    r, rdot, rho, h, Theta, Sigma, Phi = hy.make_vars(*CAYLEY)
    pars = ParTable()
    mu = pars.add("mu", orbit.mu)
    plane = orbit.plane
    th0, th1 = pars.add("th0", plane.theta0), pars.add("th1", plane.theta_rate)
    ph0, ph1 = pars.add("ph0", plane.phi0), pars.add("ph1", plane.phi_rate)
    t = hy.time
    theta, phi = th0 + th1 * t, ph0 + ph1 * t
    sigma = pars.add("sg0", plane.sigma0) + th1 * (hy.sin(phi) - hy.sin(ph0)) / ph1
    M02 = vectors.matmul(
        frames.plane_matrix(theta, sigma, phi), frames.plane_matrix(Theta, Sigma, Phi)
    )
    x = [r * (M02[i][0] * hy.cos(rho) + M02[i][1] * hy.sin(rho)) for i in range(3)]
    Omega = disturbing_function(orbit.perturbations, x, Context(mu, pars))
    d = {v: hy.diff(Omega, v) for v in (r, rho, Theta, Sigma, Phi)}
    dT = th1  # θ̇′
    A = hy.sin(Theta - sigma) * hy.sin(phi) * dT + hy.cos(Theta - sigma) * ph1
    B = hy.cos(Theta - sigma) * hy.sin(phi) * dT - hy.sin(Theta - sigma) * ph1
    csc, cot = 1 / hy.sin(Phi), hy.cos(Phi) / hy.sin(Phi)
    rhs = [
        rdot,
        h * h / r**3 - mu / r**2 + d[r],
        h / r**2,
        d[rho],
        csc / h * d[Phi] - cot * B,
        cot / h * d[Phi] - csc * B,
        -csc / h * d[Theta] - cot / h * d[Sigma] - A,
    ]
    values = np.array([float(v) for v in pars.values])
    return hy.cfunc(rhs, [r, rdot, rho, h, Theta, Sigma, Phi]), values


def test_cayley_equations_match_the_literal_form():
    """The reduced form with chain-rule partials = the printed form with symbolic partials."""
    scene, model = build(R3, "cayley")
    literal, literal_pars = literal_rhs(scene)
    ours = rhs_function(model)
    state0 = np.array([float(v) for v in model.initial_state])
    rng = np.random.default_rng(7)
    for _ in range(8):
        s = state0 + rng.normal(scale=0.1, size=7)
        t = rng.uniform(-20, 80)
        a, b = ours(s, t), literal(s, pars=literal_pars, time=t)
        # The perturbing parts are ~1e-3 of the Kepler part: compare them on their own scale.
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("formulation", ["cayley", "quaternion"])
def test_accelerations_agree_with_cartesian(formulation):
    """Position, velocity and acceleration implied by each formulation equal the Cartesian ones."""
    scene, model = build(R3, formulation)
    _, cart = build(R3, "cartesian")
    f, g = rhs_function(model), rhs_function(cart)
    out = output_function(model, ("x", "y", "z", "vx", "vy", "vz"))
    rng = np.random.default_rng(1)
    state0 = np.array([float(v) for v in model.initial_state])
    for _ in range(5):
        s = state0 + rng.normal(scale=0.05, size=state0.size)
        if formulation == "quaternion":
            s[4:] /= np.linalg.norm(s[4:])
        t = rng.uniform(0, 50)
        xv = out(s, t)
        acc = g(xv, t)[3:]
        ds = f(s, t)
        # d(x, v)/dt along the formulation's flow, by central differences of its output map.
        eps = 1e-5
        dxv = (out(s + eps * ds, t + eps) - out(s - eps * ds, t - eps)) / (2 * eps)
        np.testing.assert_allclose(dxv[:3], xv[3:], atol=1e-9)
        np.testing.assert_allclose(dxv[3:], acc, atol=1e-9)
