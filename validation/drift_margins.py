"""How much a drift envelope moves with the round-off alone, and how much a real worsening moves it.

The golden drift files (``tests/data/golden``, :mod:`cayley_heyoka.testing`) fail a window when
its drift exceeds ``factor × golden + floor``. Another CPU, compiler or LLVM version changes the
round-off of a run, not its size; this script stands in for one by moving every number of the
scene's initial state by k ε (k = 3, 6, …, 72: 24 other round-off realisations) and measures,
for every bundled scene with conserved monitors, the factor each window needed above the
floor. Then the same for changes that do worsen the integration: a tolerance of 1e-11 (1e-30
in quad) instead of the precision's epsilon.

    python validation/drift_margins.py        # ~2 min; writes the "drift_margins" section of
                                              # validation/REPORT.md and prints it
"""

from __future__ import annotations

import time
from fractions import Fraction
from pathlib import Path

import mpmath
import numpy as np
from report_sections import write_section

import cayley_heyoka as ch
from cayley_heyoka.testing import DRIFT_FACTOR, DRIFT_FLOOR, drift_envelope

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SHIFTS = range(3, 73, 3)
LOOSE = {"double": "1e-11", "quad": "1e-30"}


def nudged(value: object, k: int, eps: float) -> str:
    """``value · (1 + k ε)`` as decimal text (exact input, 45 digits)."""
    with mpmath.workdps(45):
        x = Fraction(str(value))
        return mpmath.nstr(mpmath.mpf(x.numerator) / x.denominator * (1 + k * mpmath.mpf(eps)), 45)


def perturb(data: object, k: int, eps: float) -> object:
    """Every number of the initial state moved by k ε (masses and constants untouched)."""
    if isinstance(data, dict):
        return {
            key: (value if key == "mass" else perturb(value, k, eps)) for key, value in data.items()
        }
    if isinstance(data, list):
        return [perturb(v, k, eps) for v in data]
    if isinstance(data, str | float | int) and not isinstance(data, bool):
        try:
            return nudged(data, k, eps) if Fraction(str(data)) != 0 else data
        except ValueError:
            return data
    return data


def scene_variant(name: str, k: int = 0, tolerance: str | None = None) -> ch.Scene:
    data = ch.load_scene(EXAMPLES / f"{name}.toml").to_dict()
    eps = ch.Precision.from_spec(data.get("integrator", {}).get("precision", "double")).epsilon
    if k:
        if "initial" in data:
            data["initial"] = perturb(data["initial"], k, eps)
        else:  # the predominant mass: the bodies' elements
            data["hamiltonian"]["bodies"] = perturb(data["hamiltonian"]["bodies"], k, eps)
    if tolerance:
        data.setdefault("integrator", {})["tolerance"] = tolerance
    return ch.Scene.from_dict(data)


def needed_factor(measured, golden) -> float:
    """The smallest factor with measured ≤ factor × golden + floor in every window."""
    worst = 0.0
    for name, peaks in measured.peaks.items():
        g = golden.peaks[name]
        over = peaks - DRIFT_FLOOR
        for m, gj in zip(over, g, strict=True):
            if m > 0:
                worst = max(worst, m / gj if gj > 0 else np.inf)
    return worst


def _factor(w: float) -> str:
    return "none suffices (a golden window at 0)" if np.isinf(w) else f"{w:.3g}"


def main() -> None:
    started = time.perf_counter()
    rows = []
    for path in sorted(EXAMPLES.glob("*.toml")):
        name = path.stem
        base = ch.run(scene_variant(name))
        if not base.conserved:
            continue
        golden = drift_envelope(base)
        windows = golden.windows
        factors = [
            needed_factor(drift_envelope(ch.run(scene_variant(name, k)), windows), golden)
            for k in SHIFTS
        ]
        loose = LOOSE[base.precision.kind]
        worse = needed_factor(
            drift_envelope(ch.run(scene_variant(name, tolerance=loose)), windows), golden
        )
        peak = max(float(np.max(p)) for p in golden.peaks.values())
        rows.append((name, base.precision.name, peak, max(factors), loose, worse))
        print(rows[-1], flush=True)
    lines = [
        "## Drift envelopes: round-off against a real worsening (`validation/drift_margins.py`)",
        "",
        "Factor each golden window needed above the floor of "
        f"{DRIFT_FLOOR:g} ε (default allowance {DRIFT_FACTOR:g} × golden + {DRIFT_FLOOR:g} ε): "
        f"worst over {len(SHIFTS)} re-runs with the initial state moved by 3–72 ε (another "
        "round-off realisation), and for a looser tolerance. 0 means no window rose above the "
        "floor.",
        "",
        "| scene | precision | largest golden drift (ε) | round-off: factor needed "
        "| looser tolerance | factor needed |",
        "|---|---|---|---|---|---|",
    ]
    lines += [
        f"| {n} | {p} | {peak:.1f} | {f:.2f} | {tol} | {_factor(w)} |"
        for n, p, peak, f, tol, w in rows
    ]
    lines += ["", f"Run time {time.perf_counter() - started:.0f} s."]
    body = "\n".join(lines)
    write_section(ROOT / "validation" / "REPORT.md", "drift_margins", body)
    print(body)


if __name__ == "__main__":
    main()
