"""Long-time conservation: Brouwer's law over 10⁸ steps in double, per formulation.

Run:  python validation/benchmarks.py --only conservation [--quick]

Round-off makes a conserved quantity random-walk: its relative drift grows like ε √n after n
steps (Brouwer's law, log–log slope ½). A bias — a rounding that leans the same way step after
step, or a truncation error that does not average out — adds a drift linear in n (slope 1),
which sooner or later dominates. Measured for the free rigid body (Rodrigues chart and
quaternion attitude: energy, |L|², the space components of L) and for a Kepler orbit (Cartesian,
Cayley's variables, the quaternion frame: energy and x × v), each with three estimates of the
slope:

* **ensemble**: the RMS over ``M`` runs nudged by 1…M ulps, against the step count, over the
  last two decades (the law is a statement about the ensemble);
* **windows**: from one long run, the RMS of the drift's increments over windows of a given
  length, against the length (N/1000 to N/10 steps) — disjoint stretches of one run are
  independent samples of the same walk, so this is an ensemble built from time;
* **running max** of the long run's |drift| over its last two decades (one walk: noisy).

Output times are log-spaced plus a uniform grid, through the scene's ``output.times``: the engine
records the state only there, so 10⁸ steps cost no more memory than 10³.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from bench_common import fmt

import cayley_heyoka as ch
from cayley_heyoka.rotation import attitude as att
from cayley_heyoka.rotation.charts import RodriguesAtlas

EPS = 2.0**-52
#: Steps of the long run per case in the full run.
LONG_STEPS = {
    ("free body", "quaternion"): 100_000_000,
    ("free body", "rodrigues"): 100_000_000,
    ("Kepler", "cartesian"): 100_000_000,
    ("Kepler", "cayley"): 100_000_000,
    ("Kepler", "quaternion"): 100_000_000,
}
FULL = {"members": 16, "ensemble_steps": 500_000, "diagnostic_steps": 10_000_000}
QUICK = {"members": 8, "ensemble_steps": 20_000, "long_steps": 100_000}
N_LOG, N_UNIFORM = 200, 1000
WINDOW_LAGS = (1, 2, 5, 10, 20, 50, 100)  # in uniform-grid intervals of N/1000 steps
#: A slope above these calls for a cause: ~2.5 standard deviations above ½ for an unbiased walk
#: (the scatter of each estimator is simulated on the same grids: :func:`estimator_scatter`).
FLAG = {"ensemble": 0.65, "windows": 0.6}


# ---------------------------------------------------------------------------- the cases
@dataclass(frozen=True)
class Case:
    """One system in one formulation, with the quantities it conserves."""

    system: str
    formulation: str

    @property
    def quantities(self) -> tuple[tuple[str, str], ...]:
        """(label, monitor) pairs; a vector monitor is measured by the norm of its change."""
        if self.system == "free body":
            return (
                ("energy", "energy"),
                ("|L|²", "momentum_squared"),
                ("L (space)", "momentum_space"),
            )
        return (("energy", "energy"), ("x × v", "angular_momentum"))

    @property
    def label(self) -> str:
        return f"{self.system}, {self.formulation}"

    def scene(self, times: list[float], nudge: int = 0) -> dict[str, Any]:
        """The scene on ``times``, its first number moved by ``nudge`` binary64 ulps."""
        monitors = [m for _, m in self.quantities]
        output = {"times": times, "monitors": monitors}
        if self.system == "free body":
            # The bundled free_body.toml: a generic asymmetric body near the major axis.
            return {
                "body": {"inertia": ["1", "1.5", "2.5"]},
                "initial": {
                    "rates": [_ulps(0.125, nudge), "0.25", "1"],
                    "rodrigues": ["0.1", "0.2", "-0.3"],
                },
                "attitude": {"formulation": self.formulation},
                "output": output,
            }
        # e = 0.5: the step size varies along the orbit (short at the pericentre).
        elements = {
            "a": _ulps(1.0, nudge),
            "e": "0.5",
            "inclination": "0.4",
            "node": "0.3",
            "argument_of_pericentre": "1.1",
            "mean_anomaly": "0.2",
        }
        return {
            "orbit": {"mu": "1", "elements": elements, "formulation": self.formulation},
            "output": output,
        }


CASES = tuple(Case(s, f) for s, f in LONG_STEPS)


def _ulps(x: float, k: int) -> float:
    for _ in range(k):
        x = float(np.nextafter(x, np.inf))
    return x


# ---------------------------------------------------------------------------- runs
@dataclass
class Run:
    """One integration: output times, steps, wall time (compile excluded), drifts."""

    t: np.ndarray
    steps: int
    seconds: float
    events: int
    drifts: dict[str, np.ndarray]  # per quantity label: |change| / |initial|, per output time

    @property
    def n(self) -> np.ndarray:
        """Steps up to each output time (steps are uniform in time once t spans a period)."""
        return self.steps * self.t / self.t[-1]


def execute(case: Case, times: list[float], nudge: int = 0) -> tuple[Run, dict[str, np.ndarray]]:
    """Run the case on ``times``; return the run and the signed drift of each quantity."""
    scene = ch.Scene.from_dict(case.scene(times, nudge))
    t0 = time.perf_counter()
    result = ch.run(scene)
    seconds = time.perf_counter() - t0 - result.metadata.get("compile_seconds", 0.0)
    signed = {label: result.drift(monitor) for label, monitor in case.quantities}
    norms = {
        k: np.sqrt(np.sum(d * d, axis=1)) if d.ndim == 2 else np.abs(d) for k, d in signed.items()
    }
    events = sum(v for k, v in result.counters.items() if k != "steps")
    t = np.array([float(x) for x in result.t])
    return Run(t, int(result.counters["steps"]), seconds, events, norms), signed


def integrate(case: Case, times: list[float], nudge: int = 0) -> Run:
    return execute(case, times, nudge)[0]


def step_rate(case: Case) -> float:
    """Steps per unit time, from a short run (also compiles, or loads from heyoka's cache)."""
    run = integrate(case, [0.0, 200.0])
    return run.steps / 200.0


def log_times(t_end: float, count: int, span: float) -> list[float]:
    """0 and ``count`` log-spaced binary64 times from t_end/span to t_end."""
    return [0.0, *sorted({float(x) for x in np.geomspace(t_end / span, t_end, count)})]


def long_times(t_end: float) -> list[float]:
    """Log-spaced times (for the growth curve) and a uniform grid (for the windows)."""
    uniform = [float(x) for x in np.linspace(0.0, t_end, N_UNIFORM + 1)]
    return sorted({*log_times(t_end, N_LOG, 1e6), *uniform})


# ---------------------------------------------------------------------------- fits
def slope(x: np.ndarray, y: np.ndarray) -> float:
    """Least-squares slope of log y against log x over the positive points (NaN if < 4)."""
    ok = (x > 0) & (y > 0) & np.isfinite(y)
    if np.count_nonzero(ok) < 4:
        return math.nan
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def running_max(y: np.ndarray) -> np.ndarray:
    return np.maximum.accumulate(np.where(np.isfinite(y), y, 0.0))


@dataclass
class Fits:
    """The slopes of one quantity of one case, and the numbers behind them."""

    ensemble: float
    windows: float
    running_max: float
    final: float
    worst: float  # max |drift| over the long run, in units of ε √N
    zero: bool  # exactly conserved to the last bit (nothing to fit)


def fit_case(case: Case, members: list[Run], long: Run, windows: dict[str, np.ndarray]) -> dict:
    out = {}
    t_end = members[0].t[-1]
    for label, _ in case.quantities:
        rms = np.sqrt(np.mean([m.drifts[label] ** 2 for m in members], axis=0))
        n_ens = np.mean([m.n for m in members], axis=0)
        tail = members[0].t >= t_end / 100
        env = running_max(long.drifts[label])
        late = long.t >= long.t[-1] / 100
        lags = np.array(WINDOW_LAGS, float) * long.steps / N_UNIFORM
        zero = not np.any(env > 0) and not np.any(rms > 0)
        out[label] = Fits(
            ensemble=slope(n_ens[tail], rms[tail]),
            windows=slope(lags, windows[label]),
            running_max=slope(long.n[late], env[late]),
            final=float(long.drifts[label][-1]),
            worst=float(env[-1] / (EPS * math.sqrt(long.steps))),
            zero=zero,
        )
    return out


def signed_windows(drifts: dict[str, np.ndarray], t: np.ndarray) -> dict[str, np.ndarray]:
    """RMS of the drift's change over windows of ``WINDOW_LAGS`` uniform intervals (the
    uniform grid of :func:`long_times`; vectors: the norm of the change)."""
    idx = np.searchsorted(t, np.linspace(0.0, t[-1], N_UNIFORM + 1))
    out = {}
    for label, d in drifts.items():
        d = d[idx]
        d = d if d.ndim == 2 else d[:, None]
        out[label] = np.array(
            [math.sqrt(np.mean(np.sum((d[k:] - d[:-k]) ** 2, axis=1))) for k in WINDOW_LAGS]
        )
    return out


def integrate_long(case: Case, t_end: float) -> tuple[Run, dict[str, np.ndarray]]:
    """The long run and its window RMS (which needs the signed drifts, not their norms)."""
    run, signed = execute(case, long_times(t_end))
    return run, signed_windows(signed, run.t)


# ---------------------------------------------------------------------------- the old fold
@contextlib.contextmanager
def legacy_fold() -> Iterator[None]:
    """Fold Rodrigues charts as before the fix: through the unit quaternion of the chart.

    Its w = 1/√κ is computed at κ = κ_max at every fold, so it rounds alike every time: kept
    here only to measure what that bias did (the library folds (1, λ, μ, ν) unnormalised).
    """
    fixed = RodriguesAtlas.rebase

    def rebase(self: RodriguesAtlas, ta: Any, pars: np.ndarray) -> None:
        rho = list(ta.state[self.state_slice])
        base = pars[self._base_index : self._base_index + 4]
        new = np.array(att.quaternion_multiply(list(base), att.rodrigues_to_quaternion(rho)))
        new = new / np.sqrt(np.sum(new * new))
        pars[self._base_index : self._base_index + 4] = new
        ta.state[self.state_slice] = 0 * new[:3]

    RodriguesAtlas.rebase = rebase
    try:
        yield
    finally:
        RodriguesAtlas.rebase = fixed


# ---------------------------------------------------------------------------- plots
def plot(system: str, cases: list[Case], data: dict, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.6), constrained_layout=True)
    colours = iter(plt.rcParams["axes.prop_cycle"].by_key()["color"] * 3)
    n_max = 1.0
    for case in cases:
        d = data[case]
        long, members, windows = d["long"], d["members"], d["windows"]
        n_max = max(n_max, long.steps)
        for label, _ in case.quantities:
            if d["fits"][label].zero:
                continue
            c = next(colours)
            name = f"{case.formulation}: {label}"
            keep = long.t > 0
            left.loglog(long.n[keep], running_max(long.drifts[label])[keep], "-", c=c, label=name)
            rms = np.sqrt(np.mean([m.drifts[label] ** 2 for m in members], axis=0))
            n_ens = np.mean([m.n for m in members], axis=0)
            keep = n_ens > 0
            right.loglog(n_ens[keep], rms[keep], "-", c=c, label=f"{name} (ensemble)")
            lags = np.array(WINDOW_LAGS, float) * long.steps / N_UNIFORM
            right.loglog(lags, windows[label], "o--", c=c, ms=3, lw=0.7)
    for ax in (left, right):
        n = np.geomspace(10, n_max, 50)
        ax.loglog(n, EPS * np.sqrt(n), "k:", lw=1, label="ε √n")
        ax.grid(True, which="both", alpha=0.25)
        ax.set_xlabel("steps n")
    left.set_title(f"{system}: one long run, running max of |drift|")
    left.set_ylabel("relative drift")
    right.set_title(f"{system}: ensemble RMS (lines), window RMS of one run (dots)")
    left.legend(fontsize=7)
    right.legend(fontsize=7)
    fig.savefig(out, dpi=90)
    plt.close(fig)


