"""Validation of the orbit integrators (Cayley 1860): Cayley vs quaternion vs Cartesian.

Run:  python validation/orbit_report.py            (full run; writes the ``orbit`` section of
                                                    validation/REPORT.md and
                                                    validation/figures/orbit_*.png)
      python validation/orbit_report.py --quick    (smoke run: short spans, written to a
                                                    temporary directory unless --out is given)

Four parts (cases in :mod:`orbit_cases`):

1. reference values R1–R4 (:data:`orbit_cases.REFERENCE`): every formulation in double and
   real128 at the cases' time t, every listed quantity;
2. two 1000-orbit problems in double and real128: Cayley and quaternion against the Cartesian
   system in the same precision, double against a real128 Cartesian reference, real128 against a
   160-bit Cartesian reference; conserved-quantity drifts;
3. an inclination sweep (1 … 1e-8 rad) in double against a real128 Cartesian reference that
   carries the departure-point vector (docs/orbits.md), so Θ, Σ, Φ have a reference too;
4. an eccentricity sweep (0 … 0.99) in double against a real128 Cartesian reference.

Tolerances are fixed before any number is seen, from the round-off laws (the comment block
"the laws" in ``orbit_validation/tolerances.py``, written out in the report) or taken from the
brief (``REQUIREMENTS``). A row that misses one is reported as FAIL with the measured number.
The code is the package ``validation/orbit_validation/`` (tolerances, runners, report writers);
this script is its command line and re-exports the names the tests use.
"""

from __future__ import annotations

import argparse
import concurrent.futures as cf
import multiprocessing
import sys
import tempfile
import time
from pathlib import Path

from orbit_cases import scene
from orbit_validation.long_runs import (
    drift_rows,
    long_comparisons,
    long_job,
    position_error,
)
from orbit_validation.plan import PARTS, plan
from orbit_validation.reference import reference_job
from orbit_validation.report import write_report
from orbit_validation.runs import columns, integrate, output_times, steps_at
from orbit_validation.sweeps import inclination_job
from orbit_validation.tolerances import K_x, law, reference_tolerance

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve().parent

__all__ = [
    "K_x",
    "columns",
    "drift_rows",
    "inclination_job",
    "integrate",
    "law",
    "long_comparisons",
    "long_job",
    "main",
    "output_times",
    "position_error",
    "reference_job",
    "reference_tolerance",
    "scene",
    "steps_at",
]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="short spans: a smoke run")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--parts", default=",".join(PARTS), help=f"subset of {PARTS}")
    parser.add_argument(
        "--out", default=None, help="output directory (default validation/; --quick: a temp dir)"
    )
    args = parser.parse_args(argv)
    mode = "quick" if args.quick else "full"
    parts = set(args.parts.split(","))
    if parts - set(PARTS):
        parser.error(f"unknown parts {sorted(parts - set(PARTS))}; known: {PARTS}")
    out = Path(args.out) if args.out else (HERE if mode == "full" else Path(tempfile.mkdtemp()))
    t0 = time.perf_counter()
    results = []
    ctx = multiprocessing.get_context("spawn")  # heyoka's LLVM/TBB state must not be forked
    with cf.ProcessPoolExecutor(max_workers=args.jobs, mp_context=ctx) as pool:
        futures = {pool.submit(fn, *a): a for _, fn, a in plan(mode, parts)}
        for fut in cf.as_completed(futures):
            r = fut.result()
            results.append(r)
            label = " ".join(str(x) for x in futures[fut])
            print(
                f"[{time.perf_counter() - t0:7.1f} s] {r['kind']:12s} {label} "
                f"({r['wall_seconds']:.1f} s)",
                flush=True,
            )
    path = write_report(results, out, time.perf_counter() - t0, args.jobs, mode)
    print(f"wrote {path} ({(time.perf_counter() - t0) / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
