"""An atlas of Rodrigues charts: integrating (λ, μ, ν) through rotation angles of π.

The Cayley–Rodrigues parameters ``ρ = tan(θ/2) n`` are infinite at θ = π (``κ = sec²(θ/2)``).
The attitude is therefore carried as ``base ⊗ chart``: a base rotation held in runtime
parameters (a unit quaternion, in the run's precision) and the integrated parameters ρ of the
body relative to that base. When ``κ`` reaches ``κ_max = sec²(θ_max/2)`` a terminal event stops
the integrator; the chart is folded into the base by Cayley's composition (the vector over the
scalar part of the quaternion product ``q_base ⊗ q(ρ)``) and ρ restarts from zero. The body
rates are untouched, and because the base composes with ρ exactly, the reported attitude is
continuous across the change.

Only the base's own rounding enters at each re-basing (one product and one normalisation in the
run's precision); its effect is measured in the tests against the quaternion formulation, and
its mean — which, summed over millions of re-basings, would drift the attitude linearly in
time — is checked to vanish (``tests/rotation/test_charts.py``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import mpmath
import numpy as np

from ..core.model import ParTable
from ..core.precision import Precision, scene_mpf
from . import attitude as att


def kappa_limit(max_angle_degrees: Any, precision: Precision) -> str:
    """``sec²(θ_max/2)`` as decimal text accurate in the target precision."""
    with mpmath.workdps(precision.dps + 10):
        theta = scene_mpf(max_angle_degrees) * mpmath.pi / 180  # a float at its exact value
        return mpmath.nstr(1 / mpmath.cos(theta / 2) ** 2, precision.dps + 5)


class RodriguesAtlas:
    """The base rotation of the current chart, and the re-basing step.

    Parameters
    ----------
    pars
        The model's parameter table; the base quaternion and, for invariable-plane events,
        the angular momentum in space and in base axes are allocated in it.
    state_slice
        Where λ, μ, ν sit in the integrator's state.
    values
        The scene's numbers by parameter name (:meth:`values`).
    """

    def __init__(self, pars: ParTable, state_slice: slice, values: Mapping[str, Any]) -> None:
        self.state_slice = state_slice
        self.pars = pars
        self.values = values
        self.base_pars = [
            pars.add(f"chart.base[{i}]", values[f"chart.base[{i}]"]) for i in range(4)
        ]
        self._base_index = pars.index("chart.base[0]")
        self._space_index: int | None = None

    @staticmethod
    def values_of(base: Sequence[Any], momentum_space: Sequence[Any] | None) -> dict[str, Any]:
        """The chart's parameters for a first chart based at ``base`` (a quaternion in the run's
        precision) and, for invariable-plane events, the body's constant angular momentum in
        space, ``momentum_space``."""
        out = {f"chart.base[{i}]": base[i] for i in range(4)}
        if momentum_space is not None:
            gb = _momentum_in_base(list(base), list(momentum_space))
            out |= {f"chart.momentum[{i}]": gb[i] for i in range(3)}
            out |= {f"chart.momentum_space[{i}]": momentum_space[i] for i in range(3)}
        return out

    def momentum_in_chart_base(self) -> list:
        """Parameters holding the base-frame components of the constant angular momentum
        ``(g, g′, g″)``, for the invariable-plane events of a torque-free body; kept up to date
        at every re-basing."""
        values = self.values
        pars = [
            self.pars.add(f"chart.momentum[{i}]", values[f"chart.momentum[{i}]"]) for i in range(3)
        ]
        self._momentum_index = self.pars.index("chart.momentum[0]")
        # The space vector the base-frame one is recomputed from: a number of the scene, so
        # held with the others, not by the handler (which every scene of the structure shares).
        for i in range(3):
            self.pars.add(f"chart.momentum_space[{i}]", values[f"chart.momentum_space[{i}]"])
        self._space_index = self.pars.index("chart.momentum_space[0]")
        return pars

    def rebase(self, ta: Any, pars: np.ndarray) -> None:
        """Fold the chart into the base; called with the integrator stopped at the event and
        the model's parameter vector."""
        # Scalars, not numpy arrays: the fold is a few dozen operations, which numpy's scalar
        # and small-array machinery made 9 µs a fold (a third of a hand-written loop's time
        # per re-basing). ``tolist`` keeps every value exactly (Python floats in double, the
        # precision's own numbers otherwise), and the operations and their order are those of
        # the array code, so the bits are the same.
        state = ta.state
        rho = state[self.state_slice].tolist()
        i = self._base_index
        base = pars[i : i + 4].tolist()
        # The chart as (1, λ, μ, ν), unnormalised: the fold happens at κ = κ_max, so the unit
        # quaternion's w = 1/√κ would round alike at every fold: a bias of ~0.1 ε of angle
        # per fold, which millions of folds turn into a drift of the attitude linear in time.
        # Scaling all four components by one factor rotates nothing, so the normalisation
        # below is the only rounding of the direction, and it is unbiased.
        one = 0 * rho[0] + 1  # 1 in the state's type (real128, real) without a conversion
        w, x, y, z = att.quaternion_multiply(base, [one, *rho])
        norm = _sqrt(w * w + x * x + y * y + z * z)
        new = [w / norm, x / norm, y / norm, z / norm]
        # Element by element: a slice assigned from a list first builds an array (~1 µs).
        pars[i], pars[i + 1], pars[i + 2], pars[i + 3] = new
        zero = 0 * new[1]  # in the state's type
        j = self.state_slice.start
        state[j], state[j + 1], state[j + 2] = zero, zero, zero
        if self._space_index is not None:
            j, k = self._momentum_index, self._space_index
            pars[j : j + 3] = _momentum_in_base(new, pars[k : k + 3].tolist())


def _momentum_in_base(base: list[Any], momentum_space: list[Any]) -> list[Any]:
    return att.matvec(att.transpose(att.quaternion_to_matrix(base)), momentum_space)


def _sqrt(x: Any) -> Any:
    # math.sqrt is IEEE's correctly rounded root, as numpy's; heyoka's numbers have their own.
    return math.sqrt(x) if type(x) is float else np.sqrt(x)