# ---------------------------------------------------------------------------- the section
def run(quick: bool, figures: Path) -> str:
    """Measure every case; return the Markdown of the section (plots into ``figures``)."""
    cfg = QUICK if quick else FULL
    wall0 = time.perf_counter()
    data: dict[Case, dict] = {}
    for case in CASES:
        rate = step_rate(case)
        n_ens = cfg["ensemble_steps"]
        t_ens = n_ens / rate
        members = [
            integrate(case, log_times(t_ens, 60, 1e4), nudge=k)
            for k in range(1, cfg["members"] + 1)
        ]
        n_long = cfg["long_steps"] if quick else LONG_STEPS[(case.system, case.formulation)]
        # 1 % over, so that the run reaches its nominal step count despite the rate's scatter.
        long, windows = integrate_long(case, 1.01 * n_long / rate)
        data[case] = {
            "members": members,
            "long": long,
            "windows": windows,
            "fits": fit_case(case, members, long, windows),
        }
        print(f"  conservation: {case.label}: {long.steps} steps, {long.seconds:.1f} s", flush=True)

    diagnostic = None if quick else diagnose_fold(data, cfg["diagnostic_steps"])
    for system in ("free body", "Kepler"):
        cases = [c for c in CASES if c.system == system]
        plot(system, cases, data, figures / f"bench_cons_{system.replace(' ', '_').lower()}.png")
    return section(data, cfg, diagnostic, quick, time.perf_counter() - wall0)


