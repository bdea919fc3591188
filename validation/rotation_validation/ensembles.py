"""The growth-law ensembles: runs a few ulps apart, and the RMS fit of their errors."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rotation_cases import BY_NAME, nudged

from cayley_heyoka.reference import FreeRigidBody

from .laws import ENSEMBLE_LAW, N_TIMES
from .runs import conserved_drifts, integrate, output_times, state_errors


def ensemble_member(name: str, precision: str, periods: float, ulps: int, mode: str) -> dict:
    """One member of a growth-law ensemble: the case nudged by ``ulps``, against its own
    closed form, on the unperturbed case's output grid."""
    base = BY_NAME[name]
    member = nudged(base, ulps)
    period = float(FreeRigidBody(base.inertia, base.rates, attitude=(1, 0, 0, 0), dps=20).period)
    count = N_TIMES["quick" if mode == "quick" else "long"]
    times = output_times(period, periods * period, count)
    result, steps = integrate(member, precision, times, events=False)
    t = np.array([float(x) for x in result.t])
    errs = state_errors(member, precision, result)
    drifts = conserved_drifts(result)
    return {
        "kind": "ensemble",
        "key": (name, precision, periods),
        "period": period,
        "t": t,
        "n": np.searchsorted(steps, t, side="right").astype(float),
        "state": errs["state"],
        "attitude": errs["attitude"],
        "energy": drifts["energy"],
        "momentum_squared": drifts["momentum_squared"],
    }


def ensemble_fits(members: list[dict]) -> dict[str, Any]:
    """RMS over the members at each output time and its log-log slope against the steps."""
    t, period = members[0]["t"], members[0]["period"]
    n = np.mean([m["n"] for m in members], axis=0)
    mask = t >= max(period, t[-1] / 100)
    out: dict[str, Any] = {"t": t, "n": n, "members": len(members), "rms": {}, "slope": {}}
    for k in ENSEMBLE_LAW:
        rms = np.sqrt(np.nanmean([m[k] ** 2 for m in members], axis=0))
        ok = mask & (rms > 0) & (n > 0)
        out["rms"][k] = rms
        out["slope"][k] = (
            float(np.polyfit(np.log(n[ok]), np.log(rms[ok]), 1)[0])
            if np.count_nonzero(ok) >= 5
            else math.nan
        )
    return out
