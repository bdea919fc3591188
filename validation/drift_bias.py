"""Is the round-off drift a random walk, or does part of it lean one way? (issue 20)

Run:  python validation/drift_bias.py [--steps 1e7] [--members 64]
      python validation/drift_bias.py --settings [--steps 1e7]   (which settings reach the law)
      python validation/drift_bias.py --cost [--steps 1e6]       (what the division costs)

Brouwer's law: round-off makes a conserved quantity random-walk, RMS ε √N after N steps, and
runs a few ulps apart walk independently. A bias — a rounding that leans the same way step after
step — is *shared*: every member of the ensemble drifts alike. So each configuration here is an
ensemble (members whose initial p differs by 1e-9 relative), and the table gives, for the
energy T and |L|² of the generic body of validation/rotation_cases.py (moments 1, 2, 3), after
N steps: the RMS drift over the members in units of ε √N, the exponent of the RMS against the
step count over the last two decades (½ for a walk), and the shared fraction |mean| / RMS
(about 1/√members for independent walks, 1 for a deterministic drift). The drifts are
evaluated exactly (rational arithmetic on the double states), so the monitors' own rounding
plays no part.

Configurations: the package's quaternion and Rodrigues formulations, as ``cayley_heyoka.run``
compiles them (Euler's equations as ``((B − C) q r) / A``); and, written directly in heyoka for
comparison, the form the package compiled before issue 20, ``((B − C)/A) q r`` with the
quotient rounded once — with the quaternion attitude, and Euler's equations alone.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import time
from collections.abc import Callable
from fractions import Fraction

import heyoka as hy
import numpy as np
from rotation_cases import BY_NAME

import cayley_heyoka as ch

EPS = 2.0**-52
CASE = BY_NAME["generic"]
GRID_POINTS = 60


def log_grid(t_end: float) -> list[float]:
    """0 and log-spaced times over four decades up to ``t_end`` (binary64, increasing)."""
    return [0.0, *sorted({float(x) for x in np.geomspace(t_end / 1e4, t_end, GRID_POINTS)})]


def exact_drifts(states: np.ndarray) -> dict[str, np.ndarray]:
    """Relative drift of T and |L|² along rows (p, q, r, ...), in rational arithmetic."""
    A, B, C = (Fraction(x) for x in CASE.inertia)
    rows = [tuple(Fraction(float(x)) for x in s[:3]) for s in states]
    energy = [(A * p * p + B * q * q + C * r * r) / 2 for p, q, r in rows]
    momentum = [(A * p) ** 2 + (B * q) ** 2 + (C * r) ** 2 for p, q, r in rows]
    return {
        name: np.array([float((v - values[0]) / values[0]) for v in values])
        for name, values in (("energy", energy), ("|L|²", momentum))
    }


def member_rates(k: int) -> tuple[float, float, float]:
    p, q, r = CASE.rates
    return (p * (1 + k * 1e-9), q, r)


# ------------------------------------------------------------------ the package
def package(formulation: str) -> Callable[[int, list[float]], tuple[np.ndarray, int]]:
    def run(k: int, grid: list[float]) -> tuple[np.ndarray, int]:
        body = dataclasses.replace(CASE, rates=member_rates(k))
        scene = body.scene("double", grid, events=False, formulation=formulation)
        result = ch.run(ch.Scene.from_dict(scene))
        states = np.column_stack([np.asarray(result[n], dtype=float) for n in "pqr"])
        return states, result.counters["steps"]

    return run


# ------------------------------------------------------------------ the form before issue 20
def rounded_quotient(attitude: bool) -> Callable[[int, list[float]], tuple[np.ndarray, int]]:
    A, B, C = (Fraction(x) for x in CASE.inertia)
    quotients = [float((B - C) / A), float((C - A) / B), float((A - B) / C)]
    p, q, r = hy.make_vars("p", "q", "r")
    system = [
        (p, hy.par[0] * q * r),
        (q, hy.par[1] * r * p),
        (r, hy.par[2] * p * q),
    ]
    if attitude:
        w, x, y, z = hy.make_vars("qw", "qx", "qy", "qz")
        system += [
            (w, 0.5 * (-(x * p) - y * q - z * r)),
            (x, 0.5 * (w * p + y * r - z * q)),
            (y, 0.5 * (w * q - x * r + z * p)),
            (z, 0.5 * (w * r + x * q - y * p)),
        ]
    ta = hy.taylor_adaptive(system, [0.0] * len(system), pars=quotients)

    def run(k: int, grid: list[float]) -> tuple[np.ndarray, int]:
        ta.state[:] = [*member_rates(k), *([1.0, 0.0, 0.0, 0.0] if attitude else [])]
        ta.time = 0.0
        out = ta.propagate_grid(grid)
        return out[-1], out[3]

    return run


CONFIGS = {
    "package, quaternion": package("quaternion"),
    "package, Rodrigues": package("rodrigues"),
    "rounded quotient, quaternion": rounded_quotient(attitude=True),
    "rounded quotient, Euler alone": rounded_quotient(attitude=False),
}


def measure(run: Callable, steps: float, members: int) -> dict[str, dict[str, float]]:
    """The ensemble's figures for T and |L|² after about ``steps`` steps."""
    _, probe_steps = run(0, [0.0, 1000.0])
    t_end = steps * 1000.0 / probe_steps
    grid = log_grid(t_end)
    drifts: dict[str, list[np.ndarray]] = {"energy": [], "|L|²": []}
    counts = []
    for k in range(1, members + 1):
        states, n = run(k, grid)
        counts.append(n)
        for name, d in exact_drifts(states).items():
            drifts[name].append(d)
    N = float(np.mean(counts))
    n = N * np.array(grid) / grid[-1]
    tail = n >= N / 100
    out = {}
    for name, rows in drifts.items():
        d = np.array(rows)
        rms = np.sqrt(np.mean(d**2, axis=0))
        mean = np.mean(d, axis=0)
        slope = np.polyfit(np.log(n[tail]), np.log(rms[tail]), 1)[0]
        out[name] = {
            "N": N,
            "rms": float(rms[-1] / (EPS * math.sqrt(N))),
            "exponent": float(slope),
            "shared": float(abs(mean[-1]) / rms[-1]),
            "shared_tail": float(np.median(np.abs(mean[tail]) / rms[tail])),
        }
    return out


