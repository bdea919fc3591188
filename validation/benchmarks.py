"""Regenerate validation/BENCHMARKS.md: speed against accuracy, conservation, set-up cost.

Run:  python -m pip install -e ".[bench]" && python validation/benchmarks.py
      python validation/benchmarks.py --quick            (a smoke run: seconds, not minutes)
      python validation/benchmarks.py --only ias15       (one section)

Each section is one script ``bench_<name>.py`` with ``run(quick, figures) -> str`` returning
its Markdown; this driver writes it between the section's markers (other sections untouched)
and its plots into ``figures/`` beside the document. Peers that are not installed (scipy,
REBOUND, REBOUNDx) are reported as such, not failed.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

from bench_common import machine
from report_sections import write_section

HERE = Path(__file__).resolve().parent

SECTIONS = ("users", "work_precision", "ias15", "conservation", "long_runs", "setup")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a smoke run of every section")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, help="only these sections")
    parser.add_argument("--out", type=Path, default=HERE / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    figures = args.out.parent / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    mode = " --quick" if args.quick else ""
    header = (
        "# Benchmarks: speed against accuracy\n\n"
        f"Regenerate with `python validation/benchmarks.py{mode}` (each section also alone, "
        "`--only NAME`). Machine: " + machine() + ". Every ratio is measured side by side in "
        "one process; wall times are the least of a few repeats."
    )
    write_section(args.out, "header", header)
    for name in args.only or SECTIONS:
        t0 = time.perf_counter()
        module = importlib.import_module(f"bench_{name}")
        body = module.run(quick=args.quick, figures=figures)
        body += f"\n\n_Section generated in {time.perf_counter() - t0:.0f} s._\n"
        write_section(args.out, name, body)
        print(f"{name}: {time.perf_counter() - t0:.1f} s", flush=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
