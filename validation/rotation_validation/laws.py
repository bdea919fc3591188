"""The tolerances of the rotation validation, fixed before any run.

The round-off laws and their constants (written out in the report by
:func:`.tables.laws_text`), the fixed requirements of the brief, the output-grid sizes, the
closed-form cross-check's digits and times, and :class:`LawConstants`, the laws' tolerances as
functions of what a case's exact flow gives (computed by :mod:`.exact_flow`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

# Written down before the first run. ε is the precision's machine epsilon, n(t) the steps taken
# up to t (recorded step by step), |ω₀| the norm of the initial rates.
#
# * Brouwer: round-off makes the conserved quantities random-walk, |drift(t)| ≤ C_BROUWER ε √n.
# * Phase: a perturbation of the rates of relative size e changes the period T of (p, q, r) by
#   S_T·e relatively (S_T = |∇_ω ln T|·|ω₀|) and the mean precession rate Ψ̄ = ΔΨ/T by S_Ψ·e
#   (S_Ψ = |∇_ω Ψ̄|·|ω₀|). With e(s) = ε √n(s) and n ∝ s, the time lag of the rates is
#   ∫ S_T e ds = (2/3) S_T ε t √n, so
#       scaled rates error ≤ C_LAW ε (1 + (2/3) S_T g t √n),   g = max|ω̇| / |ω₀|,
#       attitude error     ≤ C_LAW ε (1 + (1/3)(S_T |ω|max + S_Ψ) t √n)
#   (the quaternion distance is half the angle: the lag of the rates times |ω|, plus the lag of
#   Ψ). t √n ∝ n^{3/2}: this is the ε·steps^{3/2} law, with the separatrix amplification in S_T
#   (∝ 1/(δ log(1/δ)) next to it) computed from the closed form, not fitted.
# * Crossing times: an event time lags like the rates, plus the rounding of t itself:
#       |Δt| ≤ C_LAW ε (t + (2/3) S_T t √n).
# * Growth exponents (log-log fit of the running maximum against n, after the transient):
#   conserved ≤ 1/2 + FIT_SLACK, state and attitude ≤ 3/2 + FIT_SLACK.
C_BROUWER = 10.0
C_LAW = 10.0
FIT_SLACK = 0.25
# From the brief: fixed requirements, independent of the laws.
REQUIREMENTS = {
    "quad_generic_state": 1e-30,  # real128, generic case, quaternion, 100 periods
    "double_generic_crossings": 1e-14,  # |Δt|/t, generic case, double, 100 periods
}
# Output times per run (log-spaced); the long run gets more.
N_TIMES = {"full": 150, "long": 220, "quick": 40}
# The closed forms against each other: digits and evaluation times (in periods).
CLOSED_FORM_DPS = 30
CLOSED_FORM_TIMES = (0.1, 0.37, 1.0, 2.6)
# The growth exponents an ensemble's RMS errors are judged against (+ FIT_SLACK).
ENSEMBLE_LAW = {"state": 1.5, "attitude": 1.5, "energy": 0.5, "momentum_squared": 0.5}


@dataclasses.dataclass(frozen=True)
class LawConstants:
    """What the laws need from the exact flow of one case (see the comment above)."""

    period: float
    S_T: float
    S_Psi: float
    g: float
    w_max: float
    w0: float
    distance: float

    def state(self, eps: float, t: np.ndarray, n: np.ndarray) -> np.ndarray:
        return C_LAW * eps * (1 + (2 / 3) * self.S_T * self.g * t * np.sqrt(n))

    def attitude(self, eps: float, t: np.ndarray, n: np.ndarray) -> np.ndarray:
        return C_LAW * eps * (1 + (1 / 3) * (self.S_T * self.w_max + self.S_Psi) * t * np.sqrt(n))

    def conserved(self, eps: float, n: np.ndarray) -> np.ndarray:
        return C_BROUWER * eps * np.sqrt(np.maximum(n, 1))

    def crossing(self, eps: float, t: np.ndarray, n: np.ndarray) -> np.ndarray:
        return C_LAW * eps * (t + (2 / 3) * self.S_T * t * np.sqrt(n))
