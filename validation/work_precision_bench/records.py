"""What a case records: its sweep points, notes, fixed costs and the levels to rank them at."""

from __future__ import annotations

from dataclasses import dataclass, field

from .cases import DOUBLE_LEVELS, EXTENDED_LEVELS


@dataclass
class Point:
    """One sweep point: a method at one setting."""

    method: str
    setting: str
    steps: int | None
    wall: float  # seconds of integration (ours: the stepping alone, see Stepper)
    error: float
    run_wall: float | None = None  # ours: the whole run() call
    compile: float | None = None  # ours: seconds of the first run's compile (0: cache hit)
    extra: str = ""
    order: int | None = None  # ours: the Taylor order heyoka chose for the tolerance


@dataclass
class Case:
    """Everything one case reports: its points, notes and how to rank them."""

    name: str
    title: str
    error_measure: str
    reference: str
    points: list[Point] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    fixed_cost: dict[str, float] = field(default_factory=dict)
    rhs_call: float | None = None  # seconds per right-hand-side call from scipy
    missing: list[str] = field(default_factory=list)
    levels: tuple[float, ...] = DOUBLE_LEVELS + EXTENDED_LEVELS
