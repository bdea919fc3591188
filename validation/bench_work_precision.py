"""Work–precision: error against wall time over a tolerance sweep, ours and the peers side by side.

Run:  python validation/bench_work_precision.py [--quick] [--out PATH]
      (or through the driver: python validation/benchmarks.py --only work_precision)

Cases (spans kept modest; the e = 0.5, 10⁴-orbit IAS15 accuracy study is another section's):

* ``free_regular``, ``free_separatrix`` — torque-free bodies of validation/rotation_cases.py (the
  generic body and the one 1e-6 from the separatrix), 20 periods, against the closed form
  ``cayley_heyoka.reference.FreeRigidBody``;
* ``heavy_top`` — the bundled examples/heavy_top.toml over t = 50, against a real128 run;
* ``orbit_j2`` — a J2 orbit at e = 0.1 over 100 orbits, against a real128 Cartesian run;
* ``planets`` — the predominant-mass system of examples/planets.toml over 100 inner orbits,
  against a real128 canonical run;
* ``free_extended`` — the generic body over a short span in extended precision: real128,
  MPFR at 113 and 256 bits, mpmath's ``odefun``.

Our side: ``cayley_heyoka.run`` on the scene, one compiled integrator per (formulation,
precision, tolerance) — the tolerance is a compile-time option, so each sweep point compiles
once; that compile is timed and reported apart. The wall time of a point is the stepping of
that compiled integrator over the span, with ``run``'s calls and event handling
(:class:`Stepper`); ``run``'s fixed cost on top (building the model, the cache lookup,
the copy of the integrator, the outputs) is reported in its own table: it is milliseconds,
while a double-precision sweep point steps in tens of microseconds to a few milliseconds.

Peers, in the same process: scipy's ``solve_ivp`` (DOP853; Radau once, to check stiffness) on
the same equations, their right-hand side compiled by heyoka into a ``cfunc`` (so scipy pays
only its own per-call Python overhead, not a slow numpy right-hand side); mpmath's ``odefun``
(``free_extended``); REBOUND's IAS15 with REBOUNDx's ``gravitational_harmonics`` for J2 and plain
N-body gravity for the planets. A peer that is not installed is reported as such.
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import heyoka as hy
import mpmath
import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import hamilton_planets  # noqa: E402
import rotation_cases  # noqa: E402
from bench_common import Curve, available, fmt, ratios_at_equal_error  # noqa: E402
from work_precision_bench.cases import (  # noqa: E402
    EXTENDED_LEVELS,
    IAS15_EPSILON,
    J2_ORBIT,
    LABEL,
    QUICK_IAS15_EPSILON,
    QUICK_RTOL,
    REFERENCE_TOL,
    ROTATION,
    RTOL,
    TINY,
    heavy_top_data,
    heavy_top_example,
    j2_data,
    j2_initial_state,
    planets_barycentric,
    planets_data,
    quad_tolerances,
    rotation_data,
    tolerances,
    with_integrator,
)
from work_precision_bench.records import Case, Point  # noqa: E402

import cayley_heyoka as ch  # noqa: E402
from cayley_heyoka.core.engine import compile_model  # noqa: E402
from cayley_heyoka.core.families import FAMILIES  # noqa: E402
from cayley_heyoka.core.model import own_terminal  # noqa: E402
from cayley_heyoka.hamilton.predominant_mass import system as hp  # noqa: E402
from cayley_heyoka.reference import FreeRigidBody  # noqa: E402

REPEAT, BUDGET = 5, 1.0  # timing: least of up to REPEAT calls, fewer once a call exceeds BUDGET s


def _mp(x: Any) -> mpmath.mpf:
    """A double, real128 or real exactly as an mpf (their text round-trips)."""
    if isinstance(x, float | np.floating | int):
        return mpmath.mpf(float(x))
    return mpmath.mpf(str(x))


def _log(msg: str) -> None:
    print(f"  [work_precision] {msg}", flush=True)


# ---------------------------------------------------------------------------- our side
class Stepper:
    """``run``'s compiled integrator, stepped over the scene's span without ``run``'s fixed cost.

    The same template integrator ``run`` copies (``compiler.compile_model``), the same call
    (one ``propagate_grid`` over the output times, terminal events handled inside it) and the
    same event handling (the family's handlers: chart re-basings, revolutions of ρ); left out
    is what ``run`` does around them — building the model, the cache lookup, the copy of the
    integrator, the output evaluation — which is measured apart. The step count is checked
    against ``run``'s, or this would time something else.
    """

    def __init__(self, scene: ch.Scene, steps: int) -> None:
        self.model = FAMILIES[scene.family].build(scene)
        compiled, _ = compile_model(self.model, scene.integrator)
        self.prec = scene.integrator.precision
        self.grid = scene.output.time_grid(self.prec)
        self.ta = copy.deepcopy(compiled.integrator)
        self.steps = steps

    def __call__(self) -> float:
        """Seconds of one pass over the span."""
        model, ta, prec, grid = self.model, self.ta, self.prec, self.grid
        pars = prec.array(model.pars.values)  # handlers change them (a chart's base)
        held = len(ta.pars)
        ta.time = grid[0]
        ta.state[:] = prec.array(model.initial_state)
        ta.pars[:] = pars[:held]
        if model.terminal:
            ta.reset_cooldowns()  # the previous pass's last event must not mute the first
            handlers = own_terminal(model.terminal)

            def handle(index: int, ta: Any) -> bool:
                if handlers[index].handle(ta, pars) is not None:
                    raise RuntimeError("a terminal event stopped the timed run")
                ta.pars[:] = pars[:held]
                ta.reset_cooldowns()
                return True

            for ev in ta.t_events:
                ev.callback.target = handle
        s = time.perf_counter()
        res = ta.propagate_grid(grid)
        elapsed = time.perf_counter() - s
        if res[0] != hy.taylor_outcome.time_limit:
            raise RuntimeError(f"stepping ended with outcome {res[0]}")
        if res[3] != self.steps:
            raise RuntimeError(f"stepped {res[3]} steps where run() took {self.steps}")
        return elapsed


def ours(
    case: Case,
    formulation: str,
    data: dict,
    precision: str,
    tolerances: Sequence[str],
    t_end: Any,
    error: Callable[[ch.Result], float],
    label: str = "",
) -> dict[str, ch.Result]:
    """Sweep one formulation at one precision; adds points to ``case``, returns the results."""
    method = f"ours {formulation}, {LABEL[precision]}{label}"
    results = {}
    for tol in tolerances:
        scene = with_integrator(data, precision, tol, [0.0, t_end])
        first = ch.run(scene)  # compiles (or finds the code in heyoka's disk cache)
        compile_s = first.metadata["compile_seconds"]
        stepper = Stepper(scene, first.counters["steps"])
        run_wall = wall = math.inf
        for _ in range(REPEAT):
            # Interleaved, so that a change of load on the shared machine hits both alike.
            s = time.perf_counter()
            result = ch.run(scene)
            run_wall = min(run_wall, time.perf_counter() - s)
            wall = min(wall, stepper())
            if run_wall > BUDGET:
                break
        # run() does this stepping and more: a stepping time above it is the load's doing.
        wall = min(wall, run_wall)
        # run()'s own cost, from a span of one step: the same at every tolerance, so the least
        # over the sweep is the least disturbed measurement.
        tiny = with_integrator(data, precision, tol, [0.0, TINY])
        fixed = _least(lambda tiny=tiny: ch.run(tiny), 2 * REPEAT)[0]
        case.fixed_cost[method] = min(case.fixed_cost.get(method, math.inf), fixed)
        steps = result.counters["steps"]
        err = error(result)
        rebasings = result.counters.get("rebasings")
        case.points.append(
            Point(
                method,
                tol,
                steps,
                wall,
                err,
                run_wall,
                compile_s,
                f"{rebasings} re-basings" if rebasings is not None else "",
                result.metadata["order"],
            )
        )
        results[tol] = result
        _log(
            f"{case.name}: {method} tol {tol}: {steps} steps, {wall * 1e3:.2f} ms "
            f"(run {run_wall * 1e3:.2f}, compile {compile_s:.2f} s), error {err:.2e}"
        )
    return results


def high_accuracy(case: Case, data: dict, formulation: str, t_end: Any, error: Callable) -> None:
    """The tightest double tolerances again with heyoka's compensated evaluation of the Taylor
    polynomials (``integrator.high_accuracy``): does our round-off floor move?"""
    d = {**data, "integrator": {"high_accuracy": True}}
    ours(case, formulation, d, "double", ("1e-14", "1e-16"), t_end, error, ", high accuracy")


def reference_check(
    case: Case, formulation: str, data: dict, t_end: Any, error: Callable, unit: str = ""
) -> None:
    """The reference's own error: another formulation (other variables, other equations) in
    real128 at the reference's tolerance, run once, untimed."""
    other = ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, t_end]))
    case.notes.append(
        f"The reference's own error: the {formulation} formulation in real128 at "
        f"{REFERENCE_TOL} (other variables and equations) differs from it by "
        f"{error(other):.1e}{unit}."
    )


