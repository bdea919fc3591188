"""The frames of Cayley (1860) and the tables that place one in another.

Symbols, as in the memoir (Cayley 1860, "A supplementary memoir on the problem of disturbed
elliptic motion"; docs/orbits.md, "Symbols"):

* frame 0 — the fixed (inertial) reference plane;
* frame 1 — the reference plane, possibly moving: node longitude θ′, node departure σ′ and
  inclination φ′ relative to frame 0 (prescribed functions of time);
* frame 2 — the osculating orbit plane, with its origin x₂ a *departure point* (it moves only
  perpendicularly to the plane): node longitude Θ, node departure Σ and inclination Φ relative
  to frame 1;
* the body lies in frame 2 at radius r and departure ρ (angle from x₂); ``u = ρ − Σ`` is its
  argument of latitude (arc from the ascending node on plane 1).

A table ``M_ab`` holds the unit vectors of frame b as columns in frame a
(``x⁽ᵃ⁾ = M_ab x⁽ᵇ⁾``); for node longitude θ, departure σ and inclination φ,
``M(θ, σ, φ) = R₃(θ) R₁(φ) R₃(−σ)``.

The functions use arithmetic and ``sin``/``cos``/``sqrt``/``atan2`` only, taken from
:func:`functions_for`, so one formula serves heyoka expressions (the equations), mpmath numbers
(exact initial states) and numpy arrays (vectorised conversions).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from ..core.vectors import Matrix, Vector


def functions_for(*values: Any) -> SimpleNamespace:
    """``sin, cos, sqrt, atan2`` and ``cos_sin`` (both of one angle) for the kind of the
    values: heyoka, mpmath or numpy.

    mpmath's ``cos_sin`` runs the one computation its ``cos`` and ``sin`` each run
    (``libmp.mpf_cos_sin``, which returns one or both), so its two numbers are theirs, bit for
    bit, for half the cost.
    """
    import heyoka as hy

    for v in values:
        if isinstance(v, hy.expression):
            return SimpleNamespace(
                sin=hy.sin, cos=hy.cos, sqrt=hy.sqrt, atan2=hy.atan2, cos_sin=_cos_sin(hy)
            )
    for v in values:
        if type(v).__module__.startswith("mpmath"):
            import mpmath

            return SimpleNamespace(
                sin=mpmath.sin,
                cos=mpmath.cos,
                sqrt=mpmath.sqrt,
                atan2=mpmath.atan2,
                cos_sin=mpmath.cos_sin,
            )
    return SimpleNamespace(
        sin=np.sin, cos=np.cos, sqrt=np.sqrt, atan2=np.arctan2, cos_sin=_cos_sin(np)
    )


def _cos_sin(module: Any) -> Any:
    return lambda a: (module.cos(a), module.sin(a))


def rotation_x(a: Any) -> Matrix:
    """``R₁(a)``: active right-handed rotation by ``a`` about the first axis."""
    c, s = functions_for(a).cos_sin(a)
    return [[1 + 0 * c, 0 * c, 0 * c], [0 * c, c, -s], [0 * c, s, c]]


def rotation_z(a: Any) -> Matrix:
    """``R₃(a)``: active right-handed rotation by ``a`` about the third axis."""
    c, s = functions_for(a).cos_sin(a)
    return [[c, -s, 0 * c], [s, c, 0 * c], [0 * c, 0 * c, 1 + 0 * c]]


def plane_matrix(theta: Any, sigma: Any, phi: Any) -> Matrix:
    """``M(θ, σ, φ) = R₃(θ) R₁(φ) R₃(−σ)``, written out (Lamé's table; docs/orbits.md,
    "Conventions").

    Column 3 is the plane's normal, ``(sin θ sin φ, −cos θ sin φ, cos φ)``.
    """
    f = functions_for(theta, sigma, phi)
    ct, st = f.cos_sin(theta)
    cs, ss = f.cos_sin(sigma)
    cp, sp = f.cos_sin(phi)
    return [
        [cs * ct + ss * st * cp, ss * ct - cs * st * cp, st * sp],
        [cs * st - ss * ct * cp, ss * st + cs * ct * cp, -ct * sp],
        [-ss * sp, cs * sp, cp],
    ]


def orbit_axes(Theta: Any, Phi: Any, u: Any) -> tuple[Vector, Vector, Vector]:
    """``x̂₃`` (towards the body), ``ŷ₃`` (90° ahead in the orbit) and ``n̂`` in frame 1 (§5)."""
    f = functions_for(Theta, Phi, u)
    cT, sT = f.cos_sin(Theta)
    cP, sP = f.cos_sin(Phi)
    cu, su = f.cos_sin(u)
    x3 = [cT * cu - sT * cP * su, sT * cu + cT * cP * su, sP * su]
    y3 = [-cT * su - sT * cP * cu, -sT * su + cT * cP * cu, sP * cu]
    n = [sT * sP, -cT * sP, cP]
    return x3, y3, n
