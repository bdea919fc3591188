"""What each output and monitor of a rotation scene is (``Family.variables``), in the memoirs'
symbols; importing nothing heavier than the standard library."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

_NAMES = {
    "p": "body rate about principal axis 1 (Euler's p)",
    "q": "body rate about principal axis 2 (Euler's q)",
    "r": "body rate about principal axis 3 (Euler's r)",
    "lambda": "Cayley–Rodrigues parameter λ of the attitude (infinite at a half-turn)",
    "mu": "Cayley–Rodrigues parameter μ of the attitude",
    "nu": "Cayley–Rodrigues parameter ν of the attitude",
    "qw": "attitude quaternion, scalar part (cos of half the rotation angle)",
    "qx": "attitude quaternion, component along space axis x",
    "qy": "attitude quaternion, component along space axis y",
    "qz": "attitude quaternion, component along space axis z",
    "psi": "Ψ = 2 tan⁻¹ν₀: the angle about the invariable line L (unwrapped, Ψ(0) = 0)",
    "energy": "T − V: the kinetic energy ½(Ap² + Bq² + Cr²) less the force function V",
    "momentum_squared": "|L|² = (Ap)² + (Bq)² + (Cr)², the angular momentum's squared norm",
    "momentum_space": "the angular momentum L in the space frame (a vector)",
    "momentum_vertical": "L · up: the angular momentum about the forces' fixed direction (a heavy "
    "top's vertical; γ · (Ap, Bq, Cr) in the Euler–Poisson reduction)",
    "gamma1": "γ₁: the forces' fixed direction (a heavy top's vertical) along body axis 1",
    "gamma2": "γ₂: the forces' fixed direction along body axis 2",
    "gamma3": "γ₃: the forces' fixed direction along body axis 3",
    "direction_norm": "|γ|²: the squared norm of the fixed direction in body axes (exactly 1)",
    "orthogonality": (
        "how far the integrated frame is from a rotation (the quaternion's norm drift; the "
        "reported attitude is normalised)"
    ),
}


def describe(scene: Mapping[str, Any], name: str) -> str | None:
    """What ``name`` is in a rotation scene's results, or None if it is not one of its names."""
    return _NAMES.get(name)