def reference_run(data: dict, t_end: Any) -> ch.Result:
    """The real128 reference at tolerance 1e-32."""
    return ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, t_end]))


# ---------------------------------------------------------------------------- scipy
def _compiled_rhs(data: dict, jacobian: bool) -> tuple[Callable, Callable | None, np.ndarray]:
    """The scene's right-hand side (and Jacobian) as heyoka cfuncs in double, and its initial
    state: the very equations our integrator steps, callable from scipy."""
    scene = ch.Scene.from_dict(data)
    model = FAMILIES[scene.family].build(scene)
    variables = [v for v, _ in model.system]
    rhs = [r for _, r in model.system]
    y0 = np.array([float(v) for v in model.initial_state])
    n = len(y0)

    def compiled(exprs: list) -> Callable:
        f = hy.cfunc(exprs, variables)
        pars = np.array([float(v) for v in model.pars.values[: f.nparams]])
        # scipy hands over views (Radau's finite differences too): cfuncs want C order.
        return lambda t, y: f(np.ascontiguousarray(y), pars=pars, time=t)

    fun = compiled(rhs)
    if not jacobian:
        return fun, None, y0
    jac = compiled(list(np.ravel(hy.diff_tensors(rhs, diff_args=variables, diff_order=1).jacobian)))
    return fun, lambda t, y: jac(t, y).reshape(n, n), y0


def _group_scale(y0: np.ndarray, groups: Sequence[int]) -> np.ndarray:
    """Per-component scale for scipy's atol: the norm of each component's vector at t0 (a
    quaternion, a position, a momentum), so atol = rtol·scale asks for relative accuracy."""
    out, k = [], 0
    for g in groups:
        out += [np.linalg.norm(y0[k : k + g])] * g
        k += g
    return np.array(out)


def scipy_sweep(
    case: Case,
    data: dict,
    t_end: float,
    groups: Sequence[int],
    error: Callable[[np.ndarray], float],
    rtols: Sequence[float],
    method: str = "DOP853",
    label: str = "",
) -> None:
    """solve_ivp on the compiled right-hand side; also times one right-hand-side call."""
    if not available("scipy"):
        case.missing.append(f"scipy {method}: not installed")
        return
    from scipy.integrate import solve_ivp

    fun, jac, y0 = _compiled_rhs(data, jacobian=method == "Radau")
    scale = _group_scale(y0, groups)
    kwargs = {"jac": jac} if jac else {}
    for rtol in rtols:

        def go(rtol: float = rtol) -> Any:
            return solve_ivp(
                fun, (0.0, t_end), y0, method=method, rtol=rtol, atol=rtol * scale, **kwargs
            )

        w, sol = _least(go)
        if not sol.success:
            _log(f"{case.name}: scipy {method} rtol {rtol:g} failed: {sol.message}")
            continue
        err = error(sol.y[:, -1])
        steps = len(sol.t) - 1
        case.points.append(
            Point(
                label or f"scipy {method}", f"rtol {rtol:g}", steps, w, err, extra=f"{sol.nfev} f"
            )
        )
        _log(
            f"{case.name}: scipy {method} rtol {rtol:g}: {steps} steps, {w * 1e3:.1f} ms, {err:.2e}"
        )
    # Where scipy's time goes: one right-hand-side call, as solve_ivp makes it.
    calls = 20000
    s = time.perf_counter()
    for _ in range(calls):
        fun(0.0, y0)
    case.rhs_call = (time.perf_counter() - s) / calls


