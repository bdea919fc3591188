"""Figures of the engine: drift per precision, throughput, compile cost, step cost.

Run:  python validation/engine_figures.py            (writes validation/ENGINE.md)
      python validation/engine_figures.py --only formulations steps   (those sections only)

Every figure quoted in README.md and docs/ about the engine comes from this script.

* Drift: the bundled rigid-body scenes at double, quad and real (256 bits): final relative drift
  of the energy and of |L|² (or the vertical momentum for the heavy top), steps, steps per
  second. (The orbit examples have a third body: nothing is conserved; the orbit validation in
  REPORT.md measures conservation.)
* Compile cost: a cold compile (empty heyoka disk cache, new process), a new process with
  heyoka's disk cache warm, and a second run in the same process (our template cache).
* Step cost against raw heyoka: our compiled integrator and a hand-written heyoka system of the
  same equations, stepped over the same interval side by side in one process (rotation, and
  the orbit family's J2 systems).
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import heyoka as hy
import numpy as np

import cayley_heyoka as ch
from cayley_heyoka.core.compiler import compile_model
from cayley_heyoka.core.families import FAMILIES

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
PRECISIONS = {"double": "double", "quad": "quad", "real256": {"bits": 256}}
# Extended precision is slow: shorten those runs so the script stays within minutes.
STOP = {"double": None, "quad": "20", "real256": "5"}


def drift_table() -> list[str]:
    rows = [
        "| scene | precision | t_end | steps | rebasings | steps/s | energy drift "
        "| momentum drift |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for path in sorted(EXAMPLES.glob("*.toml")):
        scene = ch.load_scene(path)
        if scene.family != "rotation":
            continue  # the orbit examples conserve nothing (a third body); see REPORT.md
        base = scene.to_dict()
        for label, spec in PRECISIONS.items():
            data = copy.deepcopy(base)
            data.setdefault("integrator", {})["precision"] = spec
            if STOP[label]:
                data["output"]["times"] = {"start": "0", "stop": STOP[label], "count": 11}
            scene = ch.Scene.from_dict(data)
            ch.run(scene)  # compile outside the timing
            t0 = time.perf_counter()
            result = ch.run(scene)
            wall = time.perf_counter() - t0
            drifts = result.final_drifts()
            mom = drifts.get("momentum_squared", drifts.get("momentum_vertical", float("nan")))
            steps = result.counters["steps"]
            rebasings = result.counters.get("rebasings", "-")
            rows.append(
                f"| {path.name} | {label} | {float(result.t[-1]):g} | {steps} | {rebasings} | "
                f"{steps / wall:,.0f} | {drifts['energy']:.2e} | {mom:.2e} |"
            )
            print(rows[-1], flush=True)
    return rows


_CHILD = """
import json, sys, time
t0 = time.perf_counter()
import cayley_heyoka as ch
scene = ch.load_scene(sys.argv[1])
t1 = time.perf_counter()
r1 = ch.run(scene)
t2 = time.perf_counter()
r2 = ch.run(scene)
t3 = time.perf_counter()
print(json.dumps({"first": t2 - t1, "second": t3 - t2, "compile": r1.metadata["compile_seconds"],
                  "cached": r2.metadata["compiled_from_cache"]}))
