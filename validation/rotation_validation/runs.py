"""One run: integrate one case at one precision and measure it against the closed form.

:func:`run_job` is the worker job (picklable by name, run in a spawned process); the other
functions are its steps, also used by the tests.
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import mpmath
import numpy as np
from rotation_cases import BY_NAME, EPSILON, REFERENCE_DPS, Case

import cayley_heyoka as ch
from cayley_heyoka.reference import FreeRigidBody, PrecisionNotReached

from .exact_flow import law_constants
from .laws import N_TIMES, LawConstants


def output_times(period: float, t_end: float, count: int) -> list[float]:
    """0 and ``count`` log-spaced binary64 times from period/32 to t_end (exact in any type)."""
    t = np.geomspace(period / 32, t_end, count)
    return [0.0, *sorted({float(x) for x in t})]


def to_mpf(x: Any) -> mpmath.mpf:
    """A double, real128 or real as an exact mpf (text round-trips both extended types)."""
    if isinstance(x, float | np.floating | int):
        return mpmath.mpf(float(x))
    return mpmath.mpf(str(x))


def integrate(
    case: Case, precision: str, times: list[float], events: bool = True
) -> tuple[ch.Result, np.ndarray]:
    """Run the case; return the result and the time reached after each step."""
    steps: list[float] = []
    scene = ch.Scene.from_dict(case.scene(precision, times, events=events))
    result = ch.run(scene, progress=steps.append)
    return result, np.asarray(steps)


def state_errors(case: Case, precision: str, result: ch.Result) -> dict[str, Any]:
    """Scaled rates error and quaternion distance against the closed form at every output time."""
    dps = REFERENCE_DPS[precision]
    body = FreeRigidBody(case.inertia, case.rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
    state, attitude, ref_err = [], [], mpmath.mpf(0)
    failures = []
    names = ("p", "q", "r", "qw", "qx", "qy", "qz")
    with mpmath.workdps(dps + 20):
        columns = {k: result[k] for k in names}
        w0 = mpmath.sqrt(sum(mpmath.mpf(x) ** 2 for x in case.rates))
        for i, t in enumerate(result.t):
            try:
                s = body.at(to_mpf(t))
            except PrecisionNotReached as exc:
                failures.append(str(exc))
                state.append(math.nan)
                attitude.append(math.nan)
                continue
            ref_err = max(ref_err, s.error)
            v = {k: to_mpf(columns[k][i]) for k in names}
            de = max(abs(v["p"] - s.p), abs(v["q"] - s.q), abs(v["r"] - s.r)) / w0
            qi = [v["qw"], v["qx"], v["qy"], v["qz"]]
            minus = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(qi, s.quaternion, strict=True)))
            plus = mpmath.sqrt(sum((a + b) ** 2 for a, b in zip(qi, s.quaternion, strict=True)))
            state.append(float(de))
            attitude.append(float(min(minus, plus)))
    return {
        "state": np.asarray(state),
        "attitude": np.asarray(attitude),
        "reference_error": float(ref_err),
        "reference_failures": failures,
    }


def conserved_drifts(result: ch.Result) -> dict[str, np.ndarray]:
    """|relative drift| of energy, |L|² and (largest component of) the space L."""
    out = {}
    for name in ("energy", "momentum_squared", "momentum_space"):
        d = result.drift(name)
        d = np.array([[float(to_mpf(x)) for x in np.ravel(row)] for row in d])
        out[name] = np.max(np.abs(d), axis=1)
    return out


def crossing_errors(
    case: Case,
    precision: str,
    result: ch.Result,
    law: LawConstants,
    steps: np.ndarray,
) -> dict[str, Any]:
    """Match heyoka's invariable-plane events with the closed form's crossings, axis by axis.

    Each reference crossing is paired with the nearest event of the same axis when they are
    closer than a quarter of the spacing of consecutive reference crossings (so a pairing is
    unambiguous); unpaired reference crossings are misses, unpaired events extras. A crossing
    whose law tolerance exceeds that gate is beyond the law's horizon: the law itself predicts
    it cannot be placed, so it is counted but not judged.
    """
    eps = EPSILON[precision]
    dps = REFERENCE_DPS[precision]
    body = FreeRigidBody(case.inertia, case.rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
    log = result.events.get("invariable_plane")
    t_end = to_mpf(result.t[-1])
    rows: list[tuple[float, float, float, int, float]] = []  # t, |Δt|, tol, dir ok, gate
    misses = extras = beyond = n_ref = 0
    ref_err = 0.0
    with mpmath.workdps(dps + 20):
        for axis in ("x1", "y1", "z1"):
            ref = body.crossing_times(axis, 0, t_end)
            n_ref += len(ref)
            mask = log.label == axis if log is not None else np.zeros(0, dtype=bool)
            ev_t = [to_mpf(x) for x in log.time[mask]] if log is not None else []
            ev_d = list(log.direction[mask]) if log is not None else []
            used = [False] * len(ev_t)
            beyond_here: set[int] = set()
            ev_f = np.array([float(x) for x in ev_t])
            ref_f = np.array([float(c.time) for c in ref])
            spacing = np.diff(ref_f)
            for i, c in enumerate(ref):
                ref_err = max(ref_err, float(c.error))
                near = [spacing[j] for j in (i - 1, i) if 0 <= j < len(spacing)]
                gate = 0.25 * min(near) if near else 0.25 * law.period
                tc = float(c.time)
                n = float(np.searchsorted(steps, tc, side="right"))
                tol = float(law.crossing(eps, np.array(tc), np.array(max(n, 1.0))))
                if tol > gate:
                    beyond += 1
                    beyond_here.add(i)
                    continue
                j = int(np.argmin(np.abs(ev_f - tc))) if len(ev_f) else -1
                if j < 0 or used[j] or abs(ev_f[j] - tc) > gate:
                    misses += 1
                    continue
                used[j] = True
                dt = float(abs(ev_t[j] - c.time))
                rows.append((tc, dt, tol, int(ev_d[j] == c.direction), gate))
            # An unpaired event is extra unless its nearest reference crossing is one the law
            # cannot place (beyond the horizon): that event is the same crossing, lagging.
            for j, u in enumerate(used):
                if u:
                    continue
                k = int(np.argmin(np.abs(ref_f - ev_f[j]))) if len(ref_f) else -1
                if k >= 0 and k in beyond_here:
                    continue
                extras += 1
    arr = np.array(rows) if rows else np.zeros((0, 5))
    return {
        "n_ref": n_ref,
        "n_events": 0 if log is None else len(log),
        "matched": len(rows),
        "misses": misses,
        "extras": extras,
        "beyond_law": beyond,
        "direction_mismatches": int(np.sum(arr[:, 3] == 0)) if len(arr) else 0,
        "t": arr[:, 0],
        "abs": arr[:, 1],
        "tol": arr[:, 2],
        "reference_error": ref_err,
    }


def running_max(x: np.ndarray) -> np.ndarray:
    """max(|x[:i+1]|), NaN-safe (the error envelope fitted by the growth law)."""
    y = np.where(np.isfinite(x), np.abs(x), 0.0)
    return np.maximum.accumulate(y)


def fit_exponent(n: np.ndarray, err: np.ndarray, mask: np.ndarray) -> float:
    """Least-squares slope of log(running max of err) against log n over ``mask``."""
    env = running_max(err)
    ok = mask & (env > 0) & (n > 0)
    if np.count_nonzero(ok) < 5:
        return math.nan
    return float(np.polyfit(np.log(n[ok]), np.log(env[ok]), 1)[0])


def run_job(name: str, precision: str, periods: float, mode: str) -> dict[str, Any]:
    """Integrate one case at one precision and measure everything against the closed form."""
    case = BY_NAME[name]
    wall0 = time.perf_counter()
    law = law_constants(case)
    t_end = float(periods * law.period)
    count = N_TIMES["quick" if mode == "quick" else ("long" if case.group == "long" else "full")]
    times = output_times(law.period, t_end, count)
    t_run = time.perf_counter()
    result, steps = integrate(case, precision, times)
    # Compilation (or loading from heyoka's disk cache) is a one-off cost: not a step cost.
    run_seconds = time.perf_counter() - t_run - result.metadata.get("compile_seconds", 0.0)
    eps = EPSILON[precision]
    t = np.array([float(x) for x in result.t])
    n = np.searchsorted(steps, t, side="right").astype(float)
    errs = state_errors(case, precision, result)
    drifts = conserved_drifts(result)
    crossings = crossing_errors(case, precision, result, law, steps)
    half = result.events.get("half_turn")
    # Exponents only over runs long enough to have a regime: from one period or t_end/100 on.
    fit_mask = (t >= max(law.period, t_end / 100)) if periods >= 50 else np.zeros_like(t, bool)
    fits = {
        "state": fit_exponent(n, errs["state"], fit_mask),
        "attitude": fit_exponent(n, errs["attitude"], fit_mask),
        "energy": fit_exponent(n, drifts["energy"], fit_mask),
        "momentum_squared": fit_exponent(n, drifts["momentum_squared"], fit_mask),
    }
    return {
        "kind": "case",
        "case": name,
        "precision": precision,
        "periods": periods,
        "t_end": t_end,
        # A plain dict (the driver, plan.run_tasks, rebuilds the LawConstants): kept from when
        # the class lived in __main__, which a spawned worker cannot pickle by name.
        "law": dataclasses.asdict(law),
        "t": t,
        "n": n,
        "steps": int(result.counters["steps"]),
        "rebasings": int(result.counters.get("rebasings", 0)),
        "half_turns": 0 if half is None else len(half),
        "order": result.metadata.get("order"),
        "tolerance": result.metadata.get("tolerance"),
        "run_seconds": run_seconds,
        "wall_seconds": time.perf_counter() - wall0,
        "errors": errs,
        "drifts": drifts,
        "crossings": crossings,
        "fits": fits,
        "tol_state": law.state(eps, t, np.maximum(n, 1)),
        "tol_attitude": law.attitude(eps, t, np.maximum(n, 1)),
        "tol_conserved": law.conserved(eps, n),
    }
