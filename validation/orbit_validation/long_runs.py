"""Part 2: the 1000-orbit runs, their comparisons under the phase law and their drifts."""

from __future__ import annotations

import math
import time
from typing import Any

import mpmath
import numpy as np
from orbit_cases import EPSILON, FORMULATIONS, LONG_BY_NAME, scene

from .runs import columns, integrate, output_times, steps_at, to_mpf
from .tolerances import DPS, N_TIMES, K_x, brouwer, law


def long_job(name: str, formulation: str, precision: str, mode: str) -> dict[str, Any]:
    """One long run: positions/velocities on the log grid, steps up to each time, drifts."""
    case = LONG_BY_NAME[name]
    wall0 = time.perf_counter()
    orbits = case.orbits[mode]
    times = output_times(case.period, orbits * case.period, N_TIMES[mode])
    result, steps, seconds = integrate(scene(case.base, formulation, precision, times))
    t = np.array([float(x) for x in result.t])
    drifts = {}
    for m in ("energy", "jacobi", "polar_momentum"):
        if m in result.monitors:
            drifts[m] = np.array([abs(float(to_mpf(x))) for x in result.drift(m)])
    phi = [float(to_mpf(x)) for x in result["Phi"]] if "Phi" in result.variables else [math.nan]
    return {
        "kind": "long",
        "case": name,
        "formulation": formulation,
        "precision": precision,
        "orbits": orbits,
        "t": t,
        "n": steps_at(steps, t),
        "steps": int(result.counters["steps"]),
        "seconds": seconds,
        "compile_seconds": result.metadata["compile_seconds"],
        "wall_seconds": time.perf_counter() - wall0,
        "columns": columns(result, ("x", "y", "z")),
        "drifts": drifts,
        "min_sin_phi": float(np.min(np.abs(np.sin(phi)))),
    }


def long_pairs(jobs: dict[tuple, dict]) -> list[tuple[tuple, tuple]]:
    """(run, reference) pairs: same precision vs Cartesian; against the next precision's
    Cartesian run."""
    pairs = []
    for prec, ref_prec in (("double", "quad"), ("quad", "real160")):
        for f in ("cayley", "quaternion"):
            pairs.append(((f, prec), ("cartesian", prec)))
        for f in FORMULATIONS:
            pairs.append(((f, prec), ("cartesian", ref_prec)))
    return [(a, b) for a, b in pairs if a in jobs and b in jobs]


def position_error(a: dict, b: dict, scale: float) -> np.ndarray:
    """|x_a − x_b| / scale at every output time."""
    out = []
    with mpmath.workdps(DPS):
        for i in range(len(a["t"])):
            d2 = sum((a["columns"][k][i] - b["columns"][k][i]) ** 2 for k in ("x", "y", "z"))
            out.append(float(mpmath.sqrt(d2) / scale))
    return np.asarray(out)


def long_comparisons(case_name: str, jobs: dict[tuple, dict]) -> list[dict[str, Any]]:
    case = LONG_BY_NAME[case_name]
    rows = []
    for a_key, b_key in long_pairs(jobs):
        a, b = jobs[a_key], jobs[b_key]
        err = position_error(a, b, case.a)
        tol = law(EPSILON[a["precision"]], a["t"], np.maximum(a["n"], 1), case.period, K_x(case.e))
        tol = tol + law(
            EPSILON[b["precision"]], b["t"], np.maximum(b["n"], 1), case.period, K_x(case.e)
        )
        ratio = err / tol
        i = int(np.argmax(err))
        rows.append(
            {
                "run": a_key,
                "against": b_key,
                "t": a["t"],
                "err": err,
                "tol": tol,
                "max": float(err[i]),
                "at": float(a["t"][i]),
                "final": float(err[-1]),
                "tol_end": float(tol[-1]),
                "ratio": float(np.max(ratio)),
                "pass": bool(np.max(ratio) <= 1),
            }
        )
    return rows


def drift_rows(case_name: str, jobs: dict[tuple, dict]) -> list[dict[str, Any]]:
    case = LONG_BY_NAME[case_name]
    rows = []
    for (f, prec), j in jobs.items():
        for m, d in j["drifts"].items():
            judged = m in case.conserved
            tol = brouwer(EPSILON[prec], j["n"])
            rows.append(
                {
                    "formulation": f,
                    "precision": prec,
                    "monitor": m,
                    "max": float(np.max(d)),
                    "final": float(d[-1]),
                    "tol_end": float(tol[-1]),
                    "ratio": float(np.max(d / tol)) if judged else math.nan,
                    "judged": judged,
                    "pass": (not judged) or bool(np.max(d / tol) <= 1),
                }
            )
    return rows
