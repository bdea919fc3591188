"""What users run through the engine, against raw heyoka: a short run() and a sweep.

Rows (issue 16's table, each ours ÷ its floor, timed interleaved in one process):

* ``run()`` of a short span (about 10 steps) of a bundled scene without events, its integrator
  already compiled — against heyoka alone doing the same work with the integrator kept: a
  reset of its time and state and ``propagate_until`` (the bundled free body in Rodrigues
  parameters, and in a quaternion); beside each, a diagnostic (not judged): that floor doing
  also what a run gives — the states on the output grid, the compiled outputs there and their
  finiteness — against the bare floor;
* ``run_sweep`` of a conservation study of free bodies (the bundled random study, its member
  count raised) — against a hand-written heyoka batch integrator of the same equations looping
  over the members, recording the same output times, on as many threads as the sweep's
  workers: a short span (t = 0…100) on one worker, and t = 0…1000 on every core;
* ``run_sweep`` of members with terminal events (Cayley's orbit and ρ's revolutions, a
  Rodrigues chart and its re-basings), batched in lanes with their handlers — against the same
  members (their models' numbers) through a hand-written heyoka batch integrator of the
  model's equations and event functions, its callbacks doing the revolution / re-basing per
  lane inside heyoka's call, one ``propagate_grid`` a batch, on as many threads as the sweep's
  workers each looping over its share of the batches; checked to take the same steps and
  events member by member and to end in the same state (stderr lists them).

    python validation/users_engine.py [--quick]
"""

from __future__ import annotations

import argparse
import copy
import math
import os
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import heyoka as hy
import mpmath
import numpy as np
from users_common import Row, interleaved, table
from users_rotation import fold, whole_attitude

import cayley_heyoka as ch
from cayley_heyoka.core import engine
from cayley_heyoka.workflows.study import Study, load_study
from cayley_heyoka.workflows.sweep import run_sweep

HERE = Path(__file__).resolve().parent

EXAMPLES = HERE.parent / "examples"


def _short_scene(formulation: str) -> ch.Scene:
    data = ch.load_scene(EXAMPLES / "free_body.toml").to_dict()
    data["output"] = {"times": {"start": "0", "stop": "3", "count": 2}}
    data["attitude"] = {"formulation": formulation}
    if formulation == "quaternion":
        data["initial"] = {"rates": data["initial"]["rates"], "quaternion": ["1", "0", "0", "0"]}
    return ch.Scene.from_dict(data)


def short_runs(quick: bool) -> list[Row]:
    rows = []
    for formulation in ("rodrigues", "quaternion"):
        scene = _short_scene(formulation)
        result = ch.run(scene)
        prop = engine.Propagation(scene)
        template = prop.compiled.integrator
        prop.release()
        x0 = np.array(prop.model.initial_state, dtype=float)
        end = float(scene.output.time_grid(scene.integrator.precision)[-1])

        kept = copy.deepcopy(template)

        def floor(ta=kept, x0=x0, end=end) -> None:
            ta.time = 0.0
            ta.state[:] = x0
            ta.propagate_until(end)

        ratios, ours, raw = interleaved(
            lambda scene=scene: ch.run(scene), floor, repeats=5 if quick else 15, inner=50
        )
        rows.append(
            Row(
                f"`run()` of a short span, bundled free body ({formulation}), compiled",
                ratios,
                1.5,
                "the kept integrator: state reset + `propagate_until`",
                f"{result.counters['steps']} steps; ours {ours * 1e6:.0f} µs, "
                f"floor {raw * 1e6:.0f} µs",
            )
        )
        rows.append(_with_outputs(scene, prop, kept, x0, floor, quick))
    return rows


