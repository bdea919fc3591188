"""The section's text: the case and its reference, the long run's table, the ensemble's table
and the variants at IAS15's accuracy or better."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from bench_common import fmt

from .case import CHECK_TOL, EPS, REF_TOL
from .plots import ENSEMBLE_LABELS
from .reference import Reference
from .results import Run, growth


def brouwer(max_energy: float, steps: float) -> float:
    """max |ΔE/E| / (ε √steps): the constant of Brouwer's law."""
    return max_energy / (EPS * math.sqrt(max(steps, 1)))


def render(long: dict[str, Any], ens: dict[str, Any], names: list[str], quick: bool) -> str:
    runs: list[Run] = long["runs"]
    ref: Reference = long["ref"]
    n = long["n"]
    t = long["times"]
    ias = next((r for r in runs if r.group == "ias15"), None)
    lines = ["## The IAS15 case: e = 0.5 with J2 over 10⁴ orbits", ""]
    if quick:
        lines += [
            f"_Quick run: {n} orbits, an ensemble of {ens['members']} × {ens['n']} orbits and "
            "fewer variants: a smoke test, not the case (run without `--quick`)._",
            "",
        ]
    lines += [
        f"μ = 1, a = 1, e = 0.5, i = 0.3, node 0.4, ω = 0.5, M = 0; J2 = 10⁻³ about z, R = 0.1; "
        f"{n} orbits from one double state. Reference: our Cartesian formulation in real128 at "
        f"tolerance {REF_TOL} ({ref.steps} steps"
        + (", cached" if ref.cached else "")
        + (
            f"); a second real128 run at {CHECK_TOL} stays within {fmt(float(ref.check.max()))} "
            "of it over the whole span (that bounds the looser run's error; the reference is "
            "tighter still)."
            if np.isfinite(ref.check).all()
            else "; its check against a second real128 run is not run in quick mode)."
        )
        + " |ΔE/E| is evaluated in long double from each method's own state "
        "(Cayley's r, ṙ, h; x, v otherwise), so it is not limited by the rounding of the energy "
        "formula. Exponents: slope of the running maximum against t over the last two decades "
        "(½ is Brouwer's random walk of round-off, 1 a drift; for the position 3/2 is the "
        "phase drift that a random walk of the energy causes, 1 a steady error of the mean "
        "motion). c = max |ΔE/E| / (ε √steps), ε = 2⁻⁵². Wall: least of "
        f"{1 if quick else 2} runs in one process on 2 shared cores: the ratios ÷ IAS15, not "
        "the seconds, are the result.",
        "",
    ]
    if "convention" in long:
        cv = long["convention"]
        lines += [
            "**J2 convention.** IAS15 + REBOUNDx (`gravitational_harmonics`, J2 and R_eq on the "
            f"central mass) against our real128 run over 10 orbits: {fmt(cv[1.0])} of a; with "
            f"REBOUNDx's J2 raised by 1 %, {fmt(cv[1.01])}. The two codes integrate one field.",
            "",
        ]
    lines += [
        "| method | settings | steps | wall s | ÷ IAS15 | final \\|Δx\\|/a | max \\|ΔE/E\\| "
        "| c | exponent ΔE | exponent Δx |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in runs:
        ratio = r.wall / ias.wall if ias else math.nan
        lines.append(
            f"| {r.method} | {r.settings} | {r.steps} | {r.wall:.2f} | {fmt(ratio)} | "
            f"{fmt(r.final)} | {fmt(r.max_energy)} | {fmt(brouwer(r.max_energy, r.steps))} | "
            f"{growth(t[1:], r.energy_err[1:]):.2f} | {growth(t[1:], r.pos_err[1:]):.2f} |"
        )
    if "quad" in long:
        q = long["quad"]
        lines.append(
            f"| ours, cartesian | real128, tol {CHECK_TOL} (the reference check) | "
            f"{ref.check_steps} | {100 * q['quad_wall_100']:.0f}\\* | "
            f"{fmt(q['quad_wall_100'] / q['ias15_wall_100'])} | {fmt(q['final'])} | < 1e-18 | "
            "– | – | – |"
        )
        lines += [
            "",
            "\\* real128: 100 × its wall over 100 orbits, measured next to IAS15's over the same "
            "100 orbits (the ratio is of those two).",
        ]
    lines += ["", f"![position and energy errors](figures/{names[0]})", ""]
    lines += ensemble_table(ens)
    lines += ["", f"![energy ensemble](figures/{names[1]})", ""]
    lines += conclusions(long, ens)
    return "\n".join(lines)


def ensemble_table(ens: dict[str, Any]) -> list[str]:
    stats = ens["stats"]
    t = ens["times"]
    base = stats.get("ias15")
    lines = [
        f"**Energy over an ensemble** ({ens['members']} starting mean anomalies 2πk/"
        f"{ens['members']}, {ens['n']} orbits each; one trajectory is one draw of the "
        "round-off walk). Exponent: of the median running maximum over the last two decades.",
        "",
        "| method | steps (mean) | wall ÷ IAS15 | median max \\|ΔE/E\\| | range | c | "
        "exponent ΔE |",
        "|---|---|---|---|---|---|---|",
    ]
    for key, s in stats.items():
        med = float(np.median(s["max"]))
        steps = float(np.mean(s["steps"]))
        ratio = s["wall"] / base["wall"] if base else math.nan
        lines.append(
            f"| {ENSEMBLE_LABELS.get(key, key)} | {steps:.0f} | {fmt(ratio)} | {fmt(med)} | "
            f"{fmt(min(s['max']))} – {fmt(max(s['max']))} | {fmt(brouwer(med, steps))} | "
            f"{growth(t[1:], s['median_env'][1:]):.2f} |"
        )
    return lines


def conclusions(long: dict[str, Any], ens: dict[str, Any]) -> list[str]:
    runs: list[Run] = long["runs"]
    ias = next((r for r in runs if r.group == "ias15"), None)
    if ias is None:
        return ["REBOUND or REBOUNDx is not installed: no IAS15 rows (pip install '.[bench]')."]
    better = [
        r
        for r in runs
        if r.group in ("ours", "prototype")
        and r.final <= ias.final
        and r.max_energy <= ias.max_energy
    ]
    out = [
        "**At IAS15's accuracy or better** over the long run (final |Δx|/a and max |ΔE/E| both "
        f"at most IAS15's {fmt(ias.final)} and {fmt(ias.max_energy)}), cheapest first:",
        "",
    ]
    for r in sorted(better, key=lambda r: r.wall):
        out.append(
            f"* {r.method} ({r.settings}): cost {fmt(r.wall / ias.wall)} × IAS15's; final error "
            f"{fmt(r.final / ias.final)} ×, max energy error {fmt(r.max_energy / ias.max_energy)}"
            " × IAS15's."
        )
    if not better:
        out.append("* none of the variants run here.")
    scene_only = [r for r in better if r.group == "ours"]
    out += [
        "",
        "Scene options alone: "
        + (
            ", ".join(f"{r.method} ({r.settings})" for r in scene_only)
            if scene_only
            else "none reaches both"
        )
        + ".",
    ]
    return out
