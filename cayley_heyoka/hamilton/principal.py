"""Checking Hamilton's principal function on a run, through the variational equations.

S(η, e, t) = ∫₀ᵗ (T + U) dt is a function of the final coordinates η, the initial coordinates e
and the time (Hamilton 1835, Second Essay, (19.)–(23.)). Its partial derivatives satisfy

    ∂S/∂η = ϖ,        ∂S/∂e = −p,        ∂S/∂t = −H.

A run gives S as a function of the initial data (e, p) instead. heyoka's first-order
variational equations (``var_ode_sys``) carry the Jacobians ∂η/∂e, ∂η/∂p, ∂S/∂e, ∂S/∂p along
the run, and the chain rule turns them into the partials of S(η, e, t):

    ∂S/∂η = (∂S/∂p) (∂η/∂p)⁻¹,
    ∂S/∂e = ∂S/∂e|ₚ − (∂S/∂η) (∂η/∂e),
    ∂S/∂t = Ṡ − (∂S/∂η) η̇.

The three residuals against ϖ, −p and −H are what :func:`check_principal_function` returns.
Where ∂η/∂p is singular (t = t₀, and conjugate points such as sin μt = 0 for the projectile)
S(η, e, t) does not exist; those times are reported with an infinite condition number, and
near them the residuals grow as the condition does.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import heyoka as hy
import mpmath
import numpy as np

from ..core import outcomes
from ..core.consistency import CheckReport, CheckRow
from ..core.exact import exact
from ..core.precision import Precision, scene_mpf
from ..core.scene import Scene
from ..core.structures import model_for


@dataclass(frozen=True)
class PrincipalCheck:
    """Residuals of the principal function's partial derivatives on the output grid.

    Attributes
    ----------
    t
        Output times (the run's precision).
    eta, e, time
        max |∂S/∂η − ϖ|, max |∂S/∂e + p| and |∂S/∂t + H| at each time (floats; NaN where
        ∂η/∂p is singular).
    condition
        How much the chain rule amplifies the Jacobians' errors: ‖(∂η/∂p)⁻¹‖₁ times the largest
        entry of the Jacobian of (η, ϖ, S) (∞ at t₀ and at conjugate points). For the projectile
        it is about the condition number of ∂η/∂p; unlike that, it also sees a small ∂η/∂p
        in one dimension.
    scale
        Size of the compared quantities: the largest |ϖᵢ|, |pᵢ| and |H| on the run.
    epsilon
        Unit round-off of the run's precision.
    """

    t: np.ndarray
    eta: np.ndarray
    e: np.ndarray
    time: np.ndarray
    condition: np.ndarray
    scale: float
    epsilon: float

    def report(self) -> CheckReport:
        """The residuals as a :class:`~cayley_heyoka.core.consistency.CheckReport`.

        Each residual is a few roundings of quantities of size :attr:`scale`, amplified by the
        chain rule's :attr:`condition`; the bound is 64 ε · scale · condition, written here as
        the residual divided by scale · condition against 64 ε. Times where S(η, e, t)
        does not exist (∂η/∂p singular) are left out and counted in the note.
        """
        finite = np.isfinite(self.condition)
        skipped = int(np.count_nonzero(~finite))
        note = "÷ scale·condition"
        if skipped:
            note += f"; {skipped} singular time(s) left out"
        rows = []
        series: dict[str, np.ndarray] = {"t": np.asarray(self.t, dtype=float)}
        for name, label in (("eta", "∂S/∂η − ϖ"), ("e", "∂S/∂e + p"), ("time", "∂S/∂t + H")):
            relative = getattr(self, name)[finite] / (self.scale * self.condition[finite])
            error = float(np.max(relative)) if relative.size else float("nan")
            rows.append(CheckRow(label, error, 64 * self.epsilon, note))
            series[name] = getattr(self, name)
        series["condition"] = self.condition
        title = "Hamilton's principal function S: its partial derivatives through var_ode_sys"
        return CheckReport(title, tuple(rows), series)


def check_principal_function(scene: Scene) -> PrincipalCheck:
    """Integrate a Hamiltonian scene with its variational equations and check ∂S.

    Parameters
    ----------
    scene
        A scene of the ``hamiltonian`` family (``output.principal_function`` is implied; a
        scene with ``formulation = "elements"`` is checked in its canonical formulation).

    Returns
    -------
    PrincipalCheck
    """
    if scene.family != "hamiltonian":
        raise ValueError(f"scene: needs the hamiltonian family, got {scene.family!r}")
    # The Jacobians are taken with respect to η(t₀), ϖ(t₀): the canonical state.
    scene = scene.derive(
        {"output.principal_function": True, "hamiltonian.formulation": "canonical"}
    )
    model = model_for(scene)
    prec = scene.integrator.precision
    n = scene.model.degrees
    variational = hy.var_ode_sys(model.system, hy.var_args.vars, order=1)
    kw = prec.heyoka_kwargs
    extra = {}
    if scene.integrator.tolerance is not None:
        extra["tol"] = prec.number(scene.integrator.tolerance)
    held = model.integrator_parameters()
    ta = hy.taylor_adaptive(
        variational,
        prec.array(model.initial_state),
        pars=prec.array(model.pars.values[:held]),
        compact_mode=True,
        high_accuracy=scene.integrator.high_accuracy,
        **extra,
        **kw,
    )
    grid = scene.time_grid
    ta.time = grid[0]
    run = outcomes.GridRun.of(ta.propagate_grid(grid))
    rows = run.whole("scene: the variational equations of the principal function", ta.time)
    size = 2 * n + 1
    jac = [ta.get_vslice(order=1, component=i) for i in range(size)]
    rates = hy.cfunc([rhs for _, rhs in model.system], [v for v, _ in model.system], **kw)
    energy = hy.cfunc([model.monitors["energy"]], [v for v, _ in model.system], **kw)
    pars = prec.array(model.pars.values)
    p0 = list(scene.model.varpi)
    results = [
        _residuals(row, jac, n, rates, energy, pars, t, prec, p0)
        for row, t in zip(rows, grid[: len(rows)], strict=True)
    ]
    columns = np.array(results, dtype=float).T if results else np.empty((5, 0))
    scale = max([float(np.max(columns[4], initial=0.0))] + [abs(float(v)) for v in p0])
    return PrincipalCheck(grid[: len(rows)], *columns[:4], scale, prec.epsilon)


def _residuals(row, jac, n, rates, energy, pars, t, prec: Precision, p0):
    state = copy.copy(row[: 2 * n + 1])
    J = [[row[k] for k in range(s.start, s.stop)] for s in jac]
    with mpmath.workdps(prec.dps + 5):
        to_mp = exact  # the run's numbers, exactly
        A = mpmath.matrix([[to_mp(J[i][n + j]) for j in range(n)] for i in range(n)])  # ∂η/∂p
        B = mpmath.matrix([[to_mp(J[i][j]) for j in range(n)] for i in range(n)])  # ∂η/∂e
        sp = mpmath.matrix([to_mp(J[2 * n][n + j]) for j in range(n)])  # ∂S/∂p
        se = mpmath.matrix([to_mp(J[2 * n][j]) for j in range(n)])  # ∂S/∂e
        varpi = [to_mp(state[n + i]) for i in range(n)]
        H = to_mp(energy(state, pars=pars[: energy.nparams], time=t)[0])
        size = float(max([abs(H)] + [abs(v) for v in varpi]))
        try:
            inverse = mpmath.inverse(A)
            y = mpmath.lu_solve(A.T, sp)  # ∂S/∂η
        except ZeroDivisionError:
            return [np.nan, np.nan, np.nan, np.inf, size]
        d_eta = max(abs(y[i] - varpi[i]) for i in range(n))
        d_e_vec = se - B.T * y
        d_e = max(abs(d_e_vec[i] + scene_mpf(p0[i])) for i in range(n))
        rhs = rates(state, pars=pars[: rates.nparams], time=t)
        S_dot = to_mp(rhs[2 * n])
        d_t = abs(S_dot - sum(y[i] * to_mp(rhs[i]) for i in range(n)) + H)
        # Every Jacobian entry carries an error relative to the largest of them (heyoka controls
        # the error of the whole state), and solving with ∂η/∂p multiplies it by ‖(∂η/∂p)⁻¹‖.
        largest = max(abs(to_mp(v)) for v in row[2 * n + 1 :])
        condition = mpmath.mnorm(inverse, 1) * largest
        return [float(d_eta), float(d_e), float(d_t), float(condition), size]
