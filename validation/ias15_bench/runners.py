"""The runs: each method on the grid (our scenes, IAS15, the prototypes, the Encke
diagnostics), the long run of one orbit over 10⁴ revolutions against the reference, the energy
ensemble (the same orbit from several starting mean anomalies over 10³ revolutions; energy
needs no reference, and its medians are what the explanation rests on), and the side
measurements: IAS15's clock, the J2 convention and the cost of real128."""

from __future__ import annotations

import contextlib
import math
from typing import Any

import numpy as np
from bench_common import available

import cayley_heyoka as ch

from .case import (
    CHECK_TOL,
    ENSEMBLE,
    EPS,
    LD,
    N_FULL,
    N_QUICK,
    START,
    State,
    energy_polar,
    energy_xv,
    exact_energy,
    grid,
    initial_state,
    scene,
)
from .encke_variants import KeplerClockEncke, KeplerGlobalTimeEncke, TimedEncke, encke_variant
from .prototypes import cartesian_integrator, compensated, extended
from .rebound_runs import ias15, ias15_clock, ias15_run
from .reference import Reference, reference
from .results import Run, least


def ours(
    times: np.ndarray,
    formulation: str,
    repeat: int,
    start: State = START,
    variant: type | None = None,
    **integrator: Any,
) -> Run:
    """A scene run through ``cayley_heyoka.run``; ``variant`` replaces the Encke bookkeeping
    (the timed handler, or the global-time diagnostic)."""
    with encke_variant(variant) if variant else contextlib.nullcontext():
        ch.run(scene(formulation, grid(1), start, **integrator))  # compile: same structure
        s = scene(formulation, times, start, **integrator)
        TimedEncke.seconds = 0.0
        wall, r = least(lambda: ch.run(s), repeat)
    x = np.array([np.asarray(r[k], dtype=float) for k in ("x", "y", "z")])
    if formulation in ("cartesian", "encke"):
        v = np.array([np.asarray(r[k], dtype=float) for k in ("vx", "vy", "vz")])
        energy = energy_xv(x, v)
    else:
        energy = energy_polar(r["r"], r["rdot"], r["h"], r["z"])
    parts = []
    tol = integrator.get("tolerance", "auto")
    parts.append("tol ε" if tol == "auto" else f"tol {tol}")
    if integrator.get("high_accuracy"):
        parts.append("high_accuracy")
    if "rectifications" in r.counters:
        parts.append(f"{r.counters['rectifications']} rectifications")
    run = Run(f"ours, {formulation}", ", ".join(parts), r.counters["steps"], wall, x, energy)
    if variant is TimedEncke:
        run.extra["python"] = TimedEncke.seconds / repeat / wall
    elif variant is not None:
        where = "the global time" if variant is KeplerGlobalTimeEncke else "a clock"
        run.method = f"diagnostic: encke, kepE on {where}"
        run.group = "diagnostic"
    return run


# --------------------------------------------------------------------------------- driver
def _proto(method: str, settings: str, wall: float, out: np.ndarray, steps: int) -> Run:
    energy = energy_xv(out[:3], out[3:])
    return Run(method, settings, steps, wall, out[:3], energy, group="prototype")


def methods(quick: bool, ensemble: bool) -> list[tuple[str, Any]]:
    """(key, runner) pairs; a runner takes (times, start, repeat) and returns a Run."""
    built: dict[Any, Any] = {}  # integrators compiled on first use, shared by the runs

    def integrator(key: Any, build: Any) -> Any:
        if key not in built:
            built[key] = build()
        return built[key]

    def comp(exact: bool) -> Any:
        label = "cartesian, tol ε" + (", acceleration in long double" if exact else "")

        def go(times: np.ndarray, start: State, repeat: int) -> Run:
            ta = integrator("double", cartesian_integrator)
            wall, (out, steps) = least(lambda: compensated(times, ta, start, exact), repeat)
            return _proto("prototype: compensated state", label, wall, out, steps)

        return go

    def extd(tol: float | None) -> Any:
        label = "tol 2⁻⁵² (double's ε)" if tol else "tol 2⁻⁶³ (its own ε)"

        def go(times: np.ndarray, start: State, repeat: int) -> Run:
            ta = integrator(("extended", tol), lambda: cartesian_integrator(LD, tol))
            wall, (out, steps) = least(lambda: extended(times, ta, start), repeat)
            return _proto("prototype: extended precision", label, wall, out, steps)

        return go

    def scene_run(formulation: str, variant: type | None = None, **kw: Any) -> Any:
        return lambda times, start, repeat: ours(times, formulation, repeat, start, variant, **kw)

    rows: list[tuple[str, Any]] = []
    if available("rebound") and available("reboundx"):
        rows.append(("ias15", lambda times, start, repeat: ias15_run(times, repeat, start)))
    rows.append(("cartesian", scene_run("cartesian")))
    if not quick:
        rows.append(("cartesian ha", scene_run("cartesian", high_accuracy=True)))
    if not quick and not ensemble:
        rows.append(
            ("cartesian 1e-18", scene_run("cartesian", high_accuracy=True, tolerance="1e-18"))
        )
    rows.append(("cayley", scene_run("cayley")))
    if not quick and not ensemble:
        rows += [
            ("cayley ha", scene_run("cayley", high_accuracy=True)),
            ("cayley 1e-18", scene_run("cayley", high_accuracy=True, tolerance="1e-18")),
        ]
    if not quick:
        rows.append(("quaternion", scene_run("quaternion")))
    if ensemble:
        rows += [("compensated", comp(False)), ("compensated acc", comp(True))]
    rows.append(("extended", extd(EPS)))
    if not quick and not ensemble:
        rows.append(("extended own", extd(None)))
    rows.append(("encke", scene_run("encke", TimedEncke)))
    if not quick and not ensemble:
        rows += [
            ("encke 1e-18", scene_run("encke", tolerance="1e-18")),
            ("encke kepE clock", scene_run("encke", KeplerClockEncke)),
            ("encke kepE global time", scene_run("encke", KeplerGlobalTimeEncke)),
        ]
    return rows


