"""Closed-form references for checking integrators, at any precision, with error estimates.

The stable entry point::

    from cayley_heyoka.reference import free_rigid_body
    s = free_rigid_body(("1", "1.5", "2.5"), ("0.125", "0.25", "1"), "10", dps=30)
    s.p, s.q, s.r, s.phi, s.psi, s.nu0, s.lambda0, s.mu0, s.errors

:class:`FreeRigidBody` evaluates many times and crossing times of the invariable plane;
Euler's 1758 and Cayley's 1846 solutions are :class:`Euler1758` and :class:`Cayley1846`;
Hamilton's projectile is :func:`projectile_solution` (with :func:`principal_function`).
Every value is computed at two working precisions and comes with the difference as its error
estimate; a request that cannot be met raises :class:`PrecisionNotReached`.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

from ..core.accuracy import PrecisionNotReached

# The solutions live beside the equations they solve (rotation/, later orbit/, hamilton/) and
# import .accuracy from here, so they are loaded on first use rather than at import time.
_HOMES = {
    "Crossing": "..rotation.closed_form",
    "FreeBodyState": "..rotation.closed_form",
    "FreeRigidBody": "..rotation.closed_form",
    "free_rigid_body": "..rotation.closed_form",
    "Euler1758": "..rotation.euler1758",
    "Cayley1846": "..rotation.cayley1846",
    "projectile_solution": "..hamilton.projectile",
    "principal_function": "..hamilton.projectile",
    "ProjectileSolution": "..hamilton.projectile",
    "PrincipalFunction": "..hamilton.projectile",
}


def __getattr__(name: str) -> Any:
    if name in _HOMES:
        return getattr(import_module(_HOMES[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "Cayley1846",
    "Crossing",
    "Euler1758",
    "FreeBodyState",
    "FreeRigidBody",
    "PrecisionNotReached",
    "PrincipalFunction",
    "ProjectileSolution",
    "free_rigid_body",
    "principal_function",
    "projectile_solution",
]
