"""The error measures, and the closed form the torque-free cases are measured against."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mpmath
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.reference import FreeRigidBody


def exact_mpf(x: Any) -> mpmath.mpf:
    """A double, real128 or real exactly as an mpf (their text round-trips)."""
    if isinstance(x, float | np.floating | int):
        return mpmath.mpf(float(x))
    return mpmath.mpf(str(x))


def rotation_error(values: Sequence[Any], ref: Sequence[Any]) -> float:
    """max(|Δω|/|ω_ref|, quaternion distance up to sign) between (p, q, r, qw, qx, qy, qz)."""
    with mpmath.workdps(90):
        v, r = [exact_mpf(x) for x in values], [exact_mpf(x) for x in ref]
        w = mpmath.sqrt(sum(x * x for x in r[:3]))
        de = max(abs(a - b) for a, b in zip(v[:3], r[:3], strict=True)) / w
        minus = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(v[3:], r[3:], strict=True)))
        plus = mpmath.sqrt(sum((a + b) ** 2 for a, b in zip(v[3:], r[3:], strict=True)))
        return float(max(de, min(minus, plus)))


def final_values(result: ch.Result, names: Sequence[str]) -> list[Any]:
    return [result[k][-1] for k in names]


def closed_form_end(inertia, rates, t_end: float, dps: int) -> list[mpmath.mpf]:
    body = FreeRigidBody(inertia, rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
    s = body.at(mpmath.mpf(t_end))
    return [s.p, s.q, s.r, *s.quaternion]
