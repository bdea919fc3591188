"""Caches: a scene run in turn through each level of caching in one process (heyoka's disk
cache at a fresh directory), then in new processes (``HEYOKA_CACHE_DIR``)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

import heyoka as hy

import cayley_heyoka as ch
from cayley_heyoka.core import compiler

from .cases import cache_cases
from .compiles import forget_compiled, fresh_disk_cache

_CHILD = """
import json, sys, time
t0 = time.perf_counter()
import cayley_heyoka as ch
scene = ch.Scene.from_dict(json.loads(sys.argv[1]))
t1 = time.perf_counter()
result = ch.run(scene)
print(json.dumps({"import": t1 - t0, "compile": result.metadata["compile_seconds"],
                  "run": time.perf_counter() - t1}))
"""


def _child(scene: ch.Scene, cache_dir: Path) -> dict[str, float]:
    t0 = time.perf_counter()
    out = subprocess.run(
        [sys.executable, "-c", _CHILD, json.dumps(scene.to_dict())],
        env={**os.environ, "HEYOKA_CACHE_DIR": str(cache_dir)},
        capture_output=True,
        text=True,
        check=True,
    )
    return {**json.loads(out.stdout), "process": time.perf_counter() - t0}


def _timed_run(scene: ch.Scene) -> tuple[ch.Result, float]:
    t0 = time.perf_counter()
    result = ch.run(scene)
    return result, time.perf_counter() - t0


CacheRuns = tuple[str, list[tuple[str, ch.Result, float]], list[tuple[str, dict[str, float]]]]


def cache_runs(quick: bool) -> Iterator[CacheRuns]:
    """Per scene of :func:`.cases.cache_cases`, as each is measured: its label, the in-process
    runs (situation, result, ``run()`` wall seconds) and the new processes (situation, the
    child's import, compile, run and process seconds)."""
    for label, scene, numbers, other in cache_cases(quick):
        with fresh_disk_cache() as disk:
            forget_compiled()
            entries = []
            r, w = _timed_run(scene)
            entries.append(("cold: first run in the process, empty disk cache", r, w))
            r, w = _timed_run(scene)
            entries.append(("the same scene again (our template cache)", r, w))
            r, w = _timed_run(numbers)
            entries.append(("only numbers differ (μ, J₂, masses, state)", r, w))
            r, w = _timed_run(other)
            entries.append(("one more term or body (another structure)", r, w))
            compiler.clear_cache()
            r, w = _timed_run(scene)
            entries.append(("template cache cleared, heyoka's memory cache warm", r, w))
            compiler.clear_cache()
            hy.llvm_state.clear_memcache()
            r, w = _timed_run(scene)
            entries.append(("both cleared, heyoka's disk cache warm", r, w))
            warm = _child(scene, disk)
        process_rows = [("new process, heyoka's disk cache warm", warm)]
        if not quick:
            with tempfile.TemporaryDirectory(prefix="heyoka-cache-") as empty:
                process_rows.append(("new process, empty disk cache", _child(scene, Path(empty))))
            # The user's own disk cache, which grows with every structure ever compiled (up to
            # heyoka's limit): its size costs the first compile of each process. The first
            # child stores the scene there if it is missing; the second is measured.
            own = Path(hy.llvm_state.get_diskcache_path())
            _child(scene, own)
            mb = hy.llvm_state.get_diskcache_size() / 1e6
            text = f"new process, the default disk cache ({mb:,.0f} MB) warm"
            process_rows.append((text, _child(scene, own)))
        yield label, entries, process_rows