def _least(fn: Callable[[], Any], repeat: int | None = None) -> tuple[float, Any]:
    best, out = math.inf, None
    for _ in range(repeat or REPEAT):
        s = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - s)
        if best > BUDGET:
            break
    return best, out


# ---------------------------------------------------------------------------- REBOUND
def _ias15(sim: Any) -> Any:
    # REBOUND 4 exposes the IAS15 settings as sim.ri_ias15, REBOUND 5 as sim.integrator.
    return sim.ri_ias15 if hasattr(sim, "ri_ias15") else sim.integrator


def ias15_sweep(
    case: Case,
    build: Callable[[], tuple[Any, Any]],
    t_end: float,
    error: Callable[[Any], float],
    epsilons: Sequence[float | None],
    needs: Sequence[str] = ("rebound",),
) -> None:
    """IAS15 over the sweep of ``epsilon``; ``build`` returns a fresh simulation (and whatever
    must stay alive with it, e.g. REBOUNDx's extras). Only ``integrate`` is timed."""
    missing = [m for m in needs if not available(m)]
    if missing:
        case.missing.append(f"REBOUND IAS15: {', '.join(missing)} not installed")
        return
    for eps in epsilons:
        best, sim = math.inf, None
        for _ in range(REPEAT):
            sim, keep = build()
            _ias15(sim).epsilon = eps if eps is not None else _ias15(sim).epsilon
            label = f"ε {_ias15(sim).epsilon:g}" + (" (default)" if eps is None else "")
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                s = time.perf_counter()
                sim.integrate(t_end, exact_finish_time=1)
                best = min(best, time.perf_counter() - s)
            del keep
            if best > BUDGET:
                break
        err = error(sim)
        warned = "predictor–corrector warnings" if caught else ""
        case.points.append(
            Point("REBOUND IAS15", label, int(sim.steps_done), best, err, extra=warned)
        )
        _log(f"{case.name}: IAS15 {label}: {sim.steps_done} steps, {best * 1e3:.1f} ms, {err:.2e}")


# ---------------------------------------------------------------------------- error measures
def rotation_error(values: Sequence[Any], ref: Sequence[Any]) -> float:
    """max(|Δω|/|ω_ref|, quaternion distance up to sign) between (p, q, r, qw, qx, qy, qz)."""
    with mpmath.workdps(90):
        v, r = [_mp(x) for x in values], [_mp(x) for x in ref]
        w = mpmath.sqrt(sum(x * x for x in r[:3]))
        de = max(abs(a - b) for a, b in zip(v[:3], r[:3], strict=True)) / w
        minus = mpmath.sqrt(sum((a - b) ** 2 for a, b in zip(v[3:], r[3:], strict=True)))
        plus = mpmath.sqrt(sum((a + b) ** 2 for a, b in zip(v[3:], r[3:], strict=True)))
        return float(max(de, min(minus, plus)))


def _tuple(values: Sequence[Any]) -> str:
    return "(" + ", ".join(str(v) for v in values) + ")"


def _final(result: ch.Result, names: Sequence[str]) -> list[Any]:
    return [result[k][-1] for k in names]


def closed_form_end(inertia, rates, t_end: float, dps: int) -> list[mpmath.mpf]:
    body = FreeRigidBody(inertia, rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=dps)
    s = body.at(mpmath.mpf(t_end))
    return [s.p, s.q, s.r, *s.quaternion]


# ---------------------------------------------------------------------------- the cases
def free_body(name: str, key: str, periods: float, quick: bool) -> Case:
    rc = rotation_cases.BY_NAME[key]
    body = FreeRigidBody(rc.inertia, rc.rates, attitude=(1.0, 0.0, 0.0, 0.0), dps=30)
    t_end = float(periods * body.period)
    distance = rotation_cases.separatrix_distance(rc.inertia, rc.rates)
    case = Case(
        name,
        f"{rc.title[0].upper()}{rc.title[1:]} (validation/rotation_cases.py `{key}`): inertia "
        f"{rc.inertia}, rates "
        f"{tuple(round(x, 6) for x in rc.rates)}, identity attitude; "
        f"t = {t_end:.6g} ({periods:g} periods of the rates; separatrix distance "
        f"{mpmath.nstr(distance, 2)})",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        "the closed form (`FreeRigidBody`, 40 digits)",
    )
    ref = closed_form_end(rc.inertia, rc.rates, t_end, 40)

    def error(result: ch.Result) -> float:
        return rotation_error(_final(result, ROTATION), ref)

    for k, formulation in enumerate(("quaternion", "rodrigues")):
        data = rotation_data(rc, formulation)
        ours(case, formulation, data, "double", tolerances(quick, "double"), t_end, error)
        ours(case, formulation, data, "quad", quad_tolerances(quick, k), t_end, error)
    data = rotation_data(rc, "quaternion")
    scipy_sweep(
        case, data, t_end, (3, 4), lambda y: rotation_error(y, ref), QUICK_RTOL if quick else RTOL
    )
    if name == "free_regular" and not quick:
        # Radau only to show the case is not stiff: an implicit method buys nothing here.
        scipy_sweep(
            case, data, t_end, (3, 4), lambda y: rotation_error(y, ref), (1e-6, 1e-9), "Radau"
        )
    return case


