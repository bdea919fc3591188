"""The orbit family's record in the registry (:mod:`cayley_heyoka.core.families`)."""

from __future__ import annotations

from ..core.families import Family, later
from .model import build_model, validate
from .scene import Orbit

FAMILY = Family(
    "orbit",
    "orbit",
    ("orbit", "perturbations", "reference_plane"),
    Orbit.parse,
    build_model,
    validate,
    consistency_check=later("cayley_heyoka.orbit.cartesian_check", "check_orbit"),
    plot_kinds=("orbit",),
    plots=later("cayley_heyoka.orbit.plots", "plots"),
)
