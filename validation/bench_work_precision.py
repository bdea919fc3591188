"""Work–precision: error against wall time over a tolerance sweep, ours and the peers side by side.

Run:  python validation/bench_work_precision.py [--quick] [--out PATH]
      (or through the driver: python validation/benchmarks.py --only work_precision)

Cases: the torque-free bodies ``free_regular`` and ``free_separatrix`` against the closed form,
``heavy_top``, ``orbit_j2`` (a J2 orbit) and ``planets`` (examples/planets.toml) against
real128 runs, and ``free_extended`` in extended precision. Ours is ``cayley_heyoka.run`` swept
over its tolerance; the peers are scipy's ``solve_ivp``, REBOUND's IAS15 and mpmath's ``odefun``.

This script is the entry point; its parts are in validation/work_precision_bench/: the cases
(``cases``, ``records``), the runners (``timing``, ``errors``, ``our_side``, ``peers``,
``rotation_runs``, ``orbit_runs``) and the report writers (``report``, ``commentary``, ``plots``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from work_precision_bench import timing
from work_precision_bench.orbit_runs import orbit_j2, planets
from work_precision_bench.report import section
from work_precision_bench.rotation_runs import free_body, free_extended, heavy_top
from work_precision_bench.timing import log

HERE = Path(__file__).resolve().parent

__all__ = ["main", "run"]


# ---------------------------------------------------------------------------- driver
def run(quick: bool, figures: Path) -> str:
    """The Markdown body of the work–precision section; plots into ``figures``."""
    figures.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    timing.REPEAT = 2 if quick else 5  # the smoke run must stay within seconds
    periods = 2 if quick else 20
    cases = [
        free_body("free_regular", "generic", periods, quick),
        free_body("free_separatrix", "separatrix_p6", periods, quick),
        heavy_top(quick),
        orbit_j2(quick),
        planets(quick),
        free_extended(quick),
    ]
    text = section(cases, figures)
    log(f"total {time.perf_counter() - t0:.0f} s")
    return text


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=HERE / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    import benchmarks

    return benchmarks.main(
        ["--only", "work_precision", "--out", str(args.out)] + (["--quick"] if args.quick else [])
    )


if __name__ == "__main__":
    sys.exit(main())
