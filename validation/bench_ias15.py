"""The IAS15 case: an e = 0.5 orbit with J2 over 10⁴ orbits, against REBOUND's IAS15.

Section ``ias15`` of ``validation/BENCHMARKS.md``::

    python validation/benchmarks.py --only ias15 [--quick]
    python validation/bench_ias15.py [--quick] [--out PATH]

The orbit: μ = 1, a = 1, e = 0.5, i = 0.3, node 0.4, ω = 0.5, M = 0; J2 = 10⁻³ about z with
R = 0.1 (pericentre 0.5). Every method starts from the same double state (the scenes carry its
exact decimal expansion).

1. **One orbit over 10⁴ revolutions** against a reference: our Cartesian formulation in real128
   at tolerance 1e-24, checked against a second real128 run at 1e-20. The pair takes minutes,
   so both are cached under ``$CAYLEY_HEYOKA_BENCH_CACHE`` (default
   ``<tmp>/cayley_heyoka_bench``) and reused while the case, the grid and heyoka's version are
   the same.
2. **An energy ensemble**: the same orbit from 8 starting mean anomalies over 10³ revolutions
   (energy needs no reference). Round-off is a random walk, and one trajectory is one draw of
   it; the medians of the ensemble are what the explanation rests on.

The scene options (formulation, tolerance, ``high_accuracy``, precision) include Encke's
formulation (``orbit.formulation = "encke"``, ``cayley_heyoka/orbit/encke.py``): the deviation
from an osculating Kepler orbit, integrated in double with Battin's cancellation-free
difference of the two central forces beside the ellipse's eccentric anomaly, the ellipse
rectified at every apocentre in long double (its handler timed here, for the share of the wall
time it takes). Beside them, two prototypes, written here and not in the library, test the
explanation of the gap to IAS15 (a compensated state and extended precision,
``ias15_bench/prototypes.py``), and two diagnostics of the Encke formulation's design solve the
ellipse's anomaly with heyoka's ``kepE`` instead of integrating it
(``ias15_bench/encke_variants.py``).

Errors: |Δx|/a against the reference; |ΔE/E| from each method's own state (Cayley's r, ṙ, h;
the others' x, v) evaluated in long double against the exact energy of the initial state.
Exponents: slopes of the running maximum against t over the last two decades (log–log). Wall
times are the least of a few repeats, all in one process.

The code is in the package ``ias15_bench`` beside this script: the case (``case``), the runners
(``reference``, ``results``, ``rebound_runs``, ``prototypes``, ``encke_variants``,
``runners``) and the report writers (``plots``, ``report``, ``explanation``).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ias15_bench.case import LD, N_FULL, N_QUICK, grid, scene
from ias15_bench.encke_variants import TimedEncke, encke_variant
from ias15_bench.explanation import explanation
from ias15_bench.plots import plot
from ias15_bench.rebound_runs import ias15
from ias15_bench.reference import reference
from ias15_bench.report import render
from ias15_bench.runners import ensemble_run, long_run

HERE = Path(__file__).resolve().parent

# Taken by validation/users_orbit.py, tests/orbit/test_encke.py and validation/benchmarks.py.
__all__ = [
    "LD",
    "N_FULL",
    "N_QUICK",
    "TimedEncke",
    "encke_variant",
    "grid",
    "ias15",
    "main",
    "reference",
    "run",
    "scene",
]


def run(quick: bool, figures: Path) -> str:
    """The Markdown body of the section (and its plots in ``figures``)."""
    figures = Path(figures)
    figures.mkdir(parents=True, exist_ok=True)
    long = long_run(quick)
    ens = ensemble_run(quick)
    names = plot(long, ens, figures)
    return render(long, ens, names, quick) + "\n\n" + "\n".join(explanation(long, ens))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run (seconds)")
    parser.add_argument("--out", type=Path, default=HERE / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    from benchmarks import main as driver

    return driver(["--only", "ias15", "--out", str(args.out)] + (["--quick"] if args.quick else []))


if __name__ == "__main__":
    sys.exit(main())
