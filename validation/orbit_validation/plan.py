"""The task list of a run: every job of the chosen parts with its estimated cost."""

from __future__ import annotations

from typing import Any

from orbit_cases import ECCENTRICITIES, FORMULATIONS, INCLINATIONS, LONG, REFERENCE

from .long_runs import long_job
from .reference import reference_job
from .sweeps import eccentricity_job, inclination_job

# Estimated seconds (measured on the development machine), for load balance.
_COST = {
    ("long", "double"): 1,
    ("long", "quad"): 100,
    ("long", "real160"): 80,
}


def plan(mode: str, parts: set[str]) -> list[tuple[float, Any, tuple]]:
    tasks = []
    if "reference" in parts:
        for case in REFERENCE:
            for prec in ("double", "quad"):
                for f in (*FORMULATIONS, "departure"):
                    cost = 5 if prec == "quad" else 0.5
                    tasks.append((cost, reference_job, (case.name, f, prec)))
    if "long" in parts:
        for case in LONG:
            scale = case.orbits[mode] / 1000 * (2 if case.name == "L2" else 1)
            for f in FORMULATIONS:
                for prec in ("double", "quad"):
                    cost = _COST[("long", prec)] * scale * (2 if f != "cartesian" else 0.5)
                    tasks.append((cost, long_job, (case.name, f, prec, mode)))
            tasks.append(
                (
                    _COST[("long", "real160")] * scale,
                    long_job,
                    (case.name, "cartesian", "real160", mode),
                )
            )
    if "inclination" in parts:
        for i in INCLINATIONS:
            tasks.append((5, inclination_job, (i, mode)))
    if "eccentricity" in parts:
        for e in ECCENTRICITIES:
            tasks.append((2 + 40 * float(e) ** 8, eccentricity_job, (e, mode)))
    return sorted(tasks, key=lambda x: -x[0])


PARTS = ("reference", "long", "inclination", "eccentricity")