def diagnose_fold(data: dict, steps: int) -> dict[str, Any]:
    """The Rodrigues chart with the fold as it was, against the fixed fold at equal steps."""
    case = Case("free body", "rodrigues")
    fixed = data[case]["long"]
    rate = fixed.steps / fixed.t[-1]
    # The handler is bound when the model is built, not compiled: the cached integrator serves.
    with legacy_fold():
        old, windows = integrate_long(case, steps / rate)
    members = data[case]["members"]
    fits = fit_case(case, members, old, windows)
    at = np.searchsorted(fixed.n, old.steps)
    return {
        "steps": old.steps,
        "legacy": {k: (float(old.drifts[k][-1]), fits[k]) for k, _ in case.quantities},
        "fixed": {k: float(running_max(fixed.drifts[k])[at]) for k, _ in case.quantities},
        "legacy_max": {k: float(running_max(old.drifts[k])[-1]) for k, _ in case.quantities},
        "rebasings": old.events,
    }


def estimator_scatter(members: int, reps: int = 1000) -> dict[str, tuple[float, float]]:
    """Mean and standard deviation of each slope estimate for an unbiased random walk.

    The walks are sampled on the grids the measurements use (the ensemble's 60 log-spaced
    times, the long run's log-spaced and uniform times), so the numbers are the scatter to
    expect from the estimators alone, before any property of the integrator.
    """
    rng = np.random.default_rng(1)
    n_long = 1e8
    t = np.array(long_times(n_long))
    late = t >= n_long / 100
    grid = np.searchsorted(t, np.linspace(0.0, n_long, N_UNIFORM + 1))
    lags = np.array(WINDOW_LAGS, float)
    te = np.array(log_times(1.0, 60, 1e4))
    tail = te >= 1e-2
    out: dict[str, list[float]] = {"ensemble": [], "windows": [], "running max": []}
    for _ in range(reps):
        w = np.concatenate([[0.0], np.cumsum(rng.normal(size=len(t) - 1) * np.sqrt(np.diff(t)))])
        out["running max"].append(slope(t[late], running_max(np.abs(w))[late]))
        d = w[grid]
        rms = [math.sqrt(np.mean((d[k:] - d[:-k]) ** 2)) for k in WINDOW_LAGS]
        out["windows"].append(slope(lags, np.array(rms)))
        steps = rng.normal(size=(members, len(te) - 1)) * np.sqrt(np.diff(te))
        walks = np.concatenate([np.zeros((members, 1)), np.cumsum(steps, axis=1)], axis=1)
        ens = np.sqrt(np.mean(walks**2, axis=0))
        out["ensemble"].append(slope(te[tail], ens[tail]))
    return {k: (float(np.mean(v)), float(np.std(v))) for k, v in out.items()}


