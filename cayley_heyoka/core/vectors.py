"""3-vectors and 3×3 tables in any arithmetic: heyoka expressions (equations), mpmath numbers
(exact states), numpy arrays and Python numbers alike, since only + − × are used."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

Matrix = list[list[Any]]


Vector = list[Any]


def matmul(a: Matrix, b: Matrix) -> Matrix:
    """Product of two 3×3 tables."""
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def transpose(a: Matrix) -> Matrix:
    """Transpose of a 3×3 table (its inverse)."""
    return [[a[j][i] for j in range(3)] for i in range(3)]


def matvec(a: Matrix, v: Sequence[Any]) -> Vector:
    """``a v`` for a 3×3 table and a 3-vector."""
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def dot(a: Sequence[Any], b: Sequence[Any]) -> Any:
    """Scalar product of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Sequence[Any], b: Sequence[Any]) -> Vector:
    """Vector product of two 3-vectors."""
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