def heavy_top(quick: bool) -> Case:
    example = heavy_top_example()
    t_end = 5.0 if quick else 50.0
    case = Case(
        "heavy_top",
        f"examples/heavy_top.toml: inertia {_tuple(example['body']['inertia'])}, centre of "
        f"mass {_tuple(example['forces']['heavy_top']['center_of_mass'])}, weight "
        f"{example['forces']['heavy_top']['weight']}; identity attitude; t = {t_end:g}",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        f"our quaternion formulation in real128 at tolerance {REFERENCE_TOL}",
    )

    def data(formulation: str) -> dict:
        return heavy_top_data(example, formulation)

    ref_result = reference_run(data("quaternion"), t_end)
    ref = _final(ref_result, ROTATION)

    def error(result: ch.Result) -> float:
        return rotation_error(_final(result, ROTATION), ref)

    for k, formulation in enumerate(("quaternion", "rodrigues")):
        ours(
            case,
            formulation,
            data(formulation),
            "double",
            tolerances(quick, "double"),
            t_end,
            error,
        )
        ours(
            case,
            formulation,
            data(formulation),
            "quad",
            quad_tolerances(quick, k, reference=True),
            t_end,
            error,
        )
        if k > 0 and not quick:
            reference_check(case, formulation, data(formulation), t_end, error)
    scipy_sweep(
        case,
        data("quaternion"),
        t_end,
        (3, 4),
        lambda y: rotation_error(y, ref),
        QUICK_RTOL if quick else RTOL,
    )
    return case


def orbit_j2(quick: bool) -> Case:
    a, e, i, node, w, M = J2_ORBIT["elements"]
    mu = J2_ORBIT["mu"]
    x0, v0 = j2_initial_state()
    orbits = 1 if quick else J2_ORBIT["orbits"]
    t_end = float(2 * math.pi * orbits * math.sqrt(a**3 / mu))
    case = Case(
        "orbit_j2",
        f"J2 = {J2_ORBIT['J2']:g} about z, radius {J2_ORBIT['radius']:g}, μ = {mu:g}; a = {a:g}, "
        f"e = {e:g}, i = {i:g}, Ω = {node:g}, ω = {w:g}, M = {M:g} (rounded to a binary64 "
        f"Cartesian state); t = {t_end:.6g} ({orbits} orbits)",
        "|Δx|/a at the final time (position)",
        f"our Cartesian formulation in real128 at tolerance {REFERENCE_TOL}",
    )

    def data(formulation: str) -> dict:
        return j2_data(x0, v0, formulation)

    ref_result = reference_run(data("cartesian"), t_end)
    ref = _final(ref_result, ("x", "y", "z"))

    def pos_error(x: Sequence[Any]) -> float:
        with mpmath.workdps(60):
            d = [_mp(u) - _mp(r) for u, r in zip(x, ref, strict=True)]
            return float(mpmath.sqrt(sum(c * c for c in d)) / a)

    def error(result: ch.Result) -> float:
        return pos_error(_final(result, ("x", "y", "z")))

    for k, formulation in enumerate(("cartesian", "cayley", "quaternion")):
        d = data(formulation)
        ours(case, formulation, d, "double", tolerances(quick, "double"), t_end, error)
        ours(case, formulation, d, "quad", quad_tolerances(quick, k, reference=True), t_end, error)
        if k == 1 and not quick:
            reference_check(case, formulation, d, t_end, error, " of a")
    if not quick:
        high_accuracy(case, data("cartesian"), "cartesian", t_end, error)
    scipy_sweep(
        case,
        data("cartesian"),
        t_end,
        (3, 3),
        lambda y: pos_error(y[:3]),
        QUICK_RTOL if quick else RTOL,
    )

    def build() -> tuple[Any, Any]:
        import rebound
        import reboundx

        sim = rebound.Simulation()
        sim.G = 1.0
        # A massless orbiter keeps the central body at the origin, as in our fixed-centre
        # problem, and μ = G·m₀.
        sim.add(m=mu)
        sim.add(m=0.0, x=x0[0], y=x0[1], z=x0[2], vx=v0[0], vy=v0[1], vz=v0[2])
        sim.integrator = "ias15"
        rebx = reboundx.Extras(sim)
        gh = rebx.load_force("gravitational_harmonics")
        rebx.add_force(gh)
        sim.particles[0].params["J2"] = J2_ORBIT["J2"]
        sim.particles[0].params["R_eq"] = J2_ORBIT["radius"]
        return sim, (rebx, gh)

    def reb_error(sim: Any) -> float:
        p, c = sim.particles[1], sim.particles[0]
        return pos_error([p.x - c.x, p.y - c.y, p.z - c.z])

    if available("rebound") and available("reboundx"):
        case.notes.append(_j2_convention(build, data("cartesian"), t_end))
    ias15_sweep(
        case,
        build,
        t_end,
        reb_error,
        QUICK_IAS15_EPSILON if quick else IAS15_EPSILON,
        ("rebound", "reboundx"),
    )
    return case


def _j2_convention(build: Callable, data: dict, t_end: float) -> str:
    """REBOUNDx's J2 against ours: the same orbit over up to 10 orbits, IAS15 at its default ε
    against our real128 Cartesian run, and, for scale, IAS15 with J2 switched off (what a
    mismatch of sign or factor in J2 or R would leave)."""
    span = min(t_end, 10 * 2 * math.pi)
    ref = ch.run(with_integrator(data, "quad", REFERENCE_TOL, [0.0, span]))
    diffs = []
    for j2 in (True, False):
        sim, keep = build()
        if not j2:
            sim.particles[0].params["J2"] = 0.0
        sim.integrate(span, exact_finish_time=1)
        p, c = sim.particles[1], sim.particles[0]
        with mpmath.workdps(40):
            d = [
                _mp(u) - _mp(ref[k][-1])
                for u, k in zip((p.x - c.x, p.y - c.y, p.z - c.z), "xyz", strict=True)
            ]
            diffs.append(float(mpmath.sqrt(sum(x * x for x in d))))
        del keep
    return (
        "REBOUNDx's `gravitational_harmonics` (J2 and R_eq on the central particle, axis z) is "
        "our `[perturbations.zonal]` J2: after t = "
        f"{span:.4g}, IAS15 at its default ε is {diffs[0]:.1e} from our real128 Cartesian run "
        f"(without J2 it would be {diffs[1]:.1e} away)."
    )


