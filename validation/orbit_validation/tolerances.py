"""The round-off laws and the brief's requirements of the orbit validation.

Fixed before any number is seen; written out in the report by
:func:`orbit_validation.report.laws_text`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from orbit_cases import EPSILON, REFERENCE_BY_NAME

# ---------------------------------------------------------------------------- the laws
# Written down before the first run. ε is the run's machine epsilon, n(t) the steps taken up to
# t (recorded step by step), N_orb(t) = t/P the orbits, e the eccentricity.
#
# * Brouwer: round-off makes a conserved quantity random-walk, |drift(t)| ≤ C_BROUWER ε √n.
# * Phase law: each step perturbs the energy by ~ε κ relatively, κ = (|T| + |V|)/|E| at
#   pericentre = (3 + e)/(1 − e) (3 for a circle); as a random walk δE/E ~ ε κ √n(s)/3 (κ/3 = 1
#   for a circle). The mean motion changes by 3/2 of it, so the phase lags by
#   ∫ (3/2) (2π/P) ε (κ/3) √n ds = 2π ε (κ/3) N_orb √n (n ∝ s), and the position by the phase
#   times the largest speed in units of na, √((1 + e)/(1 − e)); a velocity by the phase times
#   the largest acceleration in units of n²a, 1/(1 − e)². The rounding of ρ itself (an angle
#   growing ~2π per orbit) adds a phase walk of the same form, ε·2π N_orb √n. Hence
#       position/a, r, h, angles:   ≤ C_LAW ε (1 + 2π N_orb √n K_x(e)),
#       velocity/(na), ṙ:            ≤ C_LAW ε (1 + 2π N_orb √n K_v(e)),
#       K_x = √((1+e)/(1−e)) (3+e)/(3(1−e)),  K_v = (3+e)/(3(1−e)^3).
#   A comparison of two runs takes the sum of their two tolerances.
# * Plane angles near Φ = 0: an absolute error δ of the orbit normal moves Θ and Σ by δ/sin Φ
#   (docs/orbits.md), and the normal random-walks like ε √n, so
#       |ΔΘ|, |ΔΣ| ≤ C_LAW ε (√n / sin Φ_min + 1 + 2π N_orb √n K_x),
#   while Φ and Θ − Σ (well defined at Φ = 0) follow the position law.
C_BROUWER = 10.0
C_LAW = 10.0
# From the brief: fixed requirements, independent of the laws.
REQUIREMENTS = {
    "quad_reference_relative": 1e-19,  # real128 vs the cases' 20-digit values
    "long_orbits": 1000,  # orbits of the long runs
}
DPS = 60  # digits of the comparisons
N_TIMES = {"full": 120, "quick": 30}  # log-spaced output times of a long run
VELOCITY_LIKE = ("rdot", "vx", "vy", "vz")


def K_x(e: float) -> float:
    return math.sqrt((1 + e) / (1 - e)) * (3 + e) / (3 * (1 - e))


def K_v(e: float) -> float:
    return (3 + e) / (3 * (1 - e) ** 3)


def law(eps: float, t: Any, n: Any, period: float, k: float) -> Any:
    """C_LAW ε (1 + 2π N_orb √n K)."""
    return C_LAW * eps * (1 + 2 * np.pi * np.asarray(t) / period * np.sqrt(np.asarray(n)) * k)


def brouwer(eps: float, n: Any) -> Any:
    return C_BROUWER * eps * np.sqrt(np.maximum(np.asarray(n, dtype=float), 1))


def reference_tolerance(case_name: str, precision: str, quantity: str, steps: int) -> float:
    """Double: the phase law at t (the steps are spread evenly); real128: the brief's 1e-19."""
    if precision != "double":
        return REQUIREMENTS["quad_reference_relative"]
    case = REFERENCE_BY_NAME[case_name]
    period = 2 * math.pi * case.a**1.5
    k = K_v(case.e) if quantity in VELOCITY_LIKE else K_x(case.e)
    return float(law(EPSILON["double"], float(case.t), steps, period, k))