"""


def compile_table() -> list[str]:
    rows = [
        "| scene | cold compile (empty disk cache) | new process, heyoka disk cache warm: "
        "compile | the same: whole first run() | same process, second run() |",
        "|---|---|---|---|---|",
    ]
    for path in sorted(EXAMPLES.glob("*.toml")):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "HEYOKA_CACHE_DIR": cache}
            runs = []
            for _ in range(2):
                out = subprocess.run(
                    [sys.executable, "-c", _CHILD, str(path)],
                    env=env,
                    capture_output=True,
                    text=True,
                    check=True,
                )
                runs.append(json.loads(out.stdout))
        rows.append(
            f"| {path.name} | {runs[0]['compile']:.2f} s | {runs[1]['compile']:.3f} s | "
            f"{runs[1]['first']:.3f} s | "
            f"{runs[1]['second'] * 1e3:.1f} ms (cache hit: {runs[1]['cached']}) |"
        )
        print(rows[-1], flush=True)
    return rows


def _hand_written_quaternion_free_body(A, B, C, state):
    p, q, r, w, x, y, z = hy.make_vars("p", "q", "r", "qw", "qx", "qy", "qz")
    sys_ = [
        (p, (B - C) * q * r / A),
        (q, (C - A) * r * p / B),
        (r, (A - B) * p * q / C),
        (w, 0.5 * (-x * p - y * q - z * r)),
        (x, 0.5 * (w * p + y * r - z * q)),
        (y, 0.5 * (w * q - x * r + z * p)),
        (z, 0.5 * (w * r + x * q - y * p)),
    ]
    return hy.taylor_adaptive(sys_, state)


def _hand_written_rates(A, B, C, state):
    p, q, r = hy.make_vars("p", "q", "r")
    return hy.taylor_adaptive(
        [(p, (B - C) * q * r / A), (q, (C - A) * r * p / B), (r, (A - B) * p * q / C)], state
    )


def _hand_written_rodrigues(A, B, C, state):
    p, q, r, lam, mu, nu = hy.make_vars("p", "q", "r", "lambda", "mu", "nu")
    sys_ = [
        (p, (B - C) * q * r / A),
        (q, (C - A) * r * p / B),
        (r, (A - B) * p * q / C),
        (lam, 0.5 * ((1 + lam * lam) * p + (lam * mu - nu) * q + (nu * lam + mu) * r)),
        (mu, 0.5 * ((lam * mu + nu) * p + (1 + mu * mu) * q + (mu * nu - lam) * r)),
        (nu, 0.5 * ((nu * lam - mu) * p + (mu * nu + lam) * q + (1 + nu * nu) * r)),
    ]
    return hy.taylor_adaptive(sys_, state)


def _side_by_side(ours, raw, init, stop, loops, repeats) -> tuple[dict, dict]:
    """Best seconds per step of two integrators from the same state, interleaved (the machine
    is noisy), and their step counts; a run ending before ``stop`` would time something else."""
    best = {"ours": np.inf, "raw": np.inf}
    steps = {}
    for _ in range(repeats):
        for label, ta in (("ours", ours), ("raw", raw)):
            total, dt = 0, 0.0
            for _ in range(loops):
                ta.time = 0.0
                ta.state[:] = init
                t0 = time.perf_counter()
                res = ta.propagate_until(stop)
                dt += time.perf_counter() - t0
                total += res[3]
                assert res[0] == hy.taylor_outcome.time_limit, res[0]
            steps[label] = total
            best[label] = min(best[label], dt / total)
    return best, steps


def step_cost_table(repeats: int = 7, t_end: float = 20000.0) -> list[str]:
    rows = [
        "| system | ours: ns/step | raw heyoka: ns/step | ratio ours/raw | steps |",
        "|---|---|---|---|---|",
    ]
    A, B, C = 1.0, 1.6, 2.3
    # The Rodrigues run stops before its first re-basing (t_end 2): it times the stepping of
    # Cayley's kinematics plus our chart event, against the bare kinematics, over many restarts.
    cases = {
        "rates only": ({"formulation": "none"}, _hand_written_rates, 3, t_end, 1),
        "Rodrigues attitude, no re-basing": (
            {"formulation": "rodrigues"},
            _hand_written_rodrigues,
            6,
            2.0,
            2000,
        ),
        "quaternion attitude": (
            {"formulation": "quaternion"},
            _hand_written_quaternion_free_body,
            7,
            t_end,
            1,
        ),
    }
    for name, (attitude, hand, n, stop, loops) in cases.items():
        data = {
            "body": {"inertia": [A, B, C]},
            "initial": {"rates": [0.3, 1.0, 0.5]},
            "attitude": attitude,
            "output": {"times": [0.0, 1.0]},
        }
        scene = ch.Scene.from_dict(data)
        model = FAMILIES["rotation"].build(scene)
        compiled, _ = compile_model(model, scene.integrator)
        ours = copy.deepcopy(compiled.integrator)
        ours.pars[:] = np.array(model.pars.values, dtype=float)
        init = np.array(model.initial_state, dtype=float)
        raw = hand(A, B, C, init[:n])
        best, steps = _side_by_side(ours, raw, init[:n], stop, loops, repeats)
        rows.append(
            f"| {name} | {best['ours'] * 1e9:.0f} | {best['raw'] * 1e9:.0f} | "
            f"{best['ours'] / best['raw']:.2f} | {steps['ours']} / {steps['raw']} |"
        )
        print(rows[-1], flush=True)
    return rows


_J2 = {"mu": 1.0, "J2": 0.0010826, "R": 0.8}


def _orbit_scene(formulation: str) -> ch.Scene:
    """Case R1 of the 1860 reference values: J2 about z, fixed reference plane."""
    return ch.Scene.from_dict(
        {
            "orbit": {
                "mu": _J2["mu"],
                "position": [0.9, 0.2, 0.1],
                "velocity": [-0.25, 0.85, 0.45],
                "formulation": formulation,
            },
            "perturbations": {"zonal": {"J2": _J2["J2"], "radius": _J2["R"]}},
            "output": {"times": [0.0, 1.0]},
        }
    )


def _j2_gradient(x):
    """∇Ω of J2 about z in closed form (Cayley 1860)."""
    mu, J2, R = _J2["mu"], _J2["J2"], _J2["R"]
    r2 = x[0] * x[0] + x[1] * x[1] + x[2] * x[2]
    c = 1.5 * mu * J2 * R**2 * r2**-2.5
    k = 5 * x[2] * x[2] / r2 - 1
    return [c * k * x[0], c * k * x[1], c * (k * x[2] - 2 * x[2])]


def _hand_written_cartesian_j2(state, parameters: bool = False):
    """ẍ = −μx/r³ + ∇Ω_J2; ``parameters``: μ and 3μJ₂R²/2 as runtime parameters, as ours has
    them (so that scenes differing in numbers share code), instead of literals heyoka folds."""
    x, y, z, vx, vy, vz = hy.make_vars("x", "y", "z", "vx", "vy", "vz")
    r2 = x * x + y * y + z * z
    if parameters:
        mu, c = hy.par[0], hy.par[1] * r2**-2.5
        k = 5 * z * z / r2 - 1
        g = [c * k * x, c * k * y, c * (k * z - 2 * z)]
        pars = {"pars": [_J2["mu"], 1.5 * _J2["mu"] * _J2["J2"] * _J2["R"] ** 2]}
    else:
        mu, g, pars = _J2["mu"], _j2_gradient([x, y, z]), {}
    kepler = -mu / (r2 * hy.sqrt(r2))
    rhs = [vx, vy, vz] + [kepler * c + gc for c, gc in zip((x, y, z), g, strict=True)]
    return hy.taylor_adaptive(list(zip((x, y, z, vx, vy, vz), rhs, strict=True)), state, **pars)


def _cayley_j2_system(recipe: bool):
    """Cayley's system (docs/orbits.md, with the reduced plane equations) for J2 about z.

    ``recipe``: a step-by-step recipe ( the orbit axes, x = r x̂₃, the closed-form
    ∇Ω, partials by scalar products) — the same equations as ours, written by hand. Otherwise
    simplified by hand for this Ω alone (s = r sin Φ sin u): what a person specialising the
    equations to J2 would write.
    """
    r, rdot, rho, h, Theta, Sigma, Phi = hy.make_vars(
        "r", "rdot", "rho", "h", "Theta", "Sigma", "Phi"
    )
    mu, J2, R = _J2["mu"], _J2["J2"], _J2["R"]
    u = rho - Sigma
    su, cu, sP, cP = hy.sin(u), hy.cos(u), hy.sin(Phi), hy.cos(Phi)
    if recipe:
        sT, cT = hy.sin(Theta), hy.cos(Theta)
        x3 = [cT * cu - sT * cP * su, sT * cu + cT * cP * su, sP * su]
        y3 = [-cT * su - sT * cP * cu, -sT * su + cT * cP * cu, sP * cu]
        n = [sT * sP, -cT * sP, cP]
        g = _j2_gradient([r * c for c in x3])

        def dot(a, b):
            return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]

        O_r, O_rho, O_beta = dot(x3, g), r * dot(y3, g), r * dot(n, g)
    else:
        c = 1.5 * mu * J2 * R**2 / r**5
        O_r = c * r * (3 * sP * sP * su * su - 1)
        O_rho = -2 * c * r * r * sP * sP * su * cu
        O_beta = -2 * c * r * r * sP * cP * su
    lift = su * O_beta / (h * sP)
    rhs = [rdot, h * h / r**3 - mu / r**2 + O_r, h / r**2, O_rho, lift, cP * lift, cu * O_beta / h]
    return list(zip((r, rdot, rho, h, Theta, Sigma, Phi), rhs, strict=True))


def orbit_step_cost_table(repeats: int = 7) -> list[str]:
    """Orbit steps (J2, double) against hand-written heyoka systems, side by side.

    The Cayley runs stop before ρ's first revolution (t = 4.5 of a period 4.97, looped): they
    time the stepping of the equations with our two terminal events (revolutions of ρ, the
    equatorial stop) armed, against bare equations.
    """
    rows = [
        "| system | ours: ns/step | hand-written: ns/step | ratio ours/hand | steps |",
        "|---|---|---|---|---|",
    ]
    cases = [
        ("Cartesian, J2, 1000 orbits", "cartesian", _hand_written_cartesian_j2, 5000.0, 1),
        (
            "Cartesian, J2, 1000 orbits, vs μ and μJ₂R² as parameters in both",
            "cartesian",
            lambda s: _hand_written_cartesian_j2(s, parameters=True),
            5000.0,
            1,
        ),
        (
            "Cayley, J2, vs a hand-written recipe (same equations)",
            "cayley",
            lambda s: hy.taylor_adaptive(_cayley_j2_system(True), s),
            4.5,
            1000,
        ),
        (
            "Cayley, J2, vs equations simplified by hand for J2",
            "cayley",
            lambda s: hy.taylor_adaptive(_cayley_j2_system(False), s),
            4.5,
            1000,
        ),
    ]
    for name, formulation, hand, stop, loops in cases:
        scene = _orbit_scene(formulation)
        model = FAMILIES["orbit"].build(scene)
        compiled, _ = compile_model(model, scene.integrator)
        ours = copy.deepcopy(compiled.integrator)
        pars = np.array([float(v) for v in model.pars.values])
        ours.pars[:] = pars[: len(ours.pars)]
        init = np.array([float(v) for v in model.initial_state])
        raw = hand(init.copy())
        best, steps = _side_by_side(ours, raw, init, stop, loops, repeats)
        rows.append(
            f"| {name} | {best['ours'] * 1e9:.0f} | {best['raw'] * 1e9:.0f} | "
            f"{best['ours'] / best['raw']:.2f} | {steps['ours']} / {steps['raw']} |"
        )
        print(rows[-1], flush=True)
    return rows


#: The span of the formulations table: long, so that the stepping, not a run's fixed cost,
#: is what the wall times compare.
FORMULATION_SPAN = 20000.0


def formulation_steps_table() -> list[str]:
    """Steps and wall time (median of five runs) of the two attitude formulations over the
    same span (double), and each run's wall time over the quaternion's (same scene)."""
    rows = [
        "| scene | formulation | max chart angle | steps | rebasings | wall | ÷ quaternion |",
        "|---|---|---|---|---|---|---|",
    ]
    forces = {
        "free body": {},
        "heavy top": {"heavy_top": {"weight": 1.0, "center_of_mass": [0.1, -0.05, 0.3]}},
    }
    variants = [("quaternion", None)] + [("rodrigues", a) for a in (90, 120, 160)]
    for label, force in forces.items():
        quaternion_wall = None
        for formulation, angle in variants:
            attitude = {"formulation": formulation}
            if angle:
                attitude["max_chart_angle"] = angle
            data = {
                "body": {"inertia": [1.0, 1.6, 2.3]},
                "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
                "attitude": attitude,
                "forces": force,
                "output": {"times": [0.0, FORMULATION_SPAN]},
            }
            scene = ch.Scene.from_dict(data)
            ch.run(scene)
            walls = []
            for _ in range(5):  # the median of five: the machine is shared
                t0 = time.perf_counter()
                result = ch.run(scene)
                walls.append(time.perf_counter() - t0)
            wall = statistics.median(walls)
            quaternion_wall = quaternion_wall or wall
            rows.append(
                f"| {label} | {formulation} | {angle or '-'} | {result.counters['steps']} | "
                f"{result.counters.get('rebasings', '-')} | {wall * 1e3:.1f} ms | "
                f"{wall / quaternion_wall:.1f} |"
            )
            print(rows[-1], flush=True)
    return rows


ORBIT_NOTE = (
    "The zonal terms (J2 and higher) enter our systems through their gradient in closed form, "
    "one power of r per degree (third bodies and user potentials are differentiated by "
    "heyoka), composed with the frame tables (docs/orbits.md); the hand-written systems use "
    "the closed-form ∇Ω of J2, with literal constants that heyoka folds unless said "
    "otherwise: our constants are runtime parameters, so that scenes differing only in "
    "numbers share compiled code. The recipe is the same equations written by hand; the "
    "last row is the price of generality against algebra specialised to J2 alone."
)

#: name -> (heading, what precedes the table, the table's function), in the file's order.
SECTIONS = {
    "drift": ("Conservation and throughput of the bundled rigid-body scenes", "", drift_table),
    "compile": (
        "Compile cost",
        "A new process with heyoka's disk cache warm still builds heyoka's LLVM state once "
        "(the compile column: loading the cached object code); the whole first run() adds "
        "the model's build and the run itself.",
        compile_table,
    ),
    "formulations": (
        "Attitude formulations over t = 2·10⁴ (double, tolerance ε)",
        "Wall: median of five whole `run()`s (not interleaved: the ratios to the quaternion "
        "move with the machine's load). At equal error, timed interleaved: "
        "`python validation/users_rotation.py` (BENCHMARKS.md).",
        formulation_steps_table,
    ),
    "steps": (
        "Step cost against a hand-written heyoka system (double, tolerance ε)",
        "",
        step_cost_table,
    ),
    "orbit": (
        "Orbit step cost against hand-written heyoka systems (double, tolerance ε)",
        ORBIT_NOTE,
        orbit_step_cost_table,
    ),
}


def _section(name: str) -> list[str]:
    heading, note, fn = SECTIONS[name]
    return [f"## {heading}", "", *([note, ""] if note else []), *fn(), ""]


def _splice(text: str, name: str, lines: list[str]) -> str:
    """``text`` (ENGINE.md) with section ``name`` replaced by ``lines``."""
    # By the heading's leading words: a section whose span or options changed is found too.
    heading = "## " + SECTIONS[name][0].split(" over ")[0].split(" (")[0]
    start = text.index(heading)
    end = text.find("\n## ", start + len(heading))
    end = len(text) if end < 0 else end + 1
    return text[:start] + "\n".join(lines) + ("\n" if end < len(text) else "") + text[end:]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--only",
        nargs="+",
        choices=list(SECTIONS),
        help="regenerate these sections of the existing ENGINE.md, the others kept",
    )
    args = parser.parse_args()
    path = ROOT / "validation" / "ENGINE.md"
    if args.only:
        text = path.read_text()
        for name in args.only:
            text = _splice(text, name, _section(name))
        path.write_text(text)
        print(f"wrote the sections {args.only} of validation/ENGINE.md")
        return
    sections = [
        "# Engine figures",
        "",
        "Generated by `python validation/engine_figures.py` on "
        f"heyoka {hy.__version__}, {os.cpu_count()} cores. Drifts are relative, at the last output "
        "time; extended precisions run over shorter spans (t_end column). steps/s times a whole "
        "`run()` (model build, re-basings, recording of every output), so short runs show the "
        "fixed cost; the pure step cost is in the last table.",
        "",
    ]
    for name in SECTIONS:
        sections += _section(name)
    path.write_text("\n".join(sections))
    print("wrote validation/ENGINE.md")


if __name__ == "__main__":
    main()