def planets(quick: bool) -> Case:
    orbits = 1 if quick else 100
    t_end = float(2 * math.pi * orbits)
    masses = [float(m) for m, _ in hamilton_planets.BODIES]
    axes = [float(e["a"]) for _, e in hamilton_planets.BODIES]
    n = len(masses)
    case = Case(
        "planets",
        f"examples/planets.toml ('N5': M = 1, G = 1, masses {masses}, a = {axes}), "
        f"t = {t_end:.6g} ({orbits} inner orbits)",
        "max over bodies of |Δξᵢ|/aᵢ (heliocentric positions) at the final time",
        f"our canonical formulation in real128 at tolerance {REFERENCE_TOL}",
    )
    names = [f"{c}{k + 1}" for k in range(n) for c in "xyz"]

    def data(formulation: str) -> dict:
        return planets_data(orbits, formulation)

    ref_result = reference_run(data("canonical"), t_end)
    ref = _final(ref_result, names)

    def pos_error(xi: Sequence[Any]) -> float:
        with mpmath.workdps(60):
            worst = mpmath.mpf(0)
            for k in range(n):
                d = [_mp(xi[3 * k + j]) - _mp(ref[3 * k + j]) for j in range(3)]
                worst = max(worst, mpmath.sqrt(sum(c * c for c in d)) / axes[k])
            return float(worst)

    def error(result: ch.Result) -> float:
        return pos_error(_final(result, names))

    for formulation in ("canonical", "elements"):
        ours(
            case,
            formulation,
            data(formulation),
            "double",
            tolerances(quick, "double"),
            t_end,
            error,
        )
    ours(
        case,
        "canonical",
        data("canonical"),
        "quad",
        quad_tolerances(quick, 0, reference=True),
        t_end,
        error,
    )
    if not quick:
        high_accuracy(case, data("canonical"), "canonical", t_end, error)
        # Hamilton's elements step ~20× slower than the canonical equations: in real128 only
        # the untimed check of the reference.
        reference_check(case, "elements", data("elements"), t_end, error, " of a")
    scipy_sweep(
        case,
        data("canonical"),
        t_end,
        (3,) * (2 * n),
        lambda y: pos_error(y[: 3 * n]),
        QUICK_RTOL if quick else RTOL,
    )

    # REBOUND gets barycentric particles from the exact canonical state, rounded once.
    X, V = planets_barycentric(orbits)

    def build() -> tuple[Any, Any]:
        import rebound

        sim = rebound.Simulation()
        sim.G = 1.0
        for m, x, v in zip([1.0, *masses], X, V, strict=True):
            sim.add(m=m, x=x[0], y=x[1], z=x[2], vx=v[0], vy=v[1], vz=v[2])
        sim.integrator = "ias15"
        return sim, None

    def reb_error(sim: Any) -> float:
        ps = sim.particles
        with mpmath.workdps(50):
            pos = [[mpmath.mpf(p.x), mpmath.mpf(p.y), mpmath.mpf(p.z)] for p in ps]
            vel = [[mpmath.mpf(p.vx), mpmath.mpf(p.vy), mpmath.mpf(p.vz)] for p in ps]
            xs, _ = hp.heliocentric(pos, vel, [mpmath.mpf(1.0), *map(mpmath.mpf, masses)])
            return pos_error([c for x in xs for c in x])

    ias15_sweep(case, build, t_end, reb_error, QUICK_IAS15_EPSILON if quick else IAS15_EPSILON)
    return case


def free_extended(quick: bool) -> Case:
    rc = rotation_cases.BY_NAME["generic"]
    t_end = 0.5 if quick else 5.0
    case = Case(
        "free_extended",
        f"The generic body of `free_regular` over t = {t_end:g}, in extended precision",
        "max(|Δω|/|ω|, quaternion distance up to sign) at the final time",
        "the closed form (`FreeRigidBody`, 100 digits)",
        levels=(1e-13, *EXTENDED_LEVELS, 1e-50, 1e-70),
    )
    ref = closed_form_end(rc.inertia, rc.rates, t_end, 100)

    def error(result: ch.Result) -> float:
        return rotation_error(_final(result, ROTATION), ref)

    data = rotation_data(rc, "quaternion")
    for precision in ("double", "quad", "real113", "real256"):
        ours(case, "quaternion", data, precision, tolerances(quick, precision), t_end, error)
    if not quick:
        for dps, tols in ((34, (1e-12, 1e-20, None)), (77, (None,))):
            for tol_mp in tols:
                mpmath_point(case, rc, t_end, dps, tol_mp, ref)
    return case


def mpmath_point(case: Case, rc, t_end: float, dps: int, tol: float | None, ref) -> None:
    """mpmath's odefun (its Taylor method) on the quaternion equations at ``dps`` digits."""
    with mpmath.workdps(dps):
        A, B, C = (mpmath.mpf(x) for x in rc.inertia)
        e0, e1, e2 = (B - C) / A, (C - A) / B, (A - B) / C
        half = mpmath.mpf(1) / 2

        def F(t, y):
            p, q, r, w, x, yy, z = y
            return [
                e0 * q * r,
                e1 * r * p,
                e2 * p * q,
                half * (-x * p - yy * q - z * r),
                half * (w * p + yy * r - z * q),
                half * (w * q - x * r + z * p),
                half * (w * r + x * q - yy * p),
            ]

        y0 = [mpmath.mpf(x) for x in (*rc.rates, 1.0, 0.0, 0.0, 0.0)]
        s = time.perf_counter()
        solution = mpmath.odefun(F, 0, y0, tol=tol)
        y = solution(mpmath.mpf(t_end))
        elapsed = time.perf_counter() - s
    err = rotation_error(y, ref)
    setting = f"{dps} digits, tol {tol:g}" if tol else f"{dps} digits, tol ε"
    case.points.append(Point(f"mpmath odefun, {dps} digits", setting, None, elapsed, err))
    _log(f"{case.name}: mpmath {setting}: {elapsed:.2f} s, {err:.2e}")


# ---------------------------------------------------------------------------- rendering
def curves(case: Case) -> list[Curve]:
    """Each method's (wall time, error) points: what a user waits for — our whole ``run()``
    (model build, output evaluation), a peer's whole call."""
    by: dict[str, Curve] = {}
    for p in case.points:
        c = by.setdefault(p.method, Curve(p.method, [], [], []))
        c.times.append(p.run_wall if p.run_wall is not None else p.wall)
        c.errors.append(p.error)
        c.settings.append(p.setting)
    return list(by.values())


