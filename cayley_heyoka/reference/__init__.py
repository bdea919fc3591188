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

from ..core.accuracy import PrecisionNotReached as PrecisionNotReached
from ..core.families import FAMILIES


def _homes() -> dict[str, str]:
    """Each public closed-form name and the module that holds it, as the families declare
    them (``Family.references``); the solutions load on first use."""
    return {
        name: module for family in FAMILIES for name, module in FAMILIES[family].references.items()
    }


def __getattr__(name: str) -> Any:
    module = _homes().get(name) if not name.startswith("_") else None
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(module), name)


__all__ = sorted(["PrecisionNotReached", *_homes()])
