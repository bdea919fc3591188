"""The reference: our Cartesian formulation in real128 at tolerance 1e-24, checked against a
second real128 run at 1e-20. The pair takes minutes, so both are cached under
``$CAYLEY_HEYOKA_BENCH_CACHE`` (default ``<tmp>/cayley_heyoka_bench``) and reused while the
case, the grid and heyoka's version are the same."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import tempfile
import time
from pathlib import Path
from typing import Any

import heyoka as hy
import numpy as np

import cayley_heyoka as ch

from .case import CHECK_TOL, LD, N_FULL, REF_TOL, grid, scene


@dataclasses.dataclass
class Reference:
    t: np.ndarray
    x: np.ndarray  # (3, n) long double: hi + lo of the real128 values
    v: np.ndarray  # (3, n) the same for the velocity
    steps: int
    check: np.ndarray  # |Δx| between the tol-1e-24 and the tol-1e-20 real128 runs
    check_steps: int
    cached: bool


def cache_dir() -> Path:
    default = Path(tempfile.gettempdir()) / "cayley_heyoka_bench"
    return Path(os.environ.get("CAYLEY_HEYOKA_BENCH_CACHE", default))


def _cache_file(times: np.ndarray, tol: str) -> Path:
    key = json.dumps(
        {
            "scene": scene("cartesian", times, precision="quad", tolerance=tol).to_dict(),
            "heyoka": hy.__version__,
        },
        sort_keys=True,
        default=str,
    )
    return cache_dir() / f"ias15_ref_{hashlib.sha256(key.encode()).hexdigest()[:20]}.npz"


def quad_run(times: np.ndarray, tol: str, compute: bool = True) -> tuple[Any, int, bool]:
    """The real128 Cartesian run at ``tol`` on ``times``: (x, v as hi + lo in long double,
    shape (6, n); steps; from the cache). A cached run over 10⁴ orbits serves every prefix of
    its grid."""
    for span in (times, grid(N_FULL)):
        path = _cache_file(span, tol)
        if len(span) >= len(times) and np.array_equal(span[: len(times)], times) and path.exists():
            data = np.load(path)
            n = len(times)
            x = data["hi"][:, :n].astype(LD) + data["lo"][:, :n].astype(LD)
            return x, int(data["steps"]), True
    if not compute:
        return None, 0, False
    t0 = time.perf_counter()
    r = ch.run(scene("cartesian", times, precision="quad", tolerance=tol))
    wall = time.perf_counter() - t0
    names = ("x", "y", "z", "vx", "vy", "vz")
    hi = np.array([[float(v) for v in r[k]] for k in names])
    lo = np.array([[float(v - hy.real128(float(v))) for v in r[k]] for k in names])
    path = _cache_file(times, tol)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, hi=hi, lo=lo, steps=r.counters["steps"], wall=wall)
    return hi.astype(LD) + lo.astype(LD), int(r.counters["steps"]), False


def reference(times: np.ndarray, check: bool = True) -> Reference:
    """The real128 reference on ``times`` and its check (without ``check``, the check run is
    taken only from the cache: quick runs skip its compilation)."""
    x, steps, cached = quad_run(times, REF_TOL)
    xc, csteps, _ = quad_run(times, CHECK_TOL, compute=check)
    if xc is None:
        diff = np.full(len(times), np.nan)
    else:
        diff = np.sqrt(((x[:3] - xc[:3]) ** 2).sum(axis=0)).astype(float)
    return Reference(times, x[:3], x[3:], steps, diff, csteps, cached)