def _with_outputs(scene: ch.Scene, prop: Any, ta: Any, x0: np.ndarray, floor, quick) -> Row:
    """A diagnostic beside a short run's row: the floor that also gives what a ``run()``
    gives — the states on the output grid (``propagate_grid``), the compiled outputs and
    monitors evaluated there, their finiteness checked — against the bare floor. What
    ``run()`` costs beyond it is the engine's own work (checks, signals, the ``Result``)."""
    evaluator = prop.compiled.evaluator
    grid = np.asarray(scene.time_grid, dtype=float)
    held = evaluator.nparams
    pars = np.asarray(prop.model.pars.values[:held], dtype=float)
    columns = np.repeat(pars[:, None], len(grid), axis=1) if held else None

    def outputs() -> None:
        ta.time = float(grid[0])
        ta.state[:] = x0
        states = ta.propagate_grid(grid)[-1]
        kwargs = {"time": grid} if columns is None else {"time": grid, "pars": columns}
        values = evaluator(np.ascontiguousarray(states.T), **kwargs)
        if not np.isfinite(values).all():
            raise RuntimeError("the short run's outputs are not finite")

    ratios, with_outputs, raw = interleaved(outputs, floor, repeats=5 if quick else 15, inner=50)
    return Row(
        f"the same span, the floor with the run's outputs (diagnostic, {len(grid)} output times)",
        ratios,
        None,
        "the kept integrator: state reset + `propagate_until`",
        f"reset + `propagate_grid` + the compiled outputs and their finiteness: "
        f"{with_outputs * 1e6:.0f} µs against {raw * 1e6:.0f} µs",
    )


def _hand_written_batch(width: int) -> hy.taylor_adaptive_batch:
    """Euler's equations and the quaternion kinematics, written directly in heyoka."""
    p, q, r, qw, qx, qy, qz = hy.make_vars("p", "q", "r", "qw", "qx", "qy", "qz")
    a, b, c = hy.par[0], hy.par[1], hy.par[2]
    half = hy.expression(0.5)
    system = [
        (p, (b - c) / a * q * r),
        (q, (c - a) / b * r * p),
        (r, (a - b) / c * p * q),
        (qw, half * (-qx * p - qy * q - qz * r)),
        (qx, half * (qw * p + qy * r - qz * q)),
        (qy, half * (qw * q + qz * p - qx * r)),
        (qz, half * (qw * r + qx * q - qy * p)),
    ]
    state = np.zeros((7, width))
    state[3] = 1.0
    return hy.taylor_adaptive_batch(system, state, pars=np.ones((3, width)))


def sweep(quick: bool) -> list[Row]:
    rows = []
    cores = os.cpu_count() or 1
    for stop, workers, target in (("100", 1, 1.5), ("1000", cores, 1.2)):
        rows.append(_sweep_row(quick, stop, workers, target))
    return rows