def ratio_rows(case: Case, cs: list[Curve]) -> dict[float, tuple[str, dict]]:
    """Per level: the reference method — our fastest double formulation there, else our
    fastest real128 one, else real 256 — and every method's time over its time."""
    out = {}
    for level in case.levels:
        ref = None
        for precision in ("double", "quad", "real256"):
            mine = [
                (c.time_at(level), c)
                for c in cs
                if c.method.startswith("ours") and f", {LABEL[precision]}" in c.method
            ]
            mine = [(t, c) for t, c in mine if math.isfinite(t)]
            if mine:
                ref = min(mine, key=lambda x: x[0])[1]
                break
        if ref is None:
            continue
        row = ratios_at_equal_error(cs, ref.method, [level])[0]
        row.pop("error")
        out[level] = (ref.method, row)
    return out


def cheapest(case: Case, method: str, level: float) -> Point | None:
    """The method's fastest sweep point at least as accurate as ``level``."""
    pts = [p for p in case.points if p.method == method and p.error <= level]
    pts = [p for p in pts if math.isfinite(p.wall)]
    return min(pts, key=lambda p: p.wall) if pts else None


def render(case: Case, figures: Path) -> str:
    cs = curves(case)
    figure = f"bench_wp_{case.name}.png"
    plot(case, cs, figures / figure)
    lines = [
        f"### {case.name}",
        "",
        f"{case.title}. Error: {case.error_measure}, against {case.reference}.",
        "",
        f"![work–precision, {case.name}](figures/{figure})",
        "",
    ]
    methods = [c.method for c in cs]
    rows = ratio_rows(case, cs)
    if rows:
        shown = [
            m for m in methods if any(math.isfinite(r[1].get(m, math.nan)) for r in rows.values())
        ]
        lines += [
            "Wall time of a whole run at equal error (ours: `run()` with its model build and "
            "output evaluation; a peer: its whole call) over the reference method's (– : the "
            "method's sweep does not reach that error):",
            "",
            "| error | relative to | " + " | ".join(shown) + " |",
            "|---|---|" + "---|" * len(shown),
        ]
        for level, (ref, row) in rows.items():
            lines.append(
                f"| {level:.0e} | {ref} | "
                + " | ".join(fmt(row.get(m, math.nan)) for m in shown)
                + " |"
            )
        lines.append("")
    lines += headline(case, rows)
    lines += ["", *commentary(case, rows)]
    lines += [""] + [f"* {n}" for n in case.notes + case.missing]
    lines += [
        "",
        "<details><summary>sweep points</summary>",
        "",
        "| method | setting | steps | order | wall (ms) | error | whole run() (ms) | compile (s) "
        "| notes |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for p in case.points:
        lines.append(
            f"| {p.method} | {p.setting} | {p.steps if p.steps is not None else '–'} | "
            f"{p.order or '–'} | {fmt(p.wall * 1e3)} | {p.error:.2e} | "
            f"{fmt(p.run_wall * 1e3) if p.run_wall is not None else '–'} | "
            f"{f'{p.compile:.2f}' if p.compile is not None else '–'} | {p.extra} |"
        )
    lines += ["", "</details>", ""]
    return "\n".join(lines)


def headline(case: Case, rows: dict) -> list[str]:
    """The ratios at equal error and what they are made of (steps × cost per step), worded
    from the numbers themselves."""
    parts = []
    for level, (ref, row) in rows.items():
        others = {m: r for m, r in row.items() if m != ref and math.isfinite(r)}
        if not others:
            continue
        said = ", ".join(f"{m} {_times(r)}" for m, r in sorted(others.items(), key=lambda x: x[1]))
        parts.append(f"at {level:.0e}, against {ref}: {said}")
    if not parts:
        return ["No two methods reach a common error level in this sweep."]
    out = ["Measured: " + "; ".join(parts) + "."]
    # The tightest level that at least two methods reach, taken apart into steps and the cost
    # of one step (the cheapest sweep point of each method reaching it).
    for level, (_, row) in sorted(rows.items()):
        reached = [m for m, r in row.items() if math.isfinite(r)]
        peers = [m for m in reached if not m.startswith("ours")]
        if len(reached) < 2 or (not peers and any(not m.startswith("ours") for m in row)):
            continue
        pieces = []
        for m in reached:
            p = cheapest(case, m, level)
            if p is None or not p.steps:
                continue
            pieces.append(f"{m} ({p.setting}) {p.steps} steps of {fmt(p.wall / p.steps * 1e6)} µs")
        if len(pieces) >= 2:
            out.append(f"Reaching {level:.0e}: " + "; ".join(pieces) + ".")
        break
    return [" ".join(out)]


def _at(case: Case, method: str, setting: str) -> Point | None:
    return next((p for p in case.points if p.method == method and p.setting == setting), None)


def _best(case: Case, prefix: str) -> Point | None:
    """The most accurate point of the methods whose name starts with ``prefix``."""
    pts = [p for p in case.points if p.method.startswith(prefix) and p.error > 0]
    return min(pts, key=lambda p: p.error) if pts else None


def _us(p: Point) -> float:
    return p.wall / p.steps * 1e6


def commentary(case: Case, rows: dict) -> list[str]:
    """What the ratios are made of, each sentence built from this run's numbers."""
    out = _formulation_commentary(case)
    doubles = [p for p in case.points if p.method.startswith("ours") and ", double" in p.method]
    if not doubles:
        return [" ".join(out)] if out else []
    best_double = min(doubles, key=lambda p: p.error)
    dop = _best(case, "scipy DOP853")
    if dop:
        # Our fastest double formulation where DOP853 reaches too (else at any double level).
        refs = [
            ref
            for _, (ref, row) in sorted(rows.items())
            if ", double" in ref and math.isfinite(row.get("scipy DOP853", math.nan))
        ]
        refs += [ref for _, (ref, _) in rows.items() if ", double" in ref]
        ref_method = refs[0] if refs else best_double.method
        mine = _at(case, ref_method, "1e-16") or best_double
        call = f", each {case.rhs_call * 1e6:.1f} µs from Python" if case.rhs_call else ""
        out.append(
            f"DOP853's steps cost {fmt(_us(dop))} µs (about 12 right-hand-side calls per step"
            f"{call}; the compiled right-hand side is the code our integrator steps with) "
            f"against {fmt(_us(mine))} µs for our order-{mine.order} Taylor step "
            f"({mine.method}, tolerance {mine.setting}); scipy raises any rtol below 100ε to "
            f"100ε, and its best error here is {dop.error:.1e} against our double's "
            f"{best_double.error:.1e}."
        )
    radau, dop6 = _at(case, "scipy Radau", "rtol 1e-06"), _at(case, "scipy DOP853", "rtol 1e-06")
    if radau and dop6:
        out.append(
            "Radau (implicit, the Jacobian compiled as well) takes "
            f"{radau.steps / dop6.steps:.0f}× DOP853's steps at rtol 1e-6 and more time per "
            "step: the case is not stiff (Radau is run on this case only; the others are "
            "conservative too, with no fast decaying modes)."
        )
    out += _ias15_commentary(case, rows, best_double)
    ha = [p for p in doubles if p.method.endswith("high accuracy")]
    if ha:
        plain = min((p for p in doubles if p not in ha), key=lambda p: p.error)
        top = min(ha, key=lambda p: p.error)
        out.append(
            f"heyoka's high-accuracy mode (compensated evaluation of the Taylor polynomials) "
            f"gives {top.error:.1e} at tolerance {top.setting} against {plain.error:.1e} for our "
            f"best plain double run; single runs, so a factor of a few either way is the "
            "round-off's own scatter."
        )
    quad = min(
        (p for p in case.points if "real128" in p.method and p.error < best_double.error),
        key=lambda p: p.wall,
        default=None,
    )
    if quad:
        best_peer = min(
            (p for p in case.points if p.error > 0 and _double_peer(p.method)),
            key=lambda p: p.error,
            default=None,
        )
        beyond = f" (no peer goes below {best_peer.error:.1e})" if best_peer else ""
        out.append(
            f"Double stops at {best_double.error:.1e}{beyond}; the cheapest real128 point below "
            f"it ({quad.method}, {quad.setting}: {quad.error:.1e}) costs "
            f"{quad.wall / best_double.wall:.0f}× that double run — real128 arithmetic is in "
            f"software, {_us(quad) / _us(best_double):.0f}× the time per step here."
        )
    out += _extended_commentary(case)
    return [" ".join(out)] if out else []


def _formulation_commentary(case: Case) -> list[str]:
    out = []
    pairs = {
        "ours rodrigues, double": (
            "ours quaternion, double",
            "the Rodrigues chart takes {s}× the quaternion's steps (the pole of tan(θ/2) at "
            "θ = π bounds its Taylor step; {extra}) at {c}× the time per step",
        ),
        "ours cayley, double": (
            "ours cartesian, double",
            "Cayley's variables take {s}× the Cartesian steps at {c}× the time per step (Ω's "
            "gradient composed with the frame tables)",
        ),
        "ours quaternion, double": (
            "ours cartesian, double",
            "the orbit-frame quaternion takes {s}× the Cartesian steps at {c}× the time per step",
        ),
        "ours elements, double": (
            "ours canonical, double",
            "Hamilton's elements take {s}× the canonical steps at {c}× the time per step "
            "(Kepler's equation and the gradient of H₂ through it, compact mode)",
        ),
    }
    for method, (base, text) in pairs.items():
        a, b = _at(case, method, "1e-16"), _at(case, base, "1e-16")
        if a and b:
            s, c = a.steps / b.steps, _us(a) / _us(b)
            extra = a.extra or "no re-basing"
            out.append(
                f"At tolerance 1e-16, {text.format(s=f'{s:.2g}', c=f'{c:.2g}', extra=extra)}."
            )
    loose_e = _at(case, "ours elements, double", "1e-6")
    loose_c = _at(case, "ours canonical, double", "1e-6")
    if loose_e and loose_c and loose_e.error < loose_c.error:
        out.append(
            f"At tolerance 1e-6 the elements are the more accurate ({loose_e.error:.1e} against "
            f"{loose_c.error:.1e}): they move by O(m/M), so the same local tolerance is a smaller "
            "error in the positions."
        )
    return out


def _ias15_commentary(case: Case, rows: dict, best_double: Point) -> list[str]:
    ias = [p for p in case.points if p.method == "REBOUND IAS15"]
    if not ias:
        return []
    out = []
    common = [
        (level, ref)
        for level, (ref, row) in sorted(rows.items())
        if math.isfinite(row.get("REBOUND IAS15", math.nan))
    ]
    if common:
        level, ref = common[0]
        mine, theirs = cheapest(case, ref, level), cheapest(case, "REBOUND IAS15", level)
        if mine and theirs:
            fewer = "fewer" if theirs.steps < mine.steps else "more"
            dearer = "dearer" if _us(theirs) > _us(mine) else "cheaper"
            out.append(
                f"At {level:.0e}, IAS15's cheapest point ({theirs.setting}) takes {theirs.steps} "
                f"steps of {fmt(_us(theirs))} µs against {mine.steps} of {fmt(_us(mine))} µs for "
                f"{mine.method} ({mine.setting}): {fewer}, {dearer} steps — an IAS15 step "
                "evaluates the forces at 7 substeps per predictor–corrector iteration, two or more "
                "iterations a step."
            )
    best = min(ias, key=lambda p: p.error)
    floors: dict[str, float] = {}
    for p in case.points:
        if p.method.startswith("ours") and ", double" in p.method:
            floors[p.method] = min(floors.get(p.method, math.inf), p.error)
    below = [m for m, e in floors.items() if e < best.error]
    out.append(
        f"Most accurate points: IAS15 {best.error:.1e} ({best.setting}); "
        + ", ".join(f"{m.removeprefix('ours ')} {e:.1e}" for m, e in floors.items())
        + ". These are round-off floors, and one run is one sample of a random walk: only "
        "factors well beyond a few mean something. "
        + (
            "IAS15's is below all of ours in double: it keeps its round-off small by "
            "compensated summation (Rein & Spiegel 2015)."
            if not below
            else f"{len(below)} of our {len(floors)} double variants "
            f"{'goes' if len(below) == 1 else 'go'} below IAS15's."
        )
    )
    tight = [p for p in ias if _eps(p) <= 1e-6]
    if len(tight) >= 2 and any(b.error > a.error for a, b in zip(tight, tight[1:], strict=False)):
        out.append(
            "Below ε = 1e-6 its error no longer falls with ε ("
            + ", ".join(f"{p.error:.0e} at {p.setting.removeprefix('ε ')}" for p in tight)
            + "): round-off, not truncation."
        )
    return out


def _double_peer(method: str) -> bool:
    return method.startswith(("scipy", "REBOUND"))


def _eps(p: Point) -> float:
    return float(p.setting.split()[1])


def _extended_commentary(case: Case) -> list[str]:
    out = []
    q, r113 = (
        _at(case, "ours quaternion, real128", "1e-32"),
        _at(case, "ours quaternion, real 113", "1e-32"),
    )
    if q and r113:
        out.append(
            f"At tolerance 1e-32, MPFR at 113 bits steps in {r113.wall / q.wall:.2g}× the time "
            "of real128 (libquadmath), with the same errors."
        )
    mp = [p for p in case.points if p.method.startswith("mpmath")]
    if mp:
        out.append(
            "mpmath's `odefun` builds each Taylor series from finite differences of Euler steps "
            "carried at (degree + 1)× the working precision, in pure Python "
            "(mpmath/calculus/odes.py): "
            + "; ".join(f"{p.setting}: {p.wall:.2f} s for {p.error:.1e}" for p in mp)
            + "."
        )
    return out


def _times(r: float) -> str:
    x = r if r >= 1 else 1 / r
    text = f"{x:.0f}×" if x >= 10 else f"{x:.2g}×"
    return f"{text} the time" if r >= 1 else f"{text} faster"


def plot(case: Case, cs: list[Curve], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.6))
    for c in cs:
        # In sweep order (tolerance tightening): where round-off takes over, the error turns
        # back, and the line shows it.
        pts = [(e, t) for e, t in zip(c.errors, c.times, strict=True) if e > 0 and math.isfinite(t)]
        if not pts:
            continue
        style = "-o" if c.method.startswith("ours") else "--s"
        ax.loglog([p[0] for p in pts], [p[1] * 1e3 for p in pts], style, ms=4, label=c.method)
    ax.set_xlabel("error at the final time")
    ax.set_ylabel("wall time (ms)")
    ax.set_title(f"work–precision: {case.name}")
    ax.invert_xaxis()
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def fixed_cost_table(cases: Sequence[Case]) -> list[str]:
    lines = [
        "| case | method | run() over one step (ms) |",
        "|---|---|---|",
    ]
    for case in cases:
        for method, cost in case.fixed_cost.items():
            lines.append(f"| {case.name} | {method} | {fmt(cost * 1e3)} |")
    return lines