def long_run(quick: bool) -> dict[str, Any]:
    n = N_QUICK if quick else N_FULL
    times = grid(n)
    rep = 1 if quick else 2
    ref = reference(times, check=not quick)
    e0 = exact_energy()
    runs: list[Run] = []
    for key, runner in methods(quick, ensemble=False):
        runs.append(runner(times, START, 1 if key == "extended own" else rep))
    out: dict[str, Any] = {"n": n, "times": times, "ref": ref, "runs": runs}
    if not quick and available("rebound") and available("reboundx"):
        runs.append(ias15_run(times, 1, t0=2.0**20))
        out["clock"] = clock_split(times, ref, e0)
    for r in runs:
        r.measure(ref, e0)
    if available("rebound") and available("reboundx"):
        out["convention"] = convention_check()
    if not quick:
        out["quad"] = quad_cost(ref)
    return out


def ensemble_run(quick: bool) -> dict[str, Any]:
    """max |ΔE/E| over the ensemble's members: per method, the members' maxima and the median
    (over members) of the running maximum on the grid."""
    n, members = ENSEMBLE[quick]
    times = grid(n)
    rows = methods(quick, ensemble=True)
    stats: dict[str, dict[str, Any]] = {}
    for m in range(members):
        start = initial_state(2 * math.pi * m / members)
        e0 = exact_energy(start)
        for key, runner in rows:
            r = runner(times, start, 1)
            r.measure(None, e0)
            s = stats.setdefault(key, {"run": r, "max": [], "env": [], "steps": [], "wall": 0.0})
            s["max"].append(r.max_energy)
            s["env"].append(np.maximum.accumulate(r.energy_err))
            s["steps"].append(r.steps)
            s["wall"] += r.wall
    for s in stats.values():
        s["median_env"] = np.median(np.array(s["env"]), axis=0)
    return {"n": n, "members": members, "times": times, "stats": stats}


def clock_split(times: np.ndarray, ref: Reference, e0: Any) -> dict[str, float]:
    """IAS15's error at its clock's time and at the time its steps add up to (the reference
    moved to it to first order, x + v δt; δt ~ 1e-9 makes the next term ~1e-18)."""
    c = ias15_clock(times)
    dt = c["T"] - LD(times[-1])  # its state is at T; its clock says times[-1]
    x = np.asarray(c["out"][:3, -1], dtype=LD)
    at_clock = x - ref.x[:, -1]
    at_steps = x - (ref.x[:, -1] + ref.v[:, -1] * dt[-1])
    return {
        "dt": float(dt[-1]),
        "at_clock": float(np.sqrt(at_clock @ at_clock)),
        "at_steps": float(np.sqrt(at_steps @ at_steps)),
        "speed": float(np.sqrt(ref.v[:, -1] @ ref.v[:, -1])),
    }


def convention_check() -> dict[float, float]:
    """IAS15 + REBOUNDx against our real128 reference over 10 orbits, with our J2 and with
    J2 off by 1%: a convention mismatch would show at the second level."""
    times = grid(10)
    ref = reference(times, check=False)
    out = {}
    for scale in (1.0, 1.01):
        x, _ = ias15(times, j2_scale=scale)
        d = np.asarray(x[:3], dtype=LD) - ref.x
        out[scale] = float(np.sqrt((d * d).sum(axis=0)).max())
    return out


def quad_cost(ref: Reference) -> dict[str, float]:
    """real128 at tolerance 1e-20 as an accurate option: its error is the reference check; its
    cost per orbit is measured over 100 orbits next to IAS15's over the same 100 orbits."""
    times = grid(100)
    s = scene("cartesian", times, precision="quad", tolerance=CHECK_TOL)
    ch.run(s)
    wq, _ = least(lambda: ch.run(s), 1)
    wi = math.nan
    if available("rebound") and available("reboundx"):
        wi, _ = least(lambda: ias15(times), 2)
    return {"quad_wall_100": wq, "ias15_wall_100": wi, "final": float(ref.check[-1])}