def _cell(text: str) -> str:
    """Text for a Markdown table cell (|L|² would split the cell)."""
    return text.replace("|", "\\|")


def _slope(x: float, flag: float | None = None) -> str:
    if not math.isfinite(x):
        return "–"
    mark = " ⚠" if flag is not None and x > flag else ""
    return f"{x:.2f}{mark}"


def section(data: dict, cfg: dict, diagnostic: dict | None, quick: bool, seconds: float) -> str:
    members = cfg["members"]
    n_ens = cfg["ensemble_steps"]
    noise = estimator_scatter(members, 200 if quick else 1000)
    spread = ", ".join(f"{k} {m:.2f} ± {sd:.2f}" for k, (m, sd) in noise.items())
    lines = [
        "## Long-time conservation (Brouwer's law)",
        "",
        f"Double precision, tolerance ε = 2⁻⁵², every run through `cayley_heyoka.run`. Slopes of "
        f"log |drift| against log n: **ensemble** = RMS over {members} runs nudged by 1…{members} "
        f"ulps (the free body's p, the orbit's a), each {n_ens:.0e} steps, fitted over the last "
        "two decades; **windows** = RMS of the drift's change over windows of N/1000 to N/10 steps "
        "of the long run (stretches of one walk are independent samples of it); **running max** "
        "= the long run's largest |drift| so far, over its last two decades. Brouwer's law is "
        "slope ½, a bias shows as slope 1. For an unbiased walk sampled on the same grids the "
        f"three estimates scatter as {spread} (simulated): ⚠ marks an ensemble slope above "
        f"{FLAG['ensemble']} or a windows slope above {FLAG['windows']}, ~2.5 σ; the running max "
        "of one walk is shown, not judged. Drifts are relative (vectors: |ΔL|/|L(0)|); "
        "max / (ε√N) is the long run's largest drift in units of ε√N.",
        "",
        "| system | formulation | quantity | long run N | drift at N | max / (ε√N) | ensemble "
        "| windows | running max |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for case, d in data.items():
        long = d["long"]
        for label, _ in case.quantities:
            f: Fits = d["fits"][label]
            if f.zero:
                row = ["0 (exact)", "0", "–", "–", "–"]
            else:
                row = [
                    fmt(f.final),
                    f"{f.worst:.2f}",
                    _slope(f.ensemble, FLAG["ensemble"]),
                    _slope(f.windows, FLAG["windows"]),
                    _slope(f.running_max),
                ]
            lines.append(
                f"| {case.system} | {case.formulation} | {_cell(label)} | {long.steps:.3g} | "
                + " | ".join(row)
                + " |"
            )
    lines += ["", "![free body](figures/bench_cons_free_body.png)", ""]
    lines += ["![Kepler](figures/bench_cons_kepler.png)", ""]
    lines += cost_table(data)
    lines += findings(data, diagnostic, quick)
    return "\n".join(lines)


def cost_table(data: dict) -> list[str]:
    lines = [
        "Cost of the long runs (a side effect: wall time of `run()` without compilation, "
        "recording included; the machine is shared, so ±30 %). Events are re-basings of the "
        "Rodrigues chart or revolutions of ρ, each handled by a Python callback inside "
        "heyoka's call (the revolution's handler works in the run's arithmetic: "
        "`python validation/users_orbit.py` measures its share).",
        "",
        "| system | formulation | steps | events | wall | ns/step |",
        "|---|---|---|---|---|---|",
    ]
    for case, d in data.items():
        long = d["long"]
        lines.append(
            f"| {case.system} | {case.formulation} | {long.steps:.3g} | {long.events:.3g} | "
            f"{long.seconds:.3g} s | {1e9 * long.seconds / long.steps:.0f} |"
        )
    return [*lines, ""]


def findings(data: dict, diagnostic: dict | None, quick: bool) -> list[str]:
    flagged = [
        f"{case.label}: {label}"
        for case, d in data.items()
        for label, f in d["fits"].items()
        if not f.zero and (f.ensemble > FLAG["ensemble"] or f.windows > FLAG["windows"])
    ]
    lines = ["### What the slopes say", ""]
    if flagged:
        lines.append(
            "* Flagged (⚠): "
            + "; ".join(flagged)
            + "."
            + (" A quick run spans too few steps to judge." if quick else "")
        )
    else:
        lines.append(
            "* Nothing flagged: every conserved quantity of every formulation random-walks "
            "(Brouwer's law), none drifts."
        )
    lines.append(
        "* **Found and fixed: a biased fold of the Rodrigues chart.** Before the fix the space "
        "components of L drifted linearly (slope 0.95–1.04 from one run of 10⁷ steps, "
        "2.4 ε√n at its end) while energy and |L|² — functions of the rates, which the fold "
        "does not touch — walked. The drift did not move with the tolerance (ε or 1e-18) nor "
        "with `high_accuracy` (so neither truncation nor the evaluation of the Taylor "
        "polynomials), and it grew with the number of re-basings (a 90° chart: 1.8× the folds, "
        "1.8× the drift). The fold composed the base with the chart's *unit* quaternion, whose "
        "w = 1/√κ is computed at κ = κ_max at every fold and so rounds alike every time: "
        "+0.11 ε of rotation angle per fold, summed over millions of folds. "
        "`RodriguesAtlas.rebase` now composes (1, λ, μ, ν) unnormalised and normalises once (a "
        "common factor rotates nothing); `tests/rotation/test_charts.py` checks over 3000 folds "
        "that the mean angle error is below 0.035 ε (it was 0.11 ε)."
    )
    if diagnostic:
        label = "L (space)"
        _, f = diagnostic["legacy"][label]
        lines += [
            "",
            f"  Re-run here with the old fold for {diagnostic['steps']:.3g} steps "
            f"({diagnostic['rebasings']:.3g} re-basings): largest |ΔL|/|L| "
            f"{fmt(diagnostic['legacy_max'][label])} against "
            f"{fmt(diagnostic['fixed'][label])} for the fixed fold's long run at the same step "
            f"count; windows slope {_slope(f.windows, FLAG['windows'])}, running max "
            f"{_slope(f.running_max)}.",
            "",
        ]
    lines.append(
        "* **Found and fixed: output times perturbed runs with terminal events** (chart "
        "re-basings, revolutions of ρ). After each event the engine reached the next output "
        "time with `propagate_until`, which ends a step there: every output after an event was "
        "a rounding kick, and cost a `propagate_grid` over the whole remaining grid. Measured "
        "while diagnosing: Kepler in Cayley's variables over 10⁷ steps, energy drift (RMS of 4 "
        "runs) 2.5e-15 with 10 outputs, 3.0e-14 with 10³, 1.9e-13 with 10⁴ — its walk counted "
        "outputs, not steps; the Rodrigues free body over 10⁶ steps took 1.8 s with 100 outputs "
        "and 37 s with 50 000. `engine.run` now makes one `propagate_grid` call over the whole "
        "grid and handles terminal events inside it (heyoka's event callbacks): outputs come "
        "from dense output, the step count and the last state are the same for any grid "
        "(`tests/rotation/test_engine.py::test_output_times_do_not_perturb_a_run_with_terminal_"
        "events`). One side effect: with sparse outputs the old "
        "path kept pure Kepler's radial pair (r, ṙ) on an exact floating-point cycle of one "
        "orbit (34 steps, the same bits at every revolution): its energy stayed within ~10 ε "
        "over 10⁷ steps; "
        "heyoka's grid propagation places terminal events a few ulps differently, and the pair "
        "now walks by Brouwer's law like any other state (any perturbation breaks such cycles "
        "anyway)."
    )
    lines += [
        "* Not causes here: time is not an argument of these autonomous systems (heyoka's "
        "double-length time only matters for the phase); the output grid is given as a list, "
        "each time a binary64 number taken as it is; the engine copies states and parameters "
        "without conversion in double. Lowering the tolerance to 1e-18 changes heyoka's order "
        "(20 → 22), not its steps (set by the radius of convergence), so it is the test for "
        "truncation; with it, or with `high_accuracy`, the old fold drifted alike.",
        "* Kepler in Cayley's variables and in the quaternion frame: h, Θ, Σ, Φ (or the frame "
        "quaternion) have zero derivatives, so x × v = h n̂ is conserved to the last bit; the "
        "energy rests on (r, ṙ) alone.",
        "* The free body's energy and |L|² depend on the rates alone, which Euler's equations "
        "integrate alike in both attitude formulations; they differ only through the step "
        "sizes (the Rodrigues chart's pole shortens its steps).",
    ]
    return lines
