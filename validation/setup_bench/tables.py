"""Table rows of the set-up section: a compile point, an ensemble throughput, a scene's cache
runs (Markdown, also printed as each is measured)."""

from __future__ import annotations

import math

from bench_common import fmt

import cayley_heyoka as ch

from .results import Point, Throughput


def point_row(p: Point) -> str:
    be = p.break_even
    be_text = "never" if be == math.inf else ("–" if be == 0 else f"{be:.1e}")
    return (
        f"| {p.family} | {p.param} | {p.size / 1e3:.1f} | {p.decomposition} | "
        f"{p.compile[False]:.2f} ({p.cpu[False]:.2f}) | {p.compile[True]:.2f} "
        f"({p.cpu[True]:.2f}) | {p.ns[False]:,.0f} | {p.ns[True]:,.0f} | {p.ratio:.2f} | "
        f"{be_text} | {'compact' if p.auto_compact else 'non-compact'} |"
    )


def throughput_row(r: Throughput) -> str:
    mark = "" if r.measured else " (extrapolated)"
    steps = r.steps / r.wall if r.wall > 0 else math.nan
    cores = r.cpu / r.wall if r.measured and r.wall > 0 else math.nan
    return (
        f"{r.method}{mark} | {r.n:,} | {fmt(r.wall)} | {r.rate:,.0f} | {steps:,.0f} | "
        f"{fmt(cores)} | {fmt(r.error) if r.measured else '–'} |"
    )


def cache_rows(
    label: str,
    entries: list[tuple[str, ch.Result, float]],
    process_rows: list[tuple[str, dict[str, float]]],
) -> list[str]:
    """One scene's rows of the cache table: its in-process runs, then its new processes."""
    rows = []
    for text, r, w in entries:
        rows.append(
            f"| {label} | {text} | {r.metadata['compiled_from_cache']} | "
            f"{r.metadata['compile_seconds']:.3f} | {w:.3f} |"
        )
    for text, c in process_rows:
        rows.append(
            f"| {label} | {text} (import {c['import']:.2f} s, process {c['process']:.2f} s) "
            f"| – | {c['compile']:.3f} | {c['run']:.3f} |"
        )
    return rows