def _sweep_row(quick: bool, stop: str, workers: int, target: float) -> Row:
    base = load_study(EXAMPLES / "studies" / "free_body_random.toml").to_dict()
    base.pop("scene_file", None)
    members = 200 if quick else 2000
    base["scene"]["output"] = {"times": {"start": "0", "stop": stop, "count": 101}}
    data = {**base, "sweep": {**base["sweep"], "count": members}, "run": {"workers": workers}}
    study = Study.from_dict(data)
    scene0 = study.member_scene(0, study.members()[0])
    grid = scene0.time_grid
    values = study.members()
    inertia = np.array([float(x) for x in scene0.source["body"]["inertia"]])
    rates = np.array([[float(x) for x in v] for v in values])
    width = hy.recommended_simd_size()
    template = _hand_written_batch(width)
    run_sweep(Study.from_dict({**data, "sweep": {**data["sweep"], "count": 16}}))  # compile
    blocks = list(range(0, members, width))

    def share(ta, starts) -> int:
        steps = 0
        table = np.repeat(grid[:, None], width, axis=1)
        for lo in starts:
            block = rates[lo : lo + width]
            block = np.vstack([block, np.repeat(block[-1:], width - len(block), axis=0)])
            ta.set_time(0.0)
            ta.state[:3] = block.T
            ta.state[3] = 1.0
            ta.state[4:] = 0.0
            ta.propagate_grid(table)
            steps += sum(res[3] for res in ta.propagate_res[: min(width, members - lo)])
        return steps

    def floor() -> int:
        # One integrator per thread, each a share of the blocks (heyoka releases the GIL).
        integrators = [copy.deepcopy(template) for _ in range(workers)]
        for ta in integrators:
            ta.pars[:] = inertia[:, None]
        if workers == 1:
            return share(integrators[0], blocks)
        with ThreadPoolExecutor(workers) as pool:
            parts = pool.map(share, integrators, [blocks[k::workers] for k in range(workers)])
            return sum(parts)

    result = run_sweep(study)
    ratios, ours, raw = interleaved(
        lambda: run_sweep(study), floor, repeats=3 if quick else 5, inner=1
    )
    steps = int(result.steps.sum())
    threads = "one thread" if workers == 1 else f"{workers} threads"
    who = "1 worker" if workers == 1 else "every core"
    return Row(
        f"`run_sweep`: {members} free bodies (quaternion, t = 0…{stop}, 101 outputs), {who}",
        ratios,
        target,
        f"hand-written `taylor_adaptive_batch` loop (width {width}), {threads}",
        f"{steps / members:.0f} steps a member; ours {steps / ours / 1e6:.2f} M "
        f"body-steps/s, floor {floor() / raw / 1e6:.2f} M; paths "
        f"{result.metadata['paths']}",
    )


TERMINAL_CASES: dict[str, dict] = {
    "Cayley's orbit (ρ's revolutions), J2": {
        "orbit": {
            "mu": "1",
            "position": ["0.9", "0.2", "0.1"],
            "velocity": ["-0.25", "0.85", "0.45"],
            "formulation": "cayley",
        },
        "perturbations": {"zonal": {"J2": "1.0826e-3", "radius": "0.8", "axis": ["0", "0", "1"]}},
        "output": {"times": {"start": "0", "stop": "60", "count": "61"}},
    },
    "free body in Rodrigues parameters (chart re-basings)": {
        "body": {"inertia": ["1", "1.5", "2.5"]},
        "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        "attitude": {"formulation": "rodrigues"},
        "output": {"times": {"start": "0", "stop": "100", "count": "101"}},
    },
}


def terminal_study(label: str, members: int) -> Study:
    """The study of a terminal-event row: ``members`` members, one initial number swept."""
    scene = TERMINAL_CASES[label]
    path = "orbit.velocity[1]" if "orbit" in scene else "initial.rates[0]"
    base = 0.85 if "orbit" in scene else 0.3
    values = [f"{base * (1 + 0.05 * k / members):.6f}" for k in range(members)]
    return Study.from_dict(
        {"scene": scene, "sweep": {"kind": "grid", "parameters": {path: values}}}
    )


