"""Hamilton's Second Essay on a General Method in Dynamics (1835): canonical systems from a
Hamiltonian, the principal function, and his worked examples."""

from .projectile import (
    PrincipalFunction,
    ProjectileSolution,
    principal_function,
    projectile_solution,
)

__all__ = ["PrincipalFunction", "ProjectileSolution", "principal_function", "projectile_solution"]
