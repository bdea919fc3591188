"""The Cartesian reference carrying the departure-point vector d̂ (Θ, Σ, Φ, ρ by geometry)."""

from __future__ import annotations

import time
from typing import Any

import mpmath
from orbit_cases import QUANTITIES, scene

import cayley_heyoka as ch

from .runs import angle_difference, to_mpf
from .tolerances import DPS

_DEPARTURE_CACHE: dict[str, Any] = {}


def departure_run(base: dict, times: list[float], precision: str = "quad") -> dict[str, Any]:
    """Cartesian run carrying the departure-point vector d̂, in ``precision``.

    ẍ = −μx/r³ + ∇Ω and ḋ = −(d̂·ṅ) n̂ = −(d̂·Ḣ)/|H|² H with Ḣ = x × ∇Ω (d̂ ⟂ n̂); d̂(t₀) is the
    first column of M₀₁M₁₂ at t₀. Θ, Σ, Φ then follow geometrically at every output time (§9.2
    step 6), and ρ = u + Σ. Ω is built by the package's own disturbing-function module; the
    system, its initial state and the read-off are this script's.
    """
    import heyoka as hy

    from cayley_heyoka.core import vectors
    from cayley_heyoka.core.model import ParTable
    from cayley_heyoka.mechanics import frames
    from cayley_heyoka.mechanics import kepler as el
    from cayley_heyoka.orbit.disturbing import Context, disturbing_function, gradient
    from cayley_heyoka.orbit.model import initial_cartesian, plane_angles_at

    sc = ch.Scene.from_dict(scene(base, "cartesian", precision, times))
    orbit, prec = sc.model, sc.integrator.precision
    pars = ParTable()
    mu = pars.add("mu", orbit.mu)
    X = list(hy.make_vars("x", "y", "z"))
    V = list(hy.make_vars("vx", "vy", "vz"))
    D = list(hy.make_vars("dx", "dy", "dz"))
    g = gradient(disturbing_function(orbit.perturbations, X, Context(mu, pars)), X)
    r2 = vectors.dot(X, X)
    H = vectors.cross(X, V)
    coef = -vectors.dot(D, vectors.cross(X, g)) / vectors.dot(H, H)
    rhs = [*V, *[-mu * x * r2**-1.5 + gi for x, gi in zip(X, g, strict=True)]]
    rhs += [coef * c for c in H]
    system = list(zip([*X, *V, *D], rhs, strict=True))
    with mpmath.workdps(DPS):
        t0 = mpmath.mpf(times[0])
        x0, v0 = initial_cartesian(orbit, t0)
        frame0 = plane_angles_at(orbit.plane, t0)
        # The gauge Σ(t₀) of the scene (the Cartesian scene itself has none).
        sigma0 = mpmath.mpf(str(base["orbit"].get("sigma0", "0")))
        s = el.cartesian_to_cayley(x0, v0, sigma=sigma0, frame=frame0)
        M02 = vectors.matmul(
            frames.plane_matrix(*frame0), frames.plane_matrix(s.Theta, s.Sigma, s.Phi)
        )
        d0 = [M02[i][0] for i in range(3)]
        state = [mpmath.nstr(c, DPS) for c in [*x0, *v0, *d0]]
    key = f"{precision}:{len(pars.values)}:{[str(e) for _, e in system]}"
    kw = prec.heyoka_kwargs
    if key not in _DEPARTURE_CACHE:
        _DEPARTURE_CACHE[key] = hy.taylor_adaptive(
            system, prec.array(state), pars=prec.array(pars.values), **kw
        )
    import copy

    ta = copy.deepcopy(_DEPARTURE_CACHE[key])
    ta.time = prec.number(times[0])
    ta.state[:] = prec.array(state)
    ta.pars[:] = prec.array(pars.values)
    wall = time.perf_counter()
    res = ta.propagate_grid(prec.array(times))
    if int(res[0]) != int(hy.taylor_outcome.time_limit):
        raise RuntimeError(f"departure reference stopped: {res[0]}")
    out = res[-1]
    rows: dict[str, list] = {k: [] for k in QUANTITIES}
    with mpmath.workdps(DPS):
        for i, t in enumerate(times):
            y = [to_mpf(c) for c in out[i]]
            x, v, d = y[0:3], y[3:6], y[6:9]
            M01 = frames.plane_matrix(*plane_angles_at(orbit.plane, mpmath.mpf(t)))
            M10 = vectors.transpose(M01)
            Xf, Vf, Df = vectors.matvec(M10, x), vectors.matvec(M10, v), vectors.matvec(M10, d)
            Hf = vectors.cross(Xf, Vf)
            h = mpmath.sqrt(vectors.dot(Hf, Hf))
            n = [c / h for c in Hf]
            Phi = mpmath.atan2(mpmath.sqrt(n[0] ** 2 + n[1] ** 2), n[2])
            Theta = mpmath.atan2(n[0], -n[1])
            N = [mpmath.cos(Theta), mpmath.sin(Theta), mpmath.mpf(0)]
            Sigma = mpmath.atan2(vectors.dot(N, vectors.cross(n, Df)), vectors.dot(N, Df))
            u = mpmath.atan2(vectors.dot(Xf, vectors.cross(n, N)), vectors.dot(Xf, N))
            r = mpmath.sqrt(vectors.dot(x, x))
            values = {
                "r": r,
                "rdot": vectors.dot(x, v) / r,
                "rho": u + Sigma,
                "h": h,
                "Theta": Theta,
                "Sigma": Sigma,
                "Phi": Phi,
                **dict(zip(("x", "y", "z", "vx", "vy", "vz"), [*x, *v], strict=True)),
            }
            for k in QUANTITIES:
                rows[k].append(values[k])
        # Θ, Σ, ρ continuous along the grid (the caller's grid must sample them finely enough).
        for k in ("Theta", "Sigma", "rho"):
            col = rows[k]
            for i in range(1, len(col)):
                col[i] = col[i - 1] + angle_difference(col[i], col[i - 1])
    return {"columns": rows, "steps": int(res[3]), "seconds": time.perf_counter() - wall}