class _LaneRevolutions:
    """Hand-written batch callback of the event ρ_s = C: one revolution of the lane's ρ moved
    into its parameters (ρ_s −= C; offset k C and phase k (C − 2π), each rounded once from
    the exact integer product, as :mod:`cayley_heyoka.orbit.revolutions` does)."""

    def __init__(self, width: int, rho: int, offset: int, phase: int) -> None:
        self.width, self.rho, self.offset, self.phase = width, rho, offset, phase
        self.C = math.tau  # 2π rounded to double
        self.mc, self.ec = mpmath.mpf(self.C).man_exp
        with mpmath.workprec(53 + 128):  # C − 2π to enough bits that k (C − 2π) rounds once
            d = mpmath.mpf(self.C) - 2 * mpmath.pi
        md, self.ed = d.man_exp  # |d|'s mantissa
        self.md = -int(md) if d < 0 else int(md)
        self.k: list[int] = []
        self.changes: list[list[tuple[float, float]]] = []

    def __deepcopy__(self, memo: dict) -> _LaneRevolutions:
        return _LaneRevolutions(self.width, self.rho, self.offset, self.phase)

    def start(self, pars: np.ndarray) -> None:
        self.k = [round(float(o) / self.C) for o in pars[self.offset]]
        self.changes = [[] for _ in range(self.width)]

    def __call__(self, ta: Any, d_sgn: Any, lane: int) -> bool:
        ta.state[self.rho, lane] -= self.C
        k = self.k[lane] = self.k[lane] + 1
        offset = math.ldexp(float(k * self.mc), self.ec)
        pars = ta.pars
        pars[self.offset, lane] = offset
        pars[self.phase, lane] = math.ldexp(float(k * self.md), self.ed)
        self.changes[lane].append((ta.time[lane], offset))
        return True

    def outputs(self, lane: int, grid: np.ndarray, states: np.ndarray, first: float) -> np.ndarray:
        """The lane's states with the continuous ρ (ρ_s + its offset at each output)."""
        times = np.array([t for t, _ in self.changes[lane]])
        offsets = np.array([first] + [o for _, o in self.changes[lane]])
        out = states.copy()
        out[:, self.rho] += offsets[np.searchsorted(times, grid, side="left")]
        return out


class _LaneCharts:
    """Hand-written batch callback of the event κ = κ_max: the lane's chart folded into its
    base (users_rotation.fold, the algebra of the single-integrator floor) and restarted."""

    def __init__(self, width: int, chart: int) -> None:
        self.width, self.chart = width, chart
        self.base: list[list[float]] = []
        self.changes: list[list[tuple[float, list[float]]]] = []

    def __deepcopy__(self, memo: dict) -> _LaneCharts:
        return _LaneCharts(self.width, self.chart)

    def start(self, bases: np.ndarray) -> None:
        self.base = bases.T.tolist()
        self.changes = [[] for _ in range(self.width)]

    def __call__(self, ta: Any, d_sgn: Any, lane: int) -> bool:
        st, j = ta.state, self.chart
        lam, mu, nu = st[j : j + 3, lane].tolist()
        new = self.base[lane] = fold(self.base[lane], lam, mu, nu)
        self.changes[lane].append((ta.time[lane], new))
        st[j : j + 3, lane] = 0.0
        return True

    def outputs(self, lane: int, grid: np.ndarray, states: np.ndarray, first: list) -> np.ndarray:
        """The lane's states with the whole attitude's λ, μ, ν (base ⊗ chart at each output)."""
        times = np.array([t for t, _ in self.changes[lane]])
        Q = np.array([first] + [b for _, b in self.changes[lane]])
        Q = Q[np.searchsorted(times, grid, side="left")]
        j = self.chart
        out = states.copy()
        out[:, j : j + 3] = whole_attitude(Q, states[:, j], states[:, j + 1], states[:, j + 2]).T
        return out


class _LaneStop:
    """Hand-written batch callback of an event that ends the lane (the orbit's equatorial
    hand-over, which none of these members reaches: counted, and checked to be zero)."""

    def __init__(self) -> None:
        self.count = 0

    def __deepcopy__(self, memo: dict) -> _LaneStop:
        return _LaneStop()

    def __call__(self, ta: Any, d_sgn: Any, lane: int) -> bool:
        self.count += 1
        return False


