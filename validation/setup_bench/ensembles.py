"""Ensembles: members per second of a loop of ``run()``, of heyoka's batch mode and its
ensemble propagation, and of :func:`cayley_heyoka.workflows.ensemble.propagate_ensemble`, on
every system of :data:`.cases.SYSTEMS` (extrapolated where a size is infeasible)."""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from typing import Any

import heyoka as hy
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.core import compiler, lanes
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows import ensemble as ens

from .cases import SYSTEMS, System, with_times
from .results import Throughput
from .tables import throughput_row

RUN_LOOP = "loop of run(), one scene per member"


def _member_states(system: System, dicts: list[dict]) -> np.ndarray:
    """The members' model states, as the scene would start them (built without a model)."""
    if system.scene.family == "rotation":
        rows = []
        for d in dicts:
            # As the scene starts it (rotation/scene.py): normalised again, w >= 0.
            q = np.array(d["initial"]["quaternion"])
            q = q / np.sqrt(np.sum(q * q))
            rows.append([*d["initial"]["rates"], *(-q if q[0] < 0 else q)])
        return np.array(rows)
    return np.array([[*d["orbit"]["position"], *d["orbit"]["velocity"]] for d in dicts])


def _measure(fn: Callable[[], tuple[np.ndarray, int]]) -> tuple[float, float, np.ndarray, int]:
    w0, c0 = time.perf_counter(), time.process_time()
    states, steps = fn()
    return time.perf_counter() - w0, time.process_time() - c0, states, steps


def _run_loop(system: System, dicts: list[dict]) -> tuple[np.ndarray, int]:
    names = ens.ensemble_state(system.scene)[0]
    out, steps = [], 0
    for d in dicts:
        result = ch.run(ch.Scene.from_dict(with_times(d, system.t_end)))
        out.append([result[n][-1] for n in names])
        steps += result.counters["steps"]
    return np.array(out), steps


def _heyoka_ensemble(system: System, X: np.ndarray, batch: bool) -> tuple[np.ndarray, int]:
    """heyoka's ensemble_propagate_until(_batch), in chunks of 1000 calls: it deep-copies the
    integrator for every call and returns them all, so one call over 10⁵ members would hold
    10⁵ integrators at once."""
    model = FAMILIES[system.scene.family].build(system.scene)
    if batch:
        template = lanes.compile_batch(model, system.scene.integrator)[0].integrator
        width = template.batch_size
    else:
        template = compiler.compile_model(model, system.scene.integrator)[0].integrator
        width = 1
    n = len(X)
    padded = np.vstack([X, np.repeat(X[-1:], (-n) % width, axis=0)])
    calls = len(padded) // width
    out, steps = np.empty_like(padded), 0

    def gen(ta: Any, i: int) -> Any:
        block = padded[(lo + i) * width : (lo + i + 1) * width]
        if batch:
            ta.set_time(0.0)
            ta.state[:] = block.T
        else:
            ta.time = 0.0
            ta.state[:] = block[0]
        return ta

    for lo in range(0, calls, 1000):
        count = min(1000, calls - lo)
        if batch:
            res = hy.ensemble_propagate_until_batch(template, system.t_end, count, gen)
        else:
            res = hy.ensemble_propagate_until(template, system.t_end, count, gen)
        for i, item in enumerate(res):
            ta = item[0]
            rows = slice((lo + i) * width, (lo + i + 1) * width)
            if batch:
                out[rows] = ta.state.T
                steps += sum(r[3] for r in ta.propagate_res)
            else:
                out[rows] = ta.state
                steps += item[4]
    return out[:n], steps


def ensemble_sweep(quick: bool) -> dict[str, list[Throughput]]:
    """Every method on every system at each ensemble size (or extrapolated where infeasible)."""
    sizes = (100, 1000) if quick else (1000, 10_000, 100_000)
    rng = np.random.default_rng(2024)
    return {system.label: _system_sweep(system, sizes, quick, rng) for system in SYSTEMS}


def _system_sweep(
    system: System, sizes: tuple[int, ...], quick: bool, rng: np.random.Generator
) -> list[Throughput]:
    run_max = 30 if quick else 1000  # run() loops beyond this are extrapolated
    # heyoka's ensembles copy an integrator per call: beyond these they are extrapolated.
    heyoka_max = {False: 100 if quick else 10_000, True: 1000 if quick else 100_000}
    workers = os.cpu_count() or 1
    x0 = ens.ensemble_state(system.scene)[1][None, :]
    for mode in ("batch", "serial"):  # compile both templates outside the timings
        ens.propagate_ensemble(system.scene, x0, system.t_end, mode=mode)
    dicts = system.members(rng, max(sizes))
    X = _member_states(system, dicts)
    rows: list[Throughput] = []
    if run_max not in sizes:
        # Measured once at its own size; the sizes above extrapolate from it.
        wall, cpu, states, steps = _measure(lambda: _run_loop(system, dicts[:run_max]))
        serial = ens.propagate_ensemble(system.scene, X[:run_max], system.t_end, mode="serial")
        error = float(np.abs(states - serial.states).max())
        rows.append(Throughput(RUN_LOOP, run_max, wall, cpu, steps, error))
        print(f"{system.label} | {throughput_row(rows[-1])}", flush=True)

    def api(mode: str, w: int, n: int) -> tuple[np.ndarray, int]:
        out = ens.propagate_ensemble(system.scene, X[:n], system.t_end, mode=mode, workers=w)
        return out.states, int(out.steps.sum())

    methods: list[tuple[str, Callable[[int], tuple[np.ndarray, int]], int]] = [
        ("ours: serial", lambda n: api("serial", 1, n), max(sizes)),
        ("ours: batch, 1 thread", lambda n: api("batch", 1, n), max(sizes)),
        (f"ours: threads ({workers})", lambda n: api("threads", workers, n), max(sizes)),
        (f"ours: batch, {workers} threads", lambda n: api("batch", workers, n), max(sizes)),
        (
            "heyoka ensemble_propagate_until (threads)",
            lambda n: _heyoka_ensemble(system, X[:n], False),
            heyoka_max[False],
        ),
        (
            "heyoka ensemble_propagate_until_batch (threads)",
            lambda n: _heyoka_ensemble(system, X[:n], True),
            heyoka_max[True],
        ),
        (RUN_LOOP, lambda n: _run_loop(system, dicts[:n]), run_max),
    ]
    for n in sizes:
        reference = None
        for method, fn, largest in methods:
            if n <= largest:
                wall, cpu, states, steps = _measure(lambda fn=fn, n=n: fn(n))
                if reference is None:
                    reference = states
                error = float(np.abs(states - reference).max())
                rows.append(Throughput(method, n, wall, cpu, steps, error))
            else:
                rows.append(_extrapolate(rows, method, n))
            print(f"{system.label} | {throughput_row(rows[-1])}", flush=True)
    return rows


def _extrapolate(rows: list[Throughput], method: str, n: int) -> Throughput:
    """A method's largest measured run, scaled linearly to ``n`` members (their cost is a
    fixed cost per member: a copied integrator, or a scene built and run)."""
    done = [r for r in rows if r.method == method and r.measured]
    if not done:
        return Throughput(method, n, math.nan, math.nan, 0, math.nan, measured=False)
    last = max(done, key=lambda r: r.n)
    scale = n / last.n
    return Throughput(
        method, n, last.wall * scale, last.cpu * scale, int(last.steps * scale), math.nan, False
    )
