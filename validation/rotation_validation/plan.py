"""The plan of a run and its process pool: every task with its cost estimate, run in parallel."""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import time
from typing import Any

import numpy as np
from rotation_cases import CASES, ENSEMBLES, QUICK_ENSEMBLES

from .diagnostic import diagnose_roundoff
from .ensembles import ensemble_fits, ensemble_member
from .laws import LawConstants
from .runs import run_job
from .verdicts import sci

# ms per step (measured) and steps per period (typical): cost estimates for load balance.
_MS_PER_STEP = {"double": 0.1, "quad": 1.2, "real256": 10.0}


def plan(mode: str, only: set[str] | None) -> list[tuple[float, Any, tuple]]:
    """Every task as (estimated cost, function, arguments), the most expensive first."""
    tasks = []
    for case in CASES:
        if only and case.name not in only:
            continue
        spans = case.quick if mode == "quick" else case.periods
        for prec, periods in spans.items():
            cost = _MS_PER_STEP[prec] * periods * (80 if case.group == "separatrix" else 30)
            tasks.append((cost, run_job, (case.name, prec, periods, mode)))
    for name, prec, periods, members in QUICK_ENSEMBLES if mode == "quick" else ENSEMBLES:
        if only and name not in only:
            continue
        for k in range(members):
            cost = _MS_PER_STEP[prec] * periods * 30
            tasks.append((cost, ensemble_member, (name, prec, periods, k, mode)))
    if not only or "symmetric" in only:
        tasks.append((10_000, diagnose_roundoff, (mode,)))
    return sorted(tasks, key=lambda x: -x[0])


def run_tasks(
    mode: str, only: set[str] | None, workers: int, t0: float
) -> tuple[list[dict[str, Any]], dict[tuple, dict], dict[str, Any] | None]:
    """Run the plan on ``workers`` spawned processes, printing each result as it arrives
    (stamped with the seconds since ``t0``); return the runs, the ensembles' fits and the
    diagnostic (None when not run)."""
    jobs, members, diagnostic = [], {}, None
    # spawn: heyoka's LLVM/TBB state must not be forked.
    ctx = multiprocessing.get_context("spawn")
    with cf.ProcessPoolExecutor(max_workers=workers, mp_context=ctx) as pool:
        futures = [pool.submit(fn, *fn_args) for _, fn, fn_args in plan(mode, only)]
        for fut in cf.as_completed(futures):
            job = fut.result()
            stamp = f"[{time.perf_counter() - t0:7.1f} s]"
            if job.get("kind") == "ensemble":
                members.setdefault(job["key"], []).append(job)
                print(f"{stamp} ensemble member {job['key']}", flush=True)
                continue
            if job.get("kind") == "diagnostic":
                diagnostic = job
                print(f"{stamp} round-off diagnostic", flush=True)
                continue
            job["law"] = LawConstants(**job["law"])
            jobs.append(job)
            print(
                f"{stamp} {job['case']:18s} {job['precision']:8s} "
                f"{job['periods']:>6g} periods, {job['steps']:7d} steps: rates "
                f"{sci(np.nanmax(job['errors']['state']))}, attitude "
                f"{sci(np.nanmax(job['errors']['attitude']))}",
                flush=True,
            )
    ensembles = {key: ensemble_fits(ms) for key, ms in sorted(members.items())}
    return jobs, ensembles, diagnostic
