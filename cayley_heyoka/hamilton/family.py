"""The Hamiltonian family's record in the registry (:mod:`cayley_heyoka.core.families`)."""

from __future__ import annotations

from ..core.families import Family, later

FAMILY = Family(
    "hamiltonian",
    "hamiltonian",
    ("hamiltonian", "initial"),
    later("cayley_heyoka.hamilton.scene", "Hamiltonian.parse"),
    later("cayley_heyoka.hamilton.model", "build_model"),
    output_keys=("principal_function",),
    consistency_check=later("cayley_heyoka.hamilton.projectile_check", "check_hamiltonian"),
    closed_form=later("cayley_heyoka.hamilton.projectile_reference", "closed_form"),
    variables=later("cayley_heyoka.hamilton.variables", "describe"),
    references={
        **dict.fromkeys(
            ("projectile_solution", "principal_function"), "cayley_heyoka.hamilton.projectile"
        ),
        **dict.fromkeys(
            ("ProjectileSolution", "PrincipalFunction"), "cayley_heyoka.hamilton.projectile"
        ),
        **dict.fromkeys(
            ("projectile_bounds", "ProjectileBounds"), "cayley_heyoka.hamilton.projectile_bounds"
        ),
    },
    memoirs=("hamilton1835",),
    structure=later("cayley_heyoka.hamilton.numbers", "structure"),
    numbers=later("cayley_heyoka.hamilton.numbers", "numbers"),
)
