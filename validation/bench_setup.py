"""Set-up cost and ensembles: compile time against scene size, the caches, ensemble throughput.

Run:  python validation/bench_setup.py [--quick] [--out FILE]   (this section of BENCHMARKS.md)
      python validation/benchmarks.py --only setup               (the same, through the driver)

1. Compile time against scene size: families of scenes of growing size (orbit zonal harmonics,
   a rigid body with a growing force function, the predominant-mass system with more bodies,
   Hamilton's elements), each compiled cold in both code models, with the step cost of each;
   from them the size above which compact mode should be the automatic choice.
2. Caches: a scene run again, a scene differing only in numbers, heyoka's in-memory and
   on-disk caches, new processes.
3. Ensembles: members per second of a loop of ``run()``, of heyoka's batch mode and its
   ensemble propagation, and of :func:`cayley_heyoka.workflows.ensemble.propagate_ensemble`.

"Cold" means that LLVM optimises and generates the code from scratch: our template cache and
heyoka's in-memory cache are cleared and heyoka's disk cache points at a fresh, empty
directory (so the measurement includes writing the code there, as a user's first run does).

The cases, runners and report writers are in the package ``setup_bench/`` beside this script.
"""

from __future__ import annotations

import sys
from pathlib import Path

from setup_bench.section import run

HERE = Path(__file__).resolve().parent

__all__ = ["run"]


if __name__ == "__main__":
    import benchmarks

    sys.exit(benchmarks.main(["--only", "setup", *sys.argv[1:]]))
