"""The verdicts: each run's measured quantities judged against the laws' tolerances."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .laws import FIT_SLACK


def verdict(ok: bool) -> str:
    return "PASS" if ok else "**FAIL**"


def worst(err: np.ndarray, tol: np.ndarray, t: np.ndarray) -> tuple[float, float, float, float]:
    """(max error, its time, the tolerance there, max err/tol ratio) over finite points."""
    ok = np.isfinite(err)
    if not np.any(ok):
        return math.nan, math.nan, math.nan, math.inf
    i = int(np.argmax(np.where(ok, err, -1)))
    ratio = np.where(ok, err / tol, 0)
    return float(err[i]), float(t[i]), float(tol[i]), float(np.max(ratio))


def quantity_rows(job: dict[str, Any]) -> list[dict[str, Any]]:
    """One judged row per measured quantity of a run."""
    t = job["t"]
    e, d = job["errors"], job["drifts"]
    out = []
    pairs = [
        ("rates (p,q,r)/|ω₀|", e["state"], job["tol_state"], "phase law"),
        ("attitude (quaternion)", e["attitude"], job["tol_attitude"], "phase law"),
        ("energy drift", d["energy"], job["tol_conserved"], "Brouwer"),
        ("|L|² drift", d["momentum_squared"], job["tol_conserved"], "Brouwer"),
        ("space L drift", d["momentum_space"], job["tol_conserved"], "Brouwer"),
    ]
    for label, err, tol, law in pairs:
        value, at, tol_at, ratio = worst(err, tol, t)
        reference_ok = not (label.startswith(("rates", "attitude")) and e["reference_failures"])
        out.append(
            {
                "quantity": label,
                "value": value,
                "at": at,
                "tol": tol_at,
                "tol_end": float(tol[-1]),
                "ratio": ratio,
                "law": law,
                "pass": ratio <= 1 and reference_ok,
            }
        )
    c = job["crossings"]
    if c["n_ref"]:
        ratio = float(np.max(c["abs"] / c["tol"])) if len(c["abs"]) else 0.0
        i = int(np.argmax(c["abs"])) if len(c["abs"]) else None
        out.append(
            {
                "quantity": "crossing times |Δt|",
                "value": float(c["abs"][i]) if i is not None else math.nan,
                "at": float(c["t"][i]) if i is not None else math.nan,
                "tol": float(c["tol"][i]) if i is not None else math.nan,
                "tol_end": float(c["tol"][-1]) if len(c["tol"]) else math.nan,
                "ratio": ratio,
                "law": "phase law",
                "pass": ratio <= 1
                and c["misses"] == 0
                and c["extras"] == 0
                and c["direction_mismatches"] == 0,
            }
        )
    return out


def fit_rows(job: dict[str, Any]) -> list[dict[str, Any]]:
    """Fitted growth exponents, judged against the law's 1/2 and 3/2."""
    expected = {"state": 1.5, "attitude": 1.5, "energy": 0.5, "momentum_squared": 0.5}
    rows = []
    for k, slope in job["fits"].items():
        if math.isnan(slope):
            continue
        rows.append(
            {
                "quantity": k,
                "slope": slope,
                "law": expected[k],
                "pass": slope <= expected[k] + FIT_SLACK,
            }
        )
    return rows


def sci(x: Any) -> str:
    """``x`` as a float in the tables' 1.2e-34 notation ("nan" for NaN)."""
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.1e}"
