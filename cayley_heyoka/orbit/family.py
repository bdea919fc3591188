"""The orbit family's record in the registry (:mod:`cayley_heyoka.core.families`)."""

from __future__ import annotations

from ..core.families import Family, later

FAMILY = Family(
    "orbit",
    "orbit",
    ("orbit", "perturbations", "reference_plane"),
    later("cayley_heyoka.orbit.scene", "Orbit.parse"),
    later("cayley_heyoka.orbit.model", "build_model"),
    later("cayley_heyoka.orbit.model", "validate"),
    consistency_check=later("cayley_heyoka.orbit.cartesian_check", "check_orbit"),
    plot_kinds=("orbit",),
    plots=later("cayley_heyoka.orbit.plots", "plots"),
    variables=later("cayley_heyoka.orbit.variables", "describe"),
    events=("node", "apsis", "equatorial"),
    formulations=("orbit.formulation", ("cartesian", "cayley", "quaternion", "encke")),
    with_formulation=later("cayley_heyoka.orbit.scene", "with_formulation"),
    memoirs=("cayley1860",),
    structure=later("cayley_heyoka.orbit.numbers", "structure"),
    numbers=later("cayley_heyoka.orbit.numbers", "numbers"),
    table=later("cayley_heyoka.orbit.tables", "table"),
)
