"""The rotation family's record in the registry (:mod:`cayley_heyoka.core.families`)."""

from __future__ import annotations

from ..core.families import Family, later

FAMILY = Family(
    "rotation",
    "body",
    ("body", "initial", "attitude", "forces"),
    later("cayley_heyoka.rotation.scene", "RigidBody.parse"),
    later("cayley_heyoka.rotation.model", "build_model"),
    output_keys=("invariable_angle", "azimuth"),
    consistency_check=later("cayley_heyoka.rotation.closed_form_check", "check_rotation"),
    closed_form=later("cayley_heyoka.rotation.free_body_reference", "closed_form"),
    plot_kinds=("polhode", "crossings"),
    plots=later("cayley_heyoka.rotation.plots", "plots"),
    variables=later("cayley_heyoka.rotation.variables", "describe"),
    references={
        **dict.fromkeys(
            ("Crossing", "FreeBodyState", "FreeRigidBody", "free_rigid_body"),
            "cayley_heyoka.rotation.closed_form",
        ),
        "FreeBodyBounds": "cayley_heyoka.rotation.enclosures",
        "Euler1758": "cayley_heyoka.rotation.euler1758",
        "Cayley1846": "cayley_heyoka.rotation.cayley1846",
    },
    events=("invariable_plane",),
    formulations=("attitude.formulation", ("quaternion", "rodrigues", "poisson")),
    with_formulation=later("cayley_heyoka.rotation.scene", "with_formulation"),
    memoirs=("cayley1843", "cayley1846", "euler1758"),
    structure=later("cayley_heyoka.rotation.numbers", "structure"),
    numbers=later("cayley_heyoka.rotation.numbers", "numbers"),
    table=later("cayley_heyoka.rotation.numbers", "table"),
)