class HandWrittenLanes:
    """The floor of a terminal-event sweep: the members integrated by a hand-written heyoka
    batch integrator (width ``hy.recommended_simd_size()``), the model's equations and event
    functions, hand-written callbacks doing the revolution / re-basing per lane inside heyoka's
    call, one ``propagate_grid`` a batch over the output times, ``workers`` threads each
    looping over its share of the batches.

    ``initial`` and ``pars`` are the members' numbers as the sweep integrates them (their
    models'); the model is any member's (the structure).
    """

    def __init__(
        self, model: Any, initial: np.ndarray, pars: np.ndarray, grid: np.ndarray, workers: int
    ) -> None:
        width = self.width = hy.recommended_simd_size()
        names = [str(v) for v, _ in model.system]
        held = self.held = model.integrator_parameters()
        self.initial, self.pars, self.grid, self.workers = initial, pars, grid, workers
        self.kind = "orbit" if "orbit.rho_offset" in model.pars.names else "chart"
        events = []
        for spec in model.terminal:
            if spec.counter == "revolutions":
                cb: Any = _LaneRevolutions(
                    width,
                    names.index("rho"),
                    model.pars.index("orbit.rho_offset"),
                    model.pars.index("orbit.rho_phase"),
                )
            elif spec.counter == "rebasings":
                cb = _LaneCharts(width, names.index("lambda"))
                self.base_index = model.pars.index("chart.base[0]")
            else:
                cb = _LaneStop()
            direction = {1: hy.event_direction.positive, -1: hy.event_direction.negative}
            events.append(
                hy.t_event_batch(
                    spec.expression,
                    callback=cb,
                    direction=direction.get(spec.direction, hy.event_direction.any),
                )
            )
        self.template = hy.taylor_adaptive_batch(
            model.system,
            np.repeat(initial[:1].T, width, axis=1),
            pars=np.repeat(pars[:1, :held].T, width, axis=1),
            t_events=events,
        )
        self.table = np.repeat(grid[:, None], width, axis=1)
        n = len(initial)
        self.blocks = list(range(0, n, width))
        self.steps = np.zeros(n, dtype=np.int64)
        self.events = np.zeros(n, dtype=np.int64)
        self.stops = 0
        self.outputs = np.full((n, len(grid), len(names)), np.nan)

    def _share(self, ta: Any, starts: list[int]) -> None:
        width, n, held = self.width, len(self.initial), self.held
        acting = ta.t_events[0].callback  # the revolution or re-basing callback
        done = hy.taylor_outcome.time_limit
        for lo in starts:
            lanes = list(range(lo, min(lo + width, n)))
            lanes += [lanes[-1]] * (width - len(lanes))  # spare lanes copy the last member
            ta.set_time(float(self.grid[0]))
            ta.state[:] = self.initial[lanes].T
            ta.pars[:] = self.pars[lanes, :held].T
            ta.reset_cooldowns()
            if self.kind == "orbit":
                acting.start(ta.pars)
                first = [float(ta.pars[acting.offset, j]) for j in range(width)]
            else:
                i = self.base_index
                acting.start(ta.pars[i : i + 4])
                first = [list(b) for b in acting.base]
            out = ta.propagate_grid(self.table)[-1]
            for j, res in enumerate(ta.propagate_res[: min(width, n - lo)]):
                if res[0] != done:
                    raise RuntimeError(f"the floor's member {lo + j} stopped with {res[0]}")
                self.steps[lo + j] = res[3]
                self.events[lo + j] = len(acting.changes[j])
                self.outputs[lo + j] = acting.outputs(j, self.grid, out[:, :, j], first[j])
        self.stops += sum(ev.callback.count for ev in ta.t_events[1:])

    def __call__(self) -> None:
        self.stops = 0
        # One integrator per thread, each a share of the batches (heyoka releases the GIL).
        integrators = [copy.deepcopy(self.template) for _ in range(self.workers)]
        shares = [self.blocks[k :: self.workers] for k in range(self.workers)]
        if self.workers == 1:
            self._share(integrators[0], shares[0])
            return
        with ThreadPoolExecutor(self.workers) as pool:
            list(pool.map(self._share, integrators, shares))


