"""The orbit cases run: orbit_j2 (a J2 orbit) and planets (examples/planets.toml)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import hamilton_planets
import mpmath
from bench_common import available

import cayley_heyoka as ch
from cayley_heyoka.hamilton.predominant_mass import system as hp

from .cases import (
    IAS15_EPSILON,
    J2_ORBIT,
    QUICK_IAS15_EPSILON,
    QUICK_RTOL,
    REFERENCE_TOL,
    RTOL,
    j2_data,
    j2_initial_state,
    planets_barycentric,
    planets_data,
    quad_tolerances,
    tolerances,
    with_integrator,
)
from .errors import exact_mpf, final_values
from .our_side import high_accuracy, ours, reference_check, reference_run
from .peers import ias15_sweep, scipy_sweep
from .records import Case


def orbit_j2(quick: bool) -> Case:
    a, e, i, node, w, M = J2_ORBIT["elements"]
    mu = J2_ORBIT["mu"]
    x0, v0 = j2_initial_state()
    orbits = 1 if quick else J2_ORBIT["orbits"]
    t_end = float(2 * math.pi * orbits * math.sqrt(a**3 / mu))
    case = Case(
        "orbit_j2",
        f"J2 = {J2_ORBIT['J2']:g} about z, radius {J2_ORBIT['radius']:g}, μ = {mu:g}; a = {a:g}, "
        f"e = {e:g}, i = {i:g}, Ω = {node:g}, ω = {w:g}, M = {M:g} (rounded to a binary64 "
        f"Cartesian state); t = {t_end:.6g} ({orbits} orbits)",
        "|Δx|/a at the final time (position)",
        f"our Cartesian formulation in real128 at tolerance {REFERENCE_TOL}",
    )

    def data(formulation: str) -> dict:
        return j2_data(x0, v0, formulation)

    ref_result = reference_run(data("cartesian"), t_end)
    ref = final_values(ref_result, ("x", "y", "z"))

    def pos_error(x: Sequence[Any]) -> float:
        with mpmath.workdps(60):
            d = [exact_mpf(u) - exact_mpf(r) for u, r in zip(x, ref, strict=True)]
            return float(mpmath.sqrt(sum(c * c for c in d)) / a)

    def error(result: ch.Result) -> float:
        return pos_error(final_values(result, ("x", "y", "z")))

    for k, formulation in enumerate(("cartesian", "cayley", "quaternion")):
        d = data(formulation)
        ours(case, formulation, d, "double", tolerances(quick, "double"), t_end, error)
        ours(case, formulation, d, "quad", quad_tolerances(quick, k, reference=True), t_end, error)
        if k == 1 and not quick:
            reference_check(case, formulation, d, t_end, error, " of a")
    if not quick:
        high_accuracy(case, data("cartesian"), "cartesian", t_end, error)
    scipy_sweep(
        case,
        data("cartesian"),
        t_end,
        (3, 3),
        lambda y: pos_error(y[:3]),
        QUICK_RTOL if quick else RTOL,
    )

    def build() -> tuple[Any, Any]:
        import rebound
        import reboundx

        sim = rebound.Simulation()
        sim.G = 1.0
        # A massless orbiter keeps the central body at the origin, as in our fixed-centre
        # problem, and μ = G·m₀.
        sim.add(m=mu)
        sim.add(m=0.0, x=x0[0], y=x0[1], z=x0[2], vx=v0[0], vy=v0[1], vz=v0[2])
        sim.integrator = "ias15"
        rebx = reboundx.Extras(sim)
        gh = rebx.load_force("gravitational_harmonics")
        rebx.add_force(gh)
        sim.particles[0].params["J2"] = J2_ORBIT["J2"]
        sim.particles[0].params["R_eq"] = J2_ORBIT["radius"]
        return sim, (rebx, gh)

    def reb_error(sim: Any) -> float:
        p, c = sim.particles[1], sim.particles[0]
        return pos_error([p.x - c.x, p.y - c.y, p.z - c.z])

    if available("rebound") and available("reboundx"):
        case.notes.append(_j2_convention(build, data("cartesian"), t_end))
    ias15_sweep(
        case,
        build,
        t_end,
        reb_error,
        QUICK_IAS15_EPSILON if quick else IAS15_EPSILON,
        ("rebound", "reboundx"),
    )
    return case


def _j2_convention(build: Callable, data: dict, t_end: float) -> str:
    """REBOUNDx's J2 against ours: the same orbit over up to 10 orbits, IAS15 at its default ε
    against our real128 Cartesian run, and, for scale, IAS15 with J2 switched off (what a
    mismatch of sign or factor in J2 or R would leave)."""
    span = min(t_end, 10 * 2 * math.pi)
    ref = ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, span]))
    diffs = []
    for j2 in (True, False):
        sim, keep = build()
        if not j2:
            sim.particles[0].params["J2"] = 0.0
        sim.integrate(span, exact_finish_time=1)
        p, c = sim.particles[1], sim.particles[0]
        with mpmath.workdps(40):
            d = [
                exact_mpf(u) - exact_mpf(ref[k][-1])
                for u, k in zip((p.x - c.x, p.y - c.y, p.z - c.z), "xyz", strict=True)
            ]
            diffs.append(float(mpmath.sqrt(sum(x * x for x in d))))
        del keep
    return (
        "REBOUNDx's `gravitational_harmonics` (J2 and R_eq on the central particle, axis z) is "
        "our `[perturbations.zonal]` J2: after t = "
        f"{span:.4g}, IAS15 at its default ε is {diffs[0]:.1e} from our real128 Cartesian run "
        f"(without J2 it would be {diffs[1]:.1e} away)."
    )


def planets(quick: bool) -> Case:
    orbits = 1 if quick else 100
    t_end = float(2 * math.pi * orbits)
    masses = [float(m) for m, _ in hamilton_planets.BODIES]
    axes = [float(e["a"]) for _, e in hamilton_planets.BODIES]
    n = len(masses)
    case = Case(
        "planets",
        f"examples/planets.toml ('N5': M = 1, G = 1, masses {masses}, a = {axes}), "
        f"t = {t_end:.6g} ({orbits} inner orbits)",
        "max over bodies of |Δξᵢ|/aᵢ (heliocentric positions) at the final time",
        f"our canonical formulation in real128 at tolerance {REFERENCE_TOL}",
    )
    names = [f"{c}{k + 1}" for k in range(n) for c in "xyz"]

    def data(formulation: str) -> dict:
        return planets_data(orbits, formulation)

    ref_result = reference_run(data("canonical"), t_end)
    ref = final_values(ref_result, names)

    def pos_error(xi: Sequence[Any]) -> float:
        with mpmath.workdps(60):
            worst = mpmath.mpf(0)
            for k in range(n):
                d = [exact_mpf(xi[3 * k + j]) - exact_mpf(ref[3 * k + j]) for j in range(3)]
                worst = max(worst, mpmath.sqrt(sum(c * c for c in d)) / axes[k])
            return float(worst)

    def error(result: ch.Result) -> float:
        return pos_error(final_values(result, names))

    for formulation in ("canonical", "elements"):
        ours(
            case,
            formulation,
            data(formulation),
            "double",
            tolerances(quick, "double"),
            t_end,
            error,
        )
    ours(
        case,
        "canonical",
        data("canonical"),
        "quad",
        quad_tolerances(quick, 0, reference=True),
        t_end,
        error,
    )
    if not quick:
        high_accuracy(case, data("canonical"), "canonical", t_end, error)
        # Hamilton's elements step ~20× slower than the canonical equations: in real128 only
        # the untimed check of the reference.
        reference_check(case, "elements", data("elements"), t_end, error, " of a")
    scipy_sweep(
        case,
        data("canonical"),
        t_end,
        (3,) * (2 * n),
        lambda y: pos_error(y[: 3 * n]),
        QUICK_RTOL if quick else RTOL,
    )

    # REBOUND gets barycentric particles from the exact canonical state, rounded once.
    X, V = planets_barycentric(orbits)

    def build() -> tuple[Any, Any]:
        import rebound

        sim = rebound.Simulation()
        sim.G = 1.0
        for m, x, v in zip([1.0, *masses], X, V, strict=True):
            sim.add(m=m, x=x[0], y=x[1], z=x[2], vx=v[0], vy=v[1], vz=v[2])
        sim.integrator = "ias15"
        return sim, None

    def reb_error(sim: Any) -> float:
        ps = sim.particles
        with mpmath.workdps(50):
            pos = [[mpmath.mpf(p.x), mpmath.mpf(p.y), mpmath.mpf(p.z)] for p in ps]
            vel = [[mpmath.mpf(p.vx), mpmath.mpf(p.vy), mpmath.mpf(p.vz)] for p in ps]
            xs, _ = hp.heliocentric(pos, vel, [mpmath.mpf(1.0), *map(mpmath.mpf, masses)])
            return pos_error([c for x in xs for c in x])

    ias15_sweep(case, build, t_end, reb_error, QUICK_IAS15_EPSILON if quick else IAS15_EPSILON)
    return case
