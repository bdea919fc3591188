"""Validation of the rotation integrators against the closed-form free rigid body.

Run:  python validation/rotation_report.py            (full run; writes validation/REPORT.md
                                                       and validation/figures/*.png)
      python validation/rotation_report.py --quick    (smoke run: short spans, written to a
                                                       temporary directory unless --out is given)

Every case of :mod:`rotation_cases` is integrated by ``cayley_heyoka.run`` at each of its
precisions and compared, at every output time, with ``cayley_heyoka.reference.FreeRigidBody``
(Cayley 1843 in Jacobi form, certified at ``REFERENCE_DPS`` digits). Measured:

* the state error of (p, q, r), scaled by |ω(0)|, and the attitude error (distance between the
  unit quaternions up to sign);
* the relative drift of the energy, |L|² and the space components of L;
* invariable-plane crossing times from heyoka's event detection against the reference's;
* the growth exponents of the errors against the step count.

Tolerances are fixed before any number is seen, from the round-off laws (the comment block
"the laws" in ``rotation_validation/laws.py``, written out in the report) or taken from the
brief (``REQUIREMENTS``). A case that misses one is reported as FAIL with the measured number.

The work is done by the package ``rotation_validation`` next to this script (the cases'
tolerances, the runners, the report writers); this script is its command line, and re-exports
the names the tests use.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from rotation_cases import BY_NAME, separatrix_distance
from rotation_validation.exact_flow import law_constants
from rotation_validation.plan import run_tasks
from rotation_validation.report import write_report
from rotation_validation.runs import (
    crossing_errors,
    integrate,
    output_times,
    run_job,
    state_errors,
)
from rotation_validation.verdicts import quantity_rows

ROOT = Path(__file__).resolve().parent.parent
HERE = Path(__file__).resolve().parent

__all__ = [
    "crossing_errors",
    "integrate",
    "law_constants",
    "main",
    "output_times",
    "quantity_rows",
    "run_job",
    "separatrix_distance",
    "state_errors",
]


def main(argv: list[str] | None = None) -> int:
    """Run every task on a process pool, then write the report and the figures."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="short spans: a smoke run")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    parser.add_argument("--cases", default="", help="comma-separated case names (default all)")
    parser.add_argument(
        "--out", default=None, help="output directory (default validation/; --quick: a temp dir)"
    )
    args = parser.parse_args(argv)
    mode = "quick" if args.quick else "full"
    only = set(args.cases.split(",")) if args.cases else None
    if only and only - set(BY_NAME):
        parser.error(f"unknown cases {sorted(only - set(BY_NAME))}; known: {list(BY_NAME)}")
    out = Path(args.out) if args.out else (HERE if mode == "full" else Path(tempfile.mkdtemp()))
    t0 = time.perf_counter()
    jobs, ensembles, diagnostic = run_tasks(mode, only, args.jobs, t0)
    path = write_report(jobs, ensembles, diagnostic, out, time.perf_counter() - t0, args.jobs, mode)
    print(f"wrote {path} ({(time.perf_counter() - t0) / 60:.1f} min)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
