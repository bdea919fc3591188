"""The measured records of the set-up section: one scene's compiles and step costs
(:class:`Point`), one ensemble method at one size (:class:`Throughput`)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class Point:
    family: str
    param: str
    size: int
    decomposition: int
    auto_compact: bool
    compile: dict[bool, float]
    cpu: dict[bool, float]
    ns: dict[bool, float]
    steps: int

    @property
    def ratio(self) -> float:
        """Step cost of compact over non-compact code."""
        return self.ns[True] / self.ns[False]

    @property
    def break_even(self) -> float:
        """Steps after which non-compact code has paid for its longer compile (inf: never;
        0: it compiles no slower)."""
        saved = self.cpu[False] - self.cpu[True]
        lost = (self.ns[True] - self.ns[False]) * 1e-9
        if saved <= 0:
            return 0.0
        return saved / lost if lost > 0 else math.inf


@dataclass
class Throughput:
    method: str
    n: int
    wall: float
    cpu: float
    steps: int
    error: float  # max |final state − our serial mode's|
    measured: bool = True

    @property
    def rate(self) -> float:
        return self.n / self.wall
