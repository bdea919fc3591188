"""The round-off diagnostic: long high-order steps at 256 bits, five ways."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rotation_cases import BY_NAME, EPSILON

import cayley_heyoka as ch

from .laws import C_BROUWER
from .runs import to_mpf


def diagnose_roundoff(mode: str) -> dict[str, Any]:
    """Why a 256-bit run can exceed Brouwer's constant: truncation or round-off?

    The symmetric body takes ~2 steps per period at 256 bits (order 90), h|ω| ≈ 3. Re-run it
    with a tolerance below ε (truncation would shrink), with heyoka's compensated summation
    (``high_accuracy``), and with 320-bit arithmetic at the *same* tolerance 2⁻²⁵⁵ (same steps,
    less round-off). Drifts are in units of ε₂₅₆.
    """
    case = BY_NAME["symmetric"]
    periods = 2 if mode == "quick" else 10
    times = list(np.linspace(0.0, periods * 2 * np.pi, 41))
    cap = 1.0 / float(np.linalg.norm(case.rates))
    variants = [
        ("256 bits, tolerance auto (ε)", {"bits": 256}, "auto", False, "none"),
        ("256 bits, tolerance 1e-80 (ε/170)", {"bits": 256}, 1e-80, False, "none"),
        ("256 bits, tolerance auto, high_accuracy", {"bits": 256}, "auto", True, "none"),
        ("320 bits, tolerance 2⁻²⁵⁵ (same steps)", {"bits": 320}, 2.0**-255, False, "none"),
        ("256 bits, tolerance auto, max_step 1/|ω₀| (the fix)", {"bits": 256}, "auto", False, cap),
    ]
    rows = []
    eps = EPSILON["real256"]
    for label, spec, tol, ha, max_step in variants:
        data = case.scene("real256", times, events=False)
        data["integrator"].update(
            {"precision": spec, "tolerance": tol, "high_accuracy": ha, "max_step": max_step}
        )
        data["output"]["monitors"] = ["energy", "momentum_space", "orthogonality"]
        res = ch.run(ch.Scene.from_dict(data))
        n = res.counters["steps"]
        ms = max(float(to_mpf(x)) for x in np.abs(res.drift("momentum_space")).ravel())
        orth = max(float(to_mpf(x)) for x in res["orthogonality"])
        h = periods * 2 * np.pi / n
        rows.append(
            {
                "label": label,
                "steps": n,
                "order": res.metadata["order"],
                "h_omega": h * float(np.linalg.norm(case.rates)),
                "space_L": ms / eps,
                "orthogonality": orth / eps,
                "brouwer": C_BROUWER * math.sqrt(n),
            }
        )
    return {"kind": "diagnostic", "periods": periods, "rows": rows}
