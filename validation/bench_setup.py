"""Set-up cost and ensembles: compile time against scene size, the caches, ensemble throughput.

Run:  python validation/bench_setup.py [--quick] [--out FILE]   (this section of BENCHMARKS.md)
      python validation/benchmarks.py --only setup               (the same, through the driver)

1. Compile time against scene size: families of scenes of growing size (orbit zonal harmonics,
   a rigid body with a growing force function, the predominant-mass system with more bodies,
   Hamilton's elements), each compiled cold in both code models, with the step cost of each;
   from them the size above which compact mode should be the automatic choice.
2. Caches: a scene run again, a scene differing only in numbers, heyoka's in-memory and
   on-disk caches, new processes.
3. Ensembles: members per second of a loop of ``run()``, of heyoka's batch mode and its
   ensemble propagation, and of :func:`cayley_heyoka.workflows.ensemble.propagate_ensemble`.

"Cold" means that LLVM optimises and generates the code from scratch: our template cache and
heyoka's in-memory cache are cleared and heyoka's disk cache points at a fresh, empty
directory (so the measurement includes writing the code there, as a user's first run does).
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import heyoka as hy
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.core import compiler, lanes
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.workflows import ensemble as ens

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from bench_common import fmt  # noqa: E402

# A cold non-compact compile longer than this is where a user starts to wait; heyoka's disk
# cache pays it once per structure and machine, the step cost is paid on every run.
PATIENCE = 10.0


# ---------------------------------------------------------------------- scene families
def orbit_zonal(degree: int, compact: Any = "auto") -> ch.Scene:
    """A Cartesian orbit with the zonal harmonics J2 … J_degree."""
    J = {f"J{n}": f"{(-1) ** n * 1e-3 / n**2:.3e}" for n in range(2, degree + 1)}
    return ch.Scene.from_dict(
        {
            "orbit": {
                "mu": 1.0,
                "position": [0.9, 0.2, 0.1],
                "velocity": [-0.25, 0.85, 0.45],
                "formulation": "cartesian",
            },
            "perturbations": {"zonal": {**J, "radius": 0.5}},
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


_COSINES = [f"R{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
_TRIPLES = list(itertools.combinations_with_replacement(_COSINES, 3))


def rigid_potential(terms: int, compact: Any = "auto") -> ch.Scene:
    """A rigid body (quaternion attitude) whose force function has ``terms`` cubic terms in
    the direction cosines: a user potential of growing length."""
    V = " + ".join(
        f"{0.1 / (j + 1):.4f} * {a} * {b} * {c}" for j, (a, b, c) in enumerate(_TRIPLES[:terms])
    )
    return ch.Scene.from_dict(
        {
            "body": {"inertia": [1.0, 1.5, 2.5]},
            "initial": {"rates": [0.3, 1.0, 0.5]},
            "attitude": {"formulation": "quaternion"},
            "forces": {"potential": {"V": V}},
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


def predominant_mass(
    bodies: int, compact: Any = "auto", formulation: str = "canonical"
) -> ch.Scene:
    """``bodies`` planets about a predominant mass (Hamilton 1835), in either formulation."""
    table = [
        {
            "mass": 1e-3 / (k + 1),
            "elements": {
                "a": 1.0 + 0.6 * k,
                "e": 0.05,
                "inclination": 0.05 + 0.01 * k,
                "node": 0.3 * k,
                "argument_of_pericentre": 1.1 + k,
                "mean_anomaly": 0.4 + 0.7 * k,
            },
        }
        for k in range(bodies)
    ]
    return ch.Scene.from_dict(
        {
            "hamiltonian": {
                "model": "predominant_mass",
                "G": 1.0,
                "central_mass": 1.0,
                "formulation": formulation,
                "bodies": table,
            },
            "integrator": {"compact_mode": compact},
            "output": {"times": [0.0, 1.0]},
        }
    )


def elements(bodies: int, compact: Any = "auto") -> ch.Scene:
    return predominant_mass(bodies, compact, "elements")


@dataclass
class Family:
    label: str
    unit: str  # what the size parameter counts
    build: Callable[..., ch.Scene]
    sizes: tuple[int, ...]
    quick: tuple[int, ...]


FAMILIES_BY_SIZE = [
    Family("orbit, zonal J2…Jn (Cartesian)", "n", orbit_zonal, (2, 3, 4, 6, 8, 12, 16), (2, 3)),
    Family("rigid body, V of k cubic terms", "k", rigid_potential, (1, 3, 10, 20, 40), (1,)),
    Family("predominant mass, N bodies (canonical)", "N", predominant_mass, (2, 3, 4, 6, 8), ()),
    Family("Hamilton's elements, N bodies", "N", elements, (2,), ()),
]
STEP_SPAN = 50.0  # time units stepped for the step cost: 100–300 steps in every family


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


@dataclass
class Point:
    family: str
    param: str
    size: int
    decomposition: int
    auto_compact: bool
    compile: dict[bool, float]
    cpu: dict[bool, float]
    ns: dict[bool, float]
    steps: int

    @property
    def ratio(self) -> float:
        """Step cost of compact over non-compact code."""
        return self.ns[True] / self.ns[False]

    @property
    def break_even(self) -> float:
        """Steps after which non-compact code has paid for its longer compile (inf: never;
        0: it compiles no slower)."""
        saved = self.cpu[False] - self.cpu[True]
        lost = (self.ns[True] - self.ns[False]) * 1e-9
        if saved <= 0:
            return 0.0
        return saved / lost if lost > 0 else math.inf


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
                print(_point_row(points[-1]), flush=True)
    return points


def _point_row(p: Point) -> str:
    be = p.break_even
    be_text = "never" if be == math.inf else ("–" if be == 0 else f"{be:.1e}")
    return (
        f"| {p.family} | {p.param} | {p.size / 1e3:.1f} | {p.decomposition} | "
        f"{p.compile[False]:.2f} ({p.cpu[False]:.2f}) | {p.compile[True]:.2f} "
        f"({p.cpu[True]:.2f}) | {p.ns[False]:,.0f} | {p.ns[True]:,.0f} | {p.ratio:.2f} | "
        f"{be_text} | {'compact' if p.auto_compact else 'non-compact'} |"
    )


def _crossing(xs: list[float], ys: list[float], level: float) -> float | None:
    """First x (log–log interpolation) where y reaches ``level`` from below; None if never."""
    for i in range(1, len(xs)):
        if ys[i - 1] < level <= ys[i]:
            f = (math.log(level) - math.log(ys[i - 1])) / (math.log(ys[i]) - math.log(ys[i - 1]))
            return math.exp(math.log(xs[i - 1]) + f * (math.log(xs[i]) - math.log(xs[i - 1])))
    if ys and ys[0] >= level:
        return xs[0]
    return None


def _span(values: list[float]) -> str:
    lo, hi = min(values), max(values)
    return f"{lo:.2f}" if f"{lo:.2f}" == f"{hi:.2f}" else f"{lo:.2f}–{hi:.2f}"


def _fit(xs: list[float], ys: list[float]) -> tuple[float, float, float]:
    """Least squares log y = a + b log x: (a, b, scatter factor exp(rms residual))."""
    lx, ly = np.log(xs), np.log(ys)
    b, a = np.polyfit(lx, ly, 1)
    return float(a), float(b), float(np.exp(np.std(ly - (a + b * lx))))


def threshold_analysis(points: list[Point]) -> tuple[list[str], float | None]:
    """Per family: the size where a cold non-compact compile reaches PATIENCE and how the step
    costs compare; pooled over the families, the power-law fit of the compile time against
    ``Model.size()`` (and against the decomposition's length), whose PATIENCE crossing is the
    recommended threshold."""
    lines = []
    for fam in FAMILIES_BY_SIZE:
        pts = sorted((p for p in points if p.family == fam.label), key=lambda p: p.size)
        if not pts:
            continue
        sizes = [float(p.size) for p in pts]
        at = _crossing(sizes, [p.cpu[False] for p in pts], PATIENCE)
        even = next((p.size for p in pts if p.ratio <= 1.0), None)
        longest = max(p.cpu[False] for p in pts)
        wait = (
            f"takes {PATIENCE:.0f} s at ≈ {at / 1e3:.0f} kB"
            if at is not None
            else f"stays under {PATIENCE:.0f} s up to {sizes[-1] / 1e3:.0f} kB ({longest:.1f} s)"
        )
        ratios = [p.ratio for p in pts]
        steps = f"compact steps cost {_span(ratios)}× the non-compact ones"
        if even is not None:
            steps += f" (no more than them from {even / 1e3:.0f} kB)"
        lines.append(f"* {fam.label}: a cold non-compact compile {wait}; {steps}.")
    distinct = {p.size for p in points}
    if len(distinct) < 3:
        return lines, None
    slow = [p.cpu[False] for p in points]
    a, b, scatter = _fit([p.size for p in points], slow)
    ad, bd, scatter_d = _fit([p.decomposition for p in points], slow)
    at = math.exp((math.log(PATIENCE) - a) / b)
    text = (
        f"Pooled over the families, a cold non-compact compile grows like size^{b:.2f} "
        f"(scattered by a factor {scatter:.2f} about the fit) and reaches {PATIENCE:.0f} s at "
        f"≈ {at / 1e3:.0f} kB; against the decomposition's length it grows like n^{bd:.2f} "
        f"(scatter {scatter_d:.2f}) and reaches {PATIENCE:.0f} s at "
        f"≈ {math.exp((math.log(PATIENCE) - ad) / bd):.0f} operations."
    )
    if max(slow) < PATIENCE:
        # The crossing would be an extrapolation beyond every measured compile.
        text += f" No measured compile reached {PATIENCE:.0f} s: no threshold is derived."
        return [*lines, "", text], None
    return [*lines, "", text], at


def plot_compile(points: list[Point], path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for fam, colour in zip(FAMILIES_BY_SIZE, colours, strict=False):
        pts = sorted((p for p in points if p.family == fam.label), key=lambda p: p.size)
        if not pts:
            continue
        s = [p.size / 1e3 for p in pts]
        ax.loglog(s, [p.cpu[False] for p in pts], "o-", color=colour, label=fam.label)
        ax.loglog(s, [p.cpu[True] for p in pts], "o--", color=colour, mfc="none")
        bx.semilogx(s, [p.ratio for p in pts], "o-", color=colour, label=fam.label)
    for a in (ax, bx):
        a.axvline(compiler.COMPACT_THRESHOLD / 1e3, color="grey", lw=0.8, ls=":")
        a.set_xlabel("Model.size() (kB of pickled right-hand sides)")
        a.grid(True, which="both", alpha=0.3)
    ax.axhline(PATIENCE, color="grey", lw=0.8)
    ax.set_ylabel("cold compile, CPU s: solid non-compact, dashed compact")
    ax.legend(fontsize=7)
    bx.axhline(1.0, color="grey", lw=0.8)
    bx.set_ylabel("step cost, compact / non-compact")
    fig.suptitle("Compile time and step cost against scene size (dotted: current threshold)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


# ---------------------------------------------------------------------- cache tiers
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


def cache_cases(quick: bool) -> list[tuple[str, ch.Scene, ch.Scene, ch.Scene]]:
    """(label, scene, the same structure with other numbers, a different structure)."""
    j2 = orbit_zonal(2)
    j2_numbers = ch.Scene.from_dict(
        {
            **j2.to_dict(),
            "orbit": {**j2.to_dict()["orbit"], "position": [1.1, -0.3, 0.2], "mu": 1.3},
            "perturbations": {"zonal": {"J2": 0.002, "radius": 0.7}},
        }
    )
    cases = [("orbit, J2 (Cartesian)", j2, j2_numbers, orbit_zonal(3))]
    if not quick:
        base = predominant_mass(3).to_dict()
        base["hamiltonian"]["central_mass"] = 1.2
        base["hamiltonian"]["bodies"][0]["mass"] = 2e-3
        cases.append(
            (
                "predominant mass, 3 bodies",
                predominant_mass(3),
                ch.Scene.from_dict(base),
                predominant_mass(4),
            )
        )
    return cases


def cache_table(quick: bool) -> list[str]:
    rows = [
        "| scene | situation | compiled_from_cache | compile (s) | run() wall (s) |",
        "|---|---|---|---|---|",
    ]
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
            for text, r, w in entries:
                rows.append(
                    f"| {label} | {text} | {r.metadata['compiled_from_cache']} | "
                    f"{r.metadata['compile_seconds']:.3f} | {w:.3f} |"
                )
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
        for text, c in process_rows:
            rows.append(
                f"| {label} | {text} (import {c['import']:.2f} s, process {c['process']:.2f} s) "
                f"| – | {c['compile']:.3f} | {c['run']:.3f} |"
            )
        print("\n".join(rows[-len(entries) - len(process_rows) :]), flush=True)
    return rows


# ---------------------------------------------------------------------- ensembles
@dataclass
class System:
    label: str
    scene: ch.Scene
    t_end: float
    members: Callable[[np.random.Generator, int], list[dict]]  # scene dictionaries


_BODY = {
    "body": {"inertia": [1.0, 1.5, 2.5]},
    "initial": {"rates": [0.3, 1.0, 0.5]},
    "attitude": {"formulation": "quaternion"},
}


def _body_members(rng: np.random.Generator, n: int) -> list[dict]:
    q = rng.standard_normal((n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    rates = np.array([0.3, 1.0, 0.5]) * (1 + 0.1 * rng.standard_normal((n, 3)))
    return [
        {**_BODY, "initial": {"rates": r.tolist(), "quaternion": qq.tolist()}}
        for r, qq in zip(rates, q, strict=True)
    ]


def _orbit_members(rng: np.random.Generator, n: int) -> list[dict]:
    base = orbit_zonal(2).to_dict()
    x = np.array([0.9, 0.2, 0.1]) * (1 + 0.05 * rng.standard_normal((n, 3)))
    v = np.array([-0.25, 0.85, 0.45]) * (1 + 0.05 * rng.standard_normal((n, 3)))
    return [
        {**base, "orbit": {**base["orbit"], "position": xi.tolist(), "velocity": vi.tolist()}}
        for xi, vi in zip(x, v, strict=True)
    ]


def _with_times(data: dict, t_end: float) -> dict:
    return {**data, "output": {"times": [0.0, t_end]}}


SYSTEMS = [
    System(
        "free rigid body (quaternion), t = 0…10",
        ch.Scene.from_dict(_with_times(_BODY, 10.0)),
        10.0,
        _body_members,
    ),
    System(
        "J2 orbit (Cartesian), t = 0…2π",
        orbit_zonal(2),
        2 * math.pi,
        _orbit_members,
    ),
]


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


@dataclass
class Throughput:
    method: str
    n: int
    wall: float
    cpu: float
    steps: int
    error: float  # max |final state − our serial mode's|
    measured: bool = True

    @property
    def rate(self) -> float:
        return self.n / self.wall


def _measure(fn: Callable[[], tuple[np.ndarray, int]]) -> tuple[float, float, np.ndarray, int]:
    w0, c0 = time.perf_counter(), time.process_time()
    states, steps = fn()
    return time.perf_counter() - w0, time.process_time() - c0, states, steps


def _run_loop(system: System, dicts: list[dict]) -> tuple[np.ndarray, int]:
    names = ens.ensemble_state(system.scene)[0]
    out, steps = [], 0
    for d in dicts:
        result = ch.run(ch.Scene.from_dict(_with_times(d, system.t_end)))
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


RUN_LOOP = "loop of run(), one scene per member"


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
        print(f"{system.label} | {_throughput_row(rows[-1])}", flush=True)

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
            print(f"{system.label} | {_throughput_row(rows[-1])}", flush=True)
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


def _throughput_row(r: Throughput) -> str:
    mark = "" if r.measured else " (extrapolated)"
    steps = r.steps / r.wall if r.wall > 0 else math.nan
    cores = r.cpu / r.wall if r.measured and r.wall > 0 else math.nan
    return (
        f"{r.method}{mark} | {r.n:,} | {fmt(r.wall)} | {r.rate:,.0f} | {steps:,.0f} | "
        f"{fmt(cores)} | {fmt(r.error) if r.measured else '–'} |"
    )


def plot_ensembles(results: dict[str, list[Throughput]], path: Path) -> bool:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    fig, axes = plt.subplots(1, len(results), figsize=(11, 4.2), sharey=True)
    for ax, (label, rows) in zip(np.atleast_1d(axes), results.items(), strict=True):
        methods = list(dict.fromkeys(r.method for r in rows))
        for method in methods:
            pts = sorted((r for r in rows if r.method == method), key=lambda r: r.n)
            meas = [(r.n, r.rate) for r in pts if r.measured]
            line = ax.loglog(*zip(*meas, strict=True), "o-", label=method)[0] if meas else None
            extra = [(r.n, r.rate) for r in pts if not r.measured and math.isfinite(r.rate)]
            if extra and meas:
                xs, ys = zip(*([meas[-1], *extra]), strict=True)
                ax.loglog(xs, ys, "o:", color=line.get_color(), mfc="none")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("members N")
        ax.grid(True, which="both", alpha=0.3)
    np.atleast_1d(axes)[0].set_ylabel("members per second (hollow: extrapolated)")
    np.atleast_1d(axes)[0].legend(fontsize=6)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


# ---------------------------------------------------------------------- the section
def run(quick: bool, figures: Path) -> str:
    """Measure set-up cost and ensemble throughput; return the section's Markdown."""
    figures = Path(figures)
    figures.mkdir(parents=True, exist_ok=True)
    simd = hy.recommended_simd_size()
    workers = os.cpu_count() or 1
    out = [
        "## Set-up cost and ensembles",
        "",
        "Generated by `python validation/bench_setup.py"
        + (" --quick" if quick else "")
        + "`. **Cold** means LLVM optimises and generates the code from scratch: our template "
        "cache and heyoka's in-memory cache are cleared and heyoka's disk cache points at a "
        "fresh, empty directory (the compile writes its code there, as a user's first run "
        "does). Compile times are `compile_model` (the integrator and the evaluator of outputs "
        "and monitors, what `run()` pays); the machine is shared, so walls are noisy and the "
        "CPU seconds (every thread of the process) are given beside them.",
        "",
        "### Compile time against scene size",
        "",
        "Each scene compiled cold with `integrator.compact_mode = false` and `true`; step cost "
        f"over t = 0…{STEP_SPAN:g} (double, tolerance ε), both integrators interleaved in one "
        "process, best of a few repeats. Size is `Model.size()` (bytes of pickled right-hand "
        "sides, what the automatic choice reads); *decomp.* is the length of heyoka's Taylor "
        "decomposition (elementary operations). Compile times are wall seconds with CPU "
        "seconds in brackets; the break-even, the analysis below and the plot use the CPU "
        "seconds, the compile's own work (on a shared machine the wall time also counts "
        "waiting for a core). *Break-even* is the number of steps after which non-compact code "
        "has paid for its longer compile; *auto* is the current automatic choice (threshold "
        f"{compiler.COMPACT_THRESHOLD / 1e3:.0f} kB, or the model's own request).",
        "",
        "| family | size parameter | size (kB) | decomp. | non-compact compile, s (CPU) | "
        "compact compile, s (CPU) | non-compact ns/step | compact ns/step | ratio | "
        "break-even steps | auto |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    points = compile_sweep(quick)
    out += [_point_row(p) for p in points]
    if plot_compile(points, figures / "bench_setup_compile.png"):
        out += ["", "![compile time against size](figures/bench_setup_compile.png)"]
    lines, recommended = threshold_analysis(points)
    out += ["", *lines, ""]
    spread = [p.ratio for p in points]
    evens = [p.break_even for p in points if 0 < p.break_even < math.inf]
    if evens:
        faster = sum(p.cpu[True] < p.cpu[False] for p in points)
        out.append(
            f"Compact code compiled faster in {faster} of {len(points)} scenes; its steps cost "
            f"{_span(spread)}× the non-compact ones, so a cold non-compact "
            "compile is paid back after "
            f"{min(evens):.1e}–{max(evens):.1e} steps."
        )
    if recommended is not None:
        out += [
            "",
            f"Recommended automatic threshold: ≈ {recommended / 1e3:.0f} kB of `Model.size()`, "
            f"where the pooled fit reaches {PATIENCE:.0f} s of cold compile (current: "
            f"{compiler.COMPACT_THRESHOLD / 1e3:.0f} kB). Below it a non-compact compile is a "
            "wait of seconds, paid once per structure and machine (the disk cache serves every "
            "later process), against steps that are cheaper on every run; above it the wait "
            "grows faster than the size while the step advantage shrinks.",
        ]
    out += [
        "",
        "### Caches",
        "",
        "A scene run in turn through each level of caching, in one process (heyoka's disk cache "
        "at a fresh directory), then in new processes (`HEYOKA_CACHE_DIR`); *compile* is "
        "`result.metadata['compile_seconds']` (0 when our template cache served it). The "
        "full run's last row per scene uses the default disk cache as this machine has it: "
        "heyoka's first compile in a process costs more the larger that cache has grown.",
        "",
        *cache_table(quick),
        "",
        "### Ensembles",
        "",
        f"Members per second and member-steps per second (double, tolerance ε) on {workers} "
        f"cores; heyoka's batch size is `recommended_simd_size()` = {simd}. *ours* is "
        "`cayley_heyoka.workflows.ensemble.propagate_ensemble` (one compiled integrator per "
        "worker, reused for every member; *batch, 1 thread* is heyoka's batch mode alone). "
        "heyoka's "
        "`ensemble_propagate_until(_batch)` deep-copies the integrator for every member (or "
        "batch) it propagates. The `run()` loop builds, validates and runs one scene per "
        "member (template cache warm). *cores* is CPU seconds over wall seconds: what the "
        "process actually obtained. *Δ* is the largest difference from our serial mode's final "
        "states. Extrapolated rows scale the largest measured run linearly (a fixed cost per "
        "member).",
        "",
    ]
    results = ensemble_sweep(quick)
    for label, rows in results.items():
        # Methods in the order they were measured (each size measures them all in turn).
        largest = max(r.n for r in rows)
        order = {r.method: i for i, r in enumerate(r for r in rows if r.n == largest)}
        rows = sorted(rows, key=lambda r: (r.n, order[r.method]))
        out += [
            f"**{label}**",
            "",
            "| method | members | wall (s) | members/s | member-steps/s | cores | Δ |",
            "|---|---|---|---|---|---|---|",
            *[
                f"| {_throughput_row(r)}"
                for r in sorted(rows, key=lambda r: (r.n, order[r.method]))
            ],
            "",
        ]
    if plot_ensembles(results, figures / "bench_setup_ensembles.png"):
        out += ["![ensemble throughput](figures/bench_setup_ensembles.png)", ""]
    return "\n".join(out).rstrip("\n")


if __name__ == "__main__":
    import benchmarks

    sys.exit(benchmarks.main(["--only", "setup", *sys.argv[1:]]))