def cost(steps: float, repeats: int = 5) -> list[tuple[str, float, float]]:
    """What the division costs, as users run it: a whole ``cayley_heyoka.run()`` of about
    ``steps`` steps against raw heyoka integrating the rounded-quotient form over the same
    span, interleaved; returns (attitude, median seconds ours, median seconds raw heyoka)."""
    rows = []
    body = dataclasses.replace(CASE, rates=member_rates(0))
    for formulation, attitude in (("quaternion", True), ("none", False)):

        def scene(t_end: float, formulation: str = formulation) -> ch.Scene:
            data = body.scene("double", [0.0, t_end], False, formulation)
            if formulation == "none":  # the rates alone: no attitude, no space vector
                data["output"]["monitors"] = ["energy", "momentum_squared"]
            return ch.Scene.from_dict(data)

        t_end = steps * 1000.0 / ch.run(scene(1000.0)).counters["steps"]
        raw = rounded_quotient(attitude)
        ours_s, raw_s = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            ch.run(scene(t_end))
            ours_s.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            raw(0, [0.0, t_end])
            raw_s.append(time.perf_counter() - t0)
        rows.append((formulation, float(np.median(ours_s)), float(np.median(raw_s))))
    return rows


#: Integrator settings beside the defaults (tolerance ε, no step cap), for ``--settings``.
SETTINGS = {
    "defaults (tolerance ε)": (),
    "high_accuracy": (("high_accuracy", True),),
    "tolerance 1e-18 (order 22)": (("tolerance", "1e-18"),),
    "max_step 0.18 (the Rodrigues chart's step)": (("max_step", 0.18),),
    "tolerance 1e-12": (("tolerance", "1e-12"),),
    "tolerance 1e-9": (("tolerance", "1e-9"),),
}