def _our_lanes(study: Study) -> tuple[Any, np.ndarray, np.ndarray, list]:
    """The sweep's structure, its members' numbers, and their lanes' results (the path
    ``run_sweep`` takes for these members: their counters)."""
    from cayley_heyoka.core import lanes
    from cayley_heyoka.workflows.members import prepare_members
    from cayley_heyoka.workflows.sweep import layout_of

    listed = list(enumerate(study.members()))
    _, groups = prepare_members(study, listed, layout_of(study))
    (group,) = groups.values()
    model, scene0 = group.model, group.scene
    initial = np.array([np.asarray(e.initial, dtype=float) for e in group.entries])
    pars = np.array([np.asarray(e.pars, dtype=float) for e in group.entries])
    runs = lanes.integrate_lanes(
        model, scene0.integrator, scene0.time_grid, initial, pars, os.cpu_count() or 1
    )
    return model, initial, pars, runs


def _per_member(label: str, ours: np.ndarray, floor: np.ndarray) -> str:
    """One line per 16 members: ours/floor, for stderr."""
    pairs = [f"{a}/{b}" for a, b in zip(ours.tolist(), floor.tolist(), strict=True)]
    lines = [" ".join(pairs[k : k + 16]) for k in range(0, len(pairs), 16)]
    return f"  {label} (ours/floor, member by member):\n    " + "\n    ".join(lines)


def terminal_sweep(quick: bool) -> list[Row]:
    """Members whose terminal events act between steps, in lanes, against the same members
    through a hand-written heyoka batch integrator (:class:`HandWrittenLanes`)."""
    members = 32 if quick else 256
    workers = os.cpu_count() or 1
    rows = []
    for label in TERMINAL_CASES:
        study = terminal_study(label, members)
        model, initial, pars, runs = _our_lanes(study)
        grid = study.member_scene(0, study.members()[0]).time_grid
        floor = HandWrittenLanes(model, initial, pars, grid, workers)
        result = run_sweep(study)  # compiles, and the figures checked below
        floor()
        counter = model.terminal[0].counter
        ours_events = np.array([r.counters[counter] for r in runs])
        if not (np.array_equal(result.steps, [r.counters["steps"] for r in runs])):
            raise RuntimeError("run_sweep's steps differ from its lanes'")
        same_steps = int(np.count_nonzero(result.steps == floor.steps))
        same_events = int(np.count_nonzero(ours_events == floor.events))
        print(_per_member(f"{label}: steps", result.steps, floor.steps), file=sys.stderr)
        print(_per_member(f"{label}: {counter}", ours_events, floor.events), file=sys.stderr)
        names = [str(v) for v, _ in model.system]
        columns = [result.final_names.index(v) for v in names]
        ours_final = np.asarray(result.final_state[:, columns], dtype=float)
        theirs = floor.outputs[:, -1, :]
        scale = np.maximum(1.0, np.abs(theirs))
        agree = float(np.max(np.abs(ours_final - theirs) / scale))
        print(
            f"  {label}: final {', '.join(names)}: max |ours − floor| / max(1, |floor|) = "
            f"{agree:.2e}; floor's stopping events {floor.stops}",
            file=sys.stderr,
        )
        ratios, ours, raw = interleaved(
            lambda study=study: run_sweep(study), floor, repeats=3 if quick else 5
        )
        steps = int(result.steps.sum())
        rows.append(
            Row(
                f"`run_sweep`: {members} members with terminal events, {label}",
                ratios,
                1.3,
                f"hand-written `taylor_adaptive_batch` (width {floor.width}, the model's "
                f"equations), {counter} in the batch `t_event` callback, `propagate_grid`, "
                f"{workers} threads",
                f"steps ours = floor for {same_steps}/{members} members "
                f"({steps / members:.0f} a member), {counter} for {same_events}/{members} "
                f"({int(ours_events.sum()) / members:.1f} a member); final state agrees to "
                f"{agree:.1e}; ours {ours * 1e3:.1f} ms, floor {raw * 1e3:.1f} ms; paths "
                f"{result.metadata['paths']}",
                {"ours": ours, "floor": raw},
            )
        )
    return rows


def rows(quick: bool) -> list[Row]:
    return short_runs(quick) + sweep(quick) + terminal_sweep(quick)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    print(table(rows(args.quick)))


if __name__ == "__main__":
    main()