# ---------------------------------------------------------------------------- driver
def run(quick: bool, figures: Path) -> str:
    """The Markdown body of the work–precision section; plots into ``figures``."""
    global REPEAT
    figures.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    REPEAT = 2 if quick else 5  # the smoke run must stay within seconds
    periods = 2 if quick else 20
    cases = [
        free_body("free_regular", "generic", periods, quick),
        free_body("free_separatrix", "separatrix_p6", periods, quick),
        heavy_top(quick),
        orbit_j2(quick),
        planets(quick),
        free_extended(quick),
    ]
    body = [
        "## Work–precision",
        "",
        INTRO,
        "",
        *[render(c, figures) for c in cases],
        "### Fixed cost of a run",
        "",
        "What one `cayley_heyoka.run` call costs besides stepping (building the model, the "
        "cache lookup, the copy of the compiled integrator, evaluating the outputs), measured "
        "as a run over a span of 1e-6 (one step). It is not in the wall times above; a short "
        "run pays it in full.",
        "",
        *fixed_cost_table(cases),
    ]
    _log(f"total {time.perf_counter() - t0:.0f} s")
    return "\n".join(body)


INTRO = (
    "Error at the final time against wall time over a sweep of each method's tolerance, every "
    "method in one process on the same machine state. **Ours**: `cayley_heyoka.run` with "
    "`integrator.tolerance` swept, output at the start and end only. The tolerance is compiled "
    "in, so each point compiles once; that compile is timed apart (the `compile` column, small "
    "when heyoka's disk cache already had the code) and excluded. A point's wall time is the "
    "stepping: the compiled integrator `run` uses, stepped over the span with `run`'s calls and "
    "event handling (chart re-basings, revolutions of ρ), the least of up to 5 repeats, its "
    "step count checked equal to `run`'s. What `run` costs besides — building the model, the "
    "cache lookup, the copy of the integrator, the outputs — is the *whole run()* column, and "
    "the table at the end. Errors come from `run`'s results. **scipy** `solve_ivp` integrates "
    "the same equations, the right-hand side (and for Radau the Jacobian) compiled by heyoka "
    "into a `cfunc` — fair to scipy: it pays its own Python loop, not a slow numpy right-hand "
    "side; `atol = rtol × |v|` for each vector v of the state at t = 0 (rates, quaternion, "
    "position, velocity, momentum). **REBOUND IAS15**: `epsilon` 1e-2 … 1e-8 and its default, "
    "`adaptive_mode` at its default; only `integrate` is timed. **mpmath** `odefun` (its "
    "Taylor method, pure Python) on `free_extended`. The ratio tables divide each method's time "
    "at equal error (log–log interpolation between sweep points; – where its sweep does not "
    "reach the level) by that of our fastest double formulation, or our fastest real128 one "
    "where double does not reach the level. Wall times come from a 2-core machine shared with "
    "other jobs: read the ratios, measured side by side, not the absolute times."
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--out", type=Path, default=HERE / "BENCHMARKS.md")
    args = parser.parse_args(argv)
    import benchmarks

    return benchmarks.main(
        ["--only", "work_precision", "--out", str(args.out)] + (["--quick"] if args.quick else [])
    )


if __name__ == "__main__":
    sys.exit(main())
