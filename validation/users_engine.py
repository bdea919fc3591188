"""What users run through the engine, against raw heyoka: a short run() and a sweep.

Rows (issue 16's table, each ours ÷ its floor, timed interleaved in one process):

* ``run()`` of a short span (about 10 steps) of a bundled scene without events, its integrator
  already compiled — against heyoka alone doing the same work with the integrator kept: a
  reset of its time and state and ``propagate_until`` (the bundled free body in Rodrigues
  parameters, and in a quaternion);
* ``run_sweep`` of a conservation study of free bodies (the bundled random study, its member
  count raised) — against a hand-written heyoka batch integrator of the same equations looping
  over the members, recording the same output times, on as many threads as the sweep's
  workers: a short span (t = 0…100) on one worker, and t = 0…1000 on every core;
* ``run_sweep`` of members with terminal events (Cayley's orbit, a Rodrigues chart), batched in
  lanes with their handlers — against ``run()`` of each member on every core, the path such
  sweeps took before (no hand-written floor: the handlers are the point).

    python validation/users_engine.py [--quick]
"""

from __future__ import annotations

import argparse
import copy
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import heyoka as hy
import numpy as np
from users_common import Row, interleaved, table

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
    return rows


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


def terminal_sweep(quick: bool) -> list[Row]:
    """Members whose terminal events act between steps, in lanes against run() per member."""
    cases = {
        "Cayley's orbit (ρ's revolutions), J2": {
            "orbit": {
                "mu": "1",
                "position": ["0.9", "0.2", "0.1"],
                "velocity": ["-0.25", "0.85", "0.45"],
                "formulation": "cayley",
            },
            "perturbations": {
                "zonal": {"J2": "1.0826e-3", "radius": "0.8", "axis": ["0", "0", "1"]}
            },
            "output": {"times": {"start": "0", "stop": "60", "count": "61"}},
        },
        "free body in Rodrigues parameters (chart re-basings)": {
            "body": {"inertia": ["1", "1.5", "2.5"]},
            "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
            "attitude": {"formulation": "rodrigues"},
            "output": {"times": {"start": "0", "stop": "100", "count": "101"}},
        },
    }
    members = 32 if quick else 256
    rows = []
    for label, scene in cases.items():
        path = "orbit.velocity[1]" if "orbit" in scene else "initial.rates[0]"
        base = 0.85 if "orbit" in scene else 0.3
        values = [f"{base * (1 + 0.05 * k / members):.6f}" for k in range(members)]
        study = Study.from_dict(
            {"scene": scene, "sweep": {"kind": "grid", "parameters": {path: values}}}
        )
        listed = list(enumerate(study.members()))
        run_sweep(study)  # compile both ways
        ch.run(study.member_scene(*listed[0]))

        def floor(study=study, listed=listed) -> None:
            # As the sweep does, and as the sweep did before: each member's scene made from the
            # study (validated), then run().
            with ThreadPoolExecutor() as pool:
                list(pool.map(lambda m: ch.run(study.member_scene(*m)), listed))

        result = run_sweep(study)
        ratios, ours, raw = interleaved(
            lambda study=study: run_sweep(study), floor, repeats=3 if quick else 5
        )
        rows.append(
            Row(
                f"`run_sweep`: {members} members with terminal events, {label}",
                ratios,
                1.0,
                "`run()` of each member on every core (threads)",
                f"{int(result.steps.sum()) // members} steps a member; paths "
                f"{result.metadata['paths']}",
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
