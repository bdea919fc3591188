"""Compile time against scene size: each scene of :data:`.cases.FAMILIES_BY_SIZE` compiled cold
in both code models, with the step cost of each.

"Cold" means that LLVM optimises and generates the code from scratch: our template cache and
heyoka's in-memory cache are cleared and heyoka's disk cache points at a fresh, empty
directory (so the measurement includes writing the code there, as a user's first run does).
"""

from __future__ import annotations

import copy
import math
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import heyoka as hy
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.core import compiler
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows import ensemble as ens

from .cases import FAMILIES_BY_SIZE, STEP_SPAN
from .results import Point
from .tables import point_row


# ---------------------------------------------------------------------- caches, cold compiles
@contextmanager
def fresh_disk_cache() -> Iterator[Path]:
    """Point heyoka's disk cache at a new empty directory (restored on exit)."""
    state = hy.llvm_state
    old_path, old_enabled = state.get_diskcache_path(), state.get_diskcache_enabled()
    with tempfile.TemporaryDirectory(prefix="heyoka-cache-") as tmp:
        state.set_diskcache_path(tmp)
        state.set_diskcache_enabled(True)
        try:
            yield Path(tmp)
        finally:
            state.set_diskcache_path(old_path)
            state.set_diskcache_enabled(old_enabled)


def forget_compiled() -> None:
    """Our template cache and heyoka's in-memory cache (not its disk cache)."""
    compiler.clear_cache()
    ens.clear_cache()
    hy.llvm_state.clear_memcache()


def cold_compile(scene: ch.Scene) -> tuple[Any, Any, float, float]:
    """Model, compiled template, wall and CPU seconds of a cold compile (the disk cache must be
    fresh: see :func:`fresh_disk_cache`). CPU counts every thread (LLVM may use several)."""
    forget_compiled()
    model = FAMILIES[scene.family].build(scene)
    w0, c0 = time.perf_counter(), time.process_time()
    compiled, cached = compiler.compile_model(model, scene.integrator)
    w1, c1 = time.perf_counter(), time.process_time()
    assert not cached
    return model, compiled, w1 - w0, c1 - c0


def step_costs(integrators: dict[str, Any], init: np.ndarray, repeats: int = 3) -> dict:
    """Best ns per step of each integrator over STEP_SPAN from ``init``, interleaved."""
    best = {k: math.inf for k in integrators}
    steps = {}
    for _ in range(repeats):
        for key, ta in integrators.items():
            ta.time = 0.0
            ta.state[:] = init
            t0 = time.perf_counter()
            res = ta.propagate_until(STEP_SPAN)
            dt = time.perf_counter() - t0
            assert res[0] == hy.taylor_outcome.time_limit, res[0]
            steps[key] = res[3]
            best[key] = min(best[key], dt / res[3] * 1e9)
    return {"ns": best, "steps": steps}


def compile_sweep(quick: bool) -> list[Point]:
    points = []
    with fresh_disk_cache():
        for fam in FAMILIES_BY_SIZE:
            for k in fam.quick if quick else fam.sizes:
                integrators, comp, cpu = {}, {}, {}
                for compact in (False, True):
                    model, compiled, comp[compact], cpu[compact] = cold_compile(
                        fam.build(k, compact)
                    )
                    ta = copy.deepcopy(compiled.integrator)
                    ta.pars[:] = np.array(model.pars.values[: len(ta.pars)], dtype=float)
                    integrators[compact] = ta
                init = np.array(model.initial_state, dtype=float)
                cost = step_costs(integrators, init, repeats=2 if quick else 5)
                auto = model.compact or model.size() > compiler.COMPACT_THRESHOLD
                points.append(
                    Point(
                        fam.label,
                        f"{fam.unit} = {k}",
                        model.size(),
                        len(integrators[True].decomposition),
                        auto,
                        comp,
                        cpu,
                        cost["ns"],
                        cost["steps"][False],
                    )
                )
                print(point_row(points[-1]), flush=True)
    return points
