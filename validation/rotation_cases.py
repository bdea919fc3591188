"""The case matrix of the rotation validation: torque-free bodies with a closed-form reference.

Every input is a Python float, i.e. an exact binary64 value. The scene keeps floats at their
exact value in every precision (``docs/scenes.md``) and the reference reads them exactly too,
so double, quad and 256-bit runs integrate the *same* numbers and are compared with the same
exact solution. The one quantity built per precision is the differences of
the moments ``B − C, …`` in Euler's equations, computed exactly and rounded once in the run's
precision (exact for these moments).

Spans are in periods of (p, q, r) (``FreeRigidBody.period``), per precision; ``quick`` spans
are for the ``--quick`` smoke run. The 256-bit spans were chosen from a measured step cost
(~9–13 ms per step at order 90 for the quaternion formulation, ~6 ms for Rodrigues, 2 cores;
15–100 steps per period) so that each run stays under about two minutes.

``ENSEMBLES`` are the growth-law measurements: one case integrated from a few inputs a few
ulps apart (independent round-off, each against its own closed form), whose RMS error is
fitted, since a single run's error is one sample path of a random walk.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mpmath

PRECISIONS = ("double", "quad", "real256")
SPECS = {"double": "double", "quad": "quad", "real256": {"bits": 256}}
EPSILON = {"double": 2.0**-52, "quad": 2.0**-112, "real256": 2.0**-255}
# Reference digits: far below each precision's error (|error| ≳ ε), with margin for the
# law's growth over the span.
REFERENCE_DPS = {"double": 40, "quad": 50, "real256": 95}


@dataclass(frozen=True)
class Case:
    """One torque-free body and how long to integrate it.

    Attributes
    ----------
    name
        Short identifier (file names, table rows).
    title
        What the case probes.
    inertia, rates
        Principal moments (A, B, C) and initial body rates (p, q, r), exact binary64 values.
    formulation
        ``"quaternion"`` or ``"rodrigues"`` (the latter re-bases its chart through θ = π).
    periods
        Span in periods of (p, q, r), per precision; a precision not listed is not run.
    quick
        Spans of the ``--quick`` smoke run.
    group
        ``"regular"``, ``"separatrix"`` or ``"long"``: the summary separates near-separatrix
        cases, whose law-predicted error is large by construction.
    target_distance
        The separatrix distance asked for (the realised one is computed from the inputs).
    """

    name: str
    title: str
    inertia: tuple[float, float, float]
    rates: tuple[float, float, float]
    formulation: str = "quaternion"
    periods: dict[str, float] = field(default_factory=dict)
    quick: dict[str, float] = field(default_factory=dict)
    group: str = "regular"
    target_distance: float | None = None

    def integrator(self, precision: str) -> dict:
        """Tolerance ε; at 256 bits also the step cap 1/|ω₀| that docs/scenes.md recommends.

        Order-90 steps at 256 bits can span half a period, and their round-off grows with the
        step (the diagnostic table of REPORT.md measures it); the cap is applied to every
        256-bit run alike, and the diagnostic keeps the uncapped runs for comparison.
        """
        table = {"precision": SPECS[precision], "tolerance": "auto"}
        if precision == "real256":
            table["max_step"] = 1.0 / math.sqrt(sum(w * w for w in self.rates))
        return table

    def scene(
        self, precision: str, times: list[float], events: bool = True, formulation: str = ""
    ) -> dict:
        """The scene dictionary of this case at ``precision`` on the output ``times``."""
        return {
            "title": f"validation: {self.name}",
            "body": {"inertia": list(self.inertia)},
            # Identity attitude: the space frame is the body frame at t = 0, so the reference is
            # built with attitude (1, 0, 0, 0) and no attitude input needs rounding.
            "initial": {"rates": list(self.rates), "quaternion": [1.0, 0.0, 0.0, 0.0]},
            "attitude": {"formulation": formulation or self.formulation},
            "integrator": self.integrator(precision),
            "output": {
                "times": list(times),
                "events": ["invariable_plane", "half_turn"] if events else [],
                "monitors": ["energy", "momentum_squared", "momentum_space"],
            },
            # w = cos(θ/2) of the continuous quaternion vanishes each time the rotation angle
            # from the start passes π: counts the passages the Rodrigues chart must re-base over.
            "events": {"half_turn": {"expression": "qw", "direction": "any"}} if events else {},
        }


def separatrix_rates(
    inertia: tuple[float, float, float], p: float, q: float, distance: str
) -> tuple[float, float, float]:
    """Rates (p, q, r) at a relative distance from the separatrix, r rounded to binary64.

    ``B`` is the middle moment (here the second one): with ``h = 2T`` and ``k² = |L|²``,
    ``hB − k² = A(B − A)p² + C(B − C)r²`` (q drops out), so fixing p, q and solving
    ``hB − k² = δ k²`` for r² is linear. The rounding of r moves δ by ~1e-16 in absolute terms;
    the report quotes the distance realised by the rounded inputs.
    """
    with mpmath.workdps(60):
        A, B, C = (mpmath.mpf(x) for x in inertia)
        if not A < B < C:
            raise ValueError("separatrix_rates expects A < B < C (B the middle moment)")
        P, Q, d = mpmath.mpf(p), mpmath.mpf(q), mpmath.mpf(distance)
        r2 = (A * (B - A) * P**2 - d * (A**2 * P**2 + B**2 * Q**2)) / (C * (C - B) + d * C**2)
        return (p, q, float(mpmath.sqrt(r2)))


def separatrix_distance(inertia, rates) -> mpmath.mpf:
    """(2T·B_mid − |L|²)/|L|² computed exactly (60 digits) from binary64 inputs."""
    with mpmath.workdps(60):
        I = [mpmath.mpf(x) for x in inertia]  # noqa: E741 - the inertia triple
        w = [mpmath.mpf(x) for x in rates]
        h = sum(I[i] * w[i] ** 2 for i in range(3))
        k2 = sum((I[i] * w[i]) ** 2 for i in range(3))
        mid = sorted(I)[1]
        return (h * mid - k2) / k2


_SEP_INERTIA = (1.0, 2.0, 3.0)
_FULL = {"double": 100, "quad": 100, "real256": 100}
_QUICK = {"double": 5, "quad": 2, "real256": 0.5}


def _separatrix_cases() -> list[Case]:
    cases = []
    for exponent in (6, 10, 14):
        for sign, side in ((1, "above"), (-1, "below")):
            target = f"{'-' if sign < 0 else ''}1e-{exponent}"
            rates = separatrix_rates(_SEP_INERTIA, 0.5, 0.5, target)
            cases.append(
                Case(
                    name=f"separatrix_{'p' if sign > 0 else 'm'}{exponent}",
                    title=(
                        f"{target} from the separatrix ({side}: "
                        f"{'rotation about the minor axis' if sign > 0 else 'about the major'})"
                    ),
                    inertia=_SEP_INERTIA,
                    rates=rates,
                    # The period grows like log(1/δ) and the steps per period with it
                    # (84 steps of ~13 ms per period at 256 bits for δ = 1e-14).
                    periods={"double": 100, "quad": 100, "real256": 20},
                    quick={"double": 3, "quad": 1, "real256": 0.25},
                    group="separatrix",
                    target_distance=float(target),
                )
            )
    return cases


CASES: list[Case] = [
    Case(
        "generic",
        "generic asymmetric body (m = 0.57), quaternion attitude",
        (1.0, 2.0, 3.0),
        (0.75, -0.5, 0.625),
        periods={"double": 100, "quad": 100, "real256": 100},
        quick=_QUICK,
    ),
    Case(
        "generic_rodrigues",
        "the generic body with the Rodrigues chart, re-based through θ = π",
        (1.0, 2.0, 3.0),
        (0.75, -0.5, 0.625),
        formulation="rodrigues",
        periods=_FULL,
        quick=_QUICK,
    ),
    Case(
        "long",
        "the generic body over 10⁴ periods (double) and 10³ (quad)",
        (1.0, 2.0, 3.0),
        (0.75, -0.5, 0.625),
        periods={"double": 10_000, "quad": 1000},
        quick={"double": 200},
        group="long",
    ),
    Case(
        "major_axis",
        "near the major axis (A < B < C, rotation mostly about C)",
        (1.0, 1.5, 2.5),
        (0.125, 0.25, 1.0),
        periods=_FULL,
        quick=_QUICK,
    ),
    Case(
        "minor_axis",
        "near the minor axis (rotation mostly about A)",
        (1.0, 1.5, 2.5),
        (1.0, 0.1875, 0.25),
        periods=_FULL,
        quick=_QUICK,
    ),
    Case(
        "unsorted",
        "unsorted moments (C the intermediate one), m = 0.94",
        (2.5, 1.0, 1.75),
        (0.5, -0.75, 0.625),
        periods=_FULL,
        quick=_QUICK,
    ),
    *_separatrix_cases(),
    Case(
        "nearly_symmetric",
        "nearly symmetric: A/B − 1 = 1e-8 (rounded to binary64)",
        (float(mpmath.mpf(1) + mpmath.mpf("1e-8")), 1.0, 2.0),
        (0.5, 0.25, 1.0),
        periods=_FULL,
        quick=_QUICK,
    ),
    Case(
        "symmetric",
        "exactly symmetric: A = B",
        (1.0, 1.0, 2.0),
        (0.5, 0.25, 1.0),
        periods=_FULL,
        quick=_QUICK,
    ),
]

BY_NAME = {c.name: c for c in CASES}

#: (case, precision, periods, members) of the ensemble growth-law fits; the quick run's below.
ENSEMBLES = [
    ("generic", "double", 1000, 16),
    ("minor_axis", "double", 1000, 16),
    ("generic", "quad", 300, 8),
    ("unsorted", "quad", 300, 8),
    ("separatrix_m10", "quad", 100, 8),
]
QUICK_ENSEMBLES = [("generic", "double", 60, 4)]


def nudged(case: Case, ulps: int) -> Case:
    """The case with p moved by ``ulps`` binary64 ulps (an ensemble member)."""
    import dataclasses

    import numpy as np

    p = case.rates[0]
    for _ in range(ulps):
        p = float(np.nextafter(p, np.inf))
    return dataclasses.replace(case, rates=(p, *case.rates[1:]))