def settings_table(steps: float, members: int, bodies: tuple[str, ...] = ("generic",)) -> list[str]:
    """``bodies`` (validation/rotation_cases.py names) under each of ``SETTINGS``, both attitude
    formulations, through bench_conservation's ensembles (the sweeps' batch lanes): which
    settings random-walk."""
    import bench_conservation as bc

    cases = [
        bc.Case("free body", formulation, body, members, steps, settings)
        for body in bodies
        for settings in SETTINGS.values()
        for formulation in ("quaternion", "rodrigues")
    ]
    data = bc.measure(cases)
    floor = bc.estimator_scatter(members, 300)
    names = {v: k for k, v in SETTINGS.items()}
    rows = [
        "| body | settings | attitude | quantity | N | RMS / (ε√N) | exponent | shared (median) | "
        "windows | windows shared |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for case, ens in data.items():
        for label in ("energy", "|L|²"):
            f = bc.fit(ens, label)
            marks = bc.flagged(f, floor)
            cells = [
                bc._num(f.rms),
                bc._num(f.exponent, "ensemble" in marks),
                bc._num(f.shared_tail, "shared" in marks),
                bc._num(f.windows, "windows" in marks),
                bc._num(f.windows_shared, "windows shared" in marks),
            ]
            head = [case.body, names[case.settings], case.formulation, bc._cell(label)]
            rows.append("| " + " | ".join([*head, f"{np.mean(ens.steps):.3g}", *cells]) + " |")
    rows.append(
        f"\n{members} members 1e-9 apart; for independent walks the median shared fraction stays "
        f"≤ {floor['shared'][0]:.2f} and the windows shared ≤ {floor['windows_shared'][0]:.2f} "
        f"(99 %), the exponents {floor['ensemble'][0]:.2f} ± {floor['ensemble'][1]:.2f} and "
        f"{floor['windows'][0]:.2f} ± {floor['windows'][1]:.2f}; ⚠ as in validation/BENCHMARKS.md."
    )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, default=1e6, help="steps per member (1e6)")
    parser.add_argument("--members", type=int, default=32, help="ensemble size (32)")
    parser.add_argument(
        "--cost", action="store_true", help="time the division form against raw heyoka instead"
    )
    parser.add_argument(
        "--settings", action="store_true", help="the package's form under integrator settings"
    )
    parser.add_argument(
        "--bodies",
        nargs="+",
        default=["generic"],
        help="with --settings: validation/rotation_cases.py bodies (generic)",
    )
    args = parser.parse_args()
    if args.settings:
        print("\n".join(settings_table(args.steps, min(args.members, 16), tuple(args.bodies))))
        return
    if args.cost:
        print(
            "| attitude | cayley_heyoka.run(), division (s) | raw heyoka, rounded quotient (s) "
            "| ratio |\n|---|---|---|---|"
        )
        for formulation, ours, raw in cost(args.steps):
            print(f"| {formulation} | {ours:.3f} | {raw:.3f} | {ours / raw:.2f} |")
        return
    print(
        f"generic body (moments 1, 2, 3; rates {CASE.rates}), {args.members} members 1e-9 "
        f"apart, about {args.steps:.0e} steps each; drifts evaluated exactly\n"
    )
    print(
        "| configuration | quantity | N | RMS / (ε√N) | exponent | shared at N | shared, "
        "median over the last two decades |"
    )
    print("|---|---|---|---|---|---|---|")
    for label, run in CONFIGS.items():
        t0 = time.perf_counter()
        figures = measure(run, args.steps, args.members)
        for name, f in figures.items():
            print(
                f"| {label} | {name} | {f['N']:.3g} | {f['rms']:.2f} | {f['exponent']:.2f} | "
                f"{f['shared']:.2f} | {f['shared_tail']:.2f} |",
                flush=True,
            )
        print(f"<!-- {label}: {time.perf_counter() - t0:.0f} s -->", flush=True)
    print(
        f"\nIndependent walks give a shared fraction of about {1 / math.sqrt(args.members):.2f} "
        f"(1/√members); a drift every member shares gives 1."
    )


if __name__ == "__main__":
    main()
