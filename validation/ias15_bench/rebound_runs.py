"""REBOUND's IAS15 on the case, with REBOUNDx's J2 on the central mass."""

from __future__ import annotations

from typing import Any

import numpy as np

from .case import J2, LD, RADIUS, START, State, energy_xv
from .results import Run, least


def _ias15_simulation(start: State, t0: float = 0.0, j2_scale: float = 1.0) -> tuple[Any, Any]:
    """A REBOUND simulation of the case: central mass 1 with REBOUNDx's J2, the body a test
    particle at ``start``, IAS15 at its defaults. The extras object is returned because the
    force lives only as long as it does."""
    import rebound
    import reboundx

    (x, y, z), (vx, vy, vz) = start
    sim = rebound.Simulation()
    sim.G = 1.0
    sim.t = t0
    sim.add(m=1.0)
    sim.add(m=0.0, x=x, y=y, z=z, vx=vx, vy=vy, vz=vz)
    sim.integrator = "ias15"
    extras = reboundx.Extras(sim)
    harmonics = extras.load_force("gravitational_harmonics")
    extras.add_force(harmonics)
    sim.particles[0].params["J2"] = float(J2) * j2_scale
    sim.particles[0].params["R_eq"] = float(RADIUS)
    return sim, extras


def ias15(
    times: np.ndarray, start: State = START, t0: float = 0.0, j2_scale: float = 1.0
) -> tuple[np.ndarray, int]:
    """REBOUND IAS15 (default ε = 1e-9, PRS23 step control) with REBOUNDx's J2 on the central
    mass; the body is a test particle (m = 0), so the central mass stays at the origin.
    ``t0`` starts the clock elsewhere (the dynamics are autonomous)."""
    sim, _extras = _ias15_simulation(start, t0, j2_scale)
    out = np.empty((6, len(times)))
    for i, t in enumerate(times):
        sim.integrate(t0 + t, exact_finish_time=1)
        p = sim.particles[1]
        out[:, i] = (p.x, p.y, p.z, p.vx, p.vy, p.vz)
    return out, int(sim.steps_done)


def ias15_clock(times: np.ndarray) -> dict[str, Any]:
    """IAS15 stepped from Python with REBOUND's own exact-finish rule, summing the steps it
    took in long double: the elapsed time its state belongs to, against its clock ``t``."""
    sim, _extras = _ias15_simulation(START)
    elapsed, T = LD(0), np.empty(len(times), dtype=LD)
    out = np.empty((6, len(times)))
    for i, t in enumerate(times):
        while sim.t < t:
            if sim.t + sim.dt > t:
                sim.dt = t - sim.t
            sim.steps(1)
            elapsed += LD(sim.dt_last_done)
        T[i] = elapsed
        p = sim.particles[1]
        out[:, i] = (p.x, p.y, p.z, p.vx, p.vy, p.vz)
    return {"T": T, "out": out, "clock": np.array([sim.t])}


def ias15_run(times: np.ndarray, repeat: int, start: State = START, t0: float = 0.0) -> Run:
    wall, (out, steps) = least(lambda: ias15(times, start, t0), repeat)
    energy = energy_xv(out[:3], out[3:])
    if t0:
        name, settings, group = (
            "IAS15, clock started at t₀ = 2²⁰",
            "same orbit, same steps; only \\|t\\| is larger",
            "diagnostic",
        )
    else:
        name, settings, group = "IAS15 (REBOUND)", "ε = 1e-9 (default), PRS23", "ias15"
    return Run(name, settings, steps, wall, out[:3], energy, group=group)
