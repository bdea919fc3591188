"""Hamilton's system with one predominant mass: the two formulations over long runs.

The N5 system (Hamilton 1835, Second Essay (S2.), (T2.); examples/planets.toml): M = 1, G = 1,
and two bodies,

    m₁ = 1e-3:  a = 1,   e = 0.05, i = 0.05, Ω = 0.3, ω = 1.1, ℓ₀ = 0.4
    m₂ = 3e-4:  a = 1.8, e = 0.08, i = 0.08, Ω = 2.0, ω = 4.0, ℓ₀ = 2.5

(the elements of the relative orbits in Hamilton's meaning, at t = 0), integrated over
``orbits`` periods of the inner body (t = 2π·orbits) three ways: the canonical equations of
(F2.) in double, Hamilton's varying elements (S2.) in double, and (F2.) in real128 as the
reference. ``measure`` returns the largest position differences, the wall times and the
error growth on the output grid; ``python validation/hamilton_planets.py [orbits]`` prints
them.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from cayley_heyoka import Scene, load_scene, run

# The bodies of the bundled example, which is check N5: the one place their numbers live.
EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "planets.toml"
BODIES = tuple(
    (body["mass"], body["elements"])
    for body in load_scene(EXAMPLE).to_dict()["hamiltonian"]["bodies"]
)
TWO_PI = "6.283185307179586476925286766559005768394"


def n5_scene(formulation: str, orbits: int, samples: int, precision: str = "double") -> dict:
    """The N5 scene dictionary over ``orbits`` inner periods with ``samples`` output times."""
    return {
        "title": f"N5, {formulation}, {orbits} inner orbits",
        "hamiltonian": {
            "model": "predominant_mass",
            "G": "1",
            "central_mass": "1",
            "formulation": formulation,
            "bodies": [{"mass": m, "elements": dict(e)} for m, e in BODIES],
        },
        "integrator": {"precision": precision},
        "output": {"times": {"start": "0", "stop": _times(orbits), "count": samples}},
    }


def _times(orbits: int) -> str:
    import mpmath

    with mpmath.workdps(40):
        return mpmath.nstr(orbits * mpmath.mpf(TWO_PI), 38)


def _positions(result: Any) -> np.ndarray:
    """(samples, 6): ξ of both bodies, in double."""
    names = ("x1", "y1", "z1", "x2", "y2", "z2")
    return np.stack([np.asarray(result[k], dtype=float) for k in names], axis=1)


def _timed(scene: dict, warm: bool = True) -> tuple[Any, float]:
    """The result of a run and its wall time; with ``warm``, of a second run (the compiled
    integrator from the cache)."""
    if warm:
        run(Scene.from_dict(scene))
    t0 = time.perf_counter()
    result = run(Scene.from_dict(scene))
    return result, time.perf_counter() - t0


def measure(orbits: int = 1000, samples: int = 201, reference: bool = True) -> dict[str, Any]:
    """Elements against canonical in double, each against a real128 canonical reference.

    Parameters
    ----------
    orbits
        Inner orbits (t = 2π·orbits).
    samples
        Output times, evenly spaced from 0.
    reference
        Also run the real128 canonical reference (the slow part: ~1 min at 1000 orbits).

    Returns
    -------
    dict
        ``t`` (output times), ``difference`` (max over bodies of |ξ_elements − ξ_canonical| at
        each time), ``error`` ({formulation: |ξ − ξ_reference| per time}, with the reference),
        ``max`` (the largest of each), ``wall`` (of a second, compiled run; the reference's
        includes compiling) and ``steps`` per run, ``energy_drift``
        (largest |ΔH/H| per double run).
    """
    runs: dict[str, Any] = {}
    wall: dict[str, float] = {}
    for name, formulation, precision in (
        ("canonical", "canonical", "double"),
        ("elements", "elements", "double"),
        *((("reference", "canonical", "quad"),) if reference else ()),
    ):
        scene = n5_scene(formulation, orbits, samples, precision)
        runs[name], wall[name] = _timed(scene, warm=name != "reference")
    t = np.asarray(runs["canonical"].t, dtype=float)
    pos = {k: _positions(r) for k, r in runs.items()}

    def distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        d = a - b
        return np.maximum(np.linalg.norm(d[:, :3], axis=1), np.linalg.norm(d[:, 3:], axis=1))

    out: dict[str, Any] = {
        "orbits": orbits,
        "t": t,
        "difference": distance(pos["elements"], pos["canonical"]),
        "wall": wall,
        "steps": {k: r.counters["steps"] for k, r in runs.items()},
        "energy_drift": {
            k: float(np.max(np.abs(runs[k].drift("energy")))) for k in ("canonical", "elements")
        },
    }
    out["max"] = {"elements_vs_canonical": float(np.max(out["difference"]))}
    if reference:
        ref = pos["reference"]
        out["error"] = {k: distance(pos[k], ref) for k in ("canonical", "elements")}
        out["exponent"] = {}
        for k, e in out["error"].items():
            out["max"][f"{k}_vs_reference"] = float(np.max(e))
            out["exponent"][k] = _growth_exponent(t, e)
    return out


def _growth_exponent(t: np.ndarray, error: np.ndarray) -> float:
    """Slope of log(error) against log(t) over the last 90% of the run (least squares)."""
    keep = (t > 0.1 * t[-1]) & (error > 0)
    return float(np.polyfit(np.log(t[keep]), np.log(error[keep]), 1)[0])


def main(argv: list[str]) -> None:
    orbits = int(argv[1]) if len(argv) > 1 else 1000
    m = measure(orbits)
    print(f"N5 over {orbits} inner orbits (t = {2 * math.pi * orbits:.1f}), position differences:")
    for k, v in m["max"].items():
        print(f"  {k:28s} {v:.2e}")
    print("wall seconds (second run, compiled):", {k: round(v, 3) for k, v in m["wall"].items()})
    print("steps:", m["steps"])
    print("energy drift:", {k: f"{v:.1e}" for k, v in m["energy_drift"].items()})
    if "exponent" in m:
        print(
            "error growth exponents (error ~ t^k):",
            {k: round(v, 2) for k, v in m["exponent"].items()},
        )
    if "error" in m:
        print("error growth (t, canonical, elements, |elements - canonical|):")
        for i in np.linspace(0, len(m["t"]) - 1, 11).astype(int):
            print(
                f"  {m['t'][i]:9.1f}  {m['error']['canonical'][i]:.2e}  "
                f"{m['error']['elements'][i]:.2e}  {m['difference'][i]:.2e}"
            )


if __name__ == "__main__":
    main(sys.argv)
