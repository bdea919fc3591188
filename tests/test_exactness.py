"""Every number in an extended-precision system is exactly the number intended.

heyoka folds numbers in the type of their nodes, so a double node in a quad system (``3/5``
built from double 3 and 5) makes the double 0.6: 17 digits lost without a warning (issue 15).
The walker below converts every compiled expression of a model (right-hand sides, events,
terminal events, outputs, monitors) to sympy without evaluation, where each number keeps its
binary precision, and fails on

* a double node in a quad or multiprecision system that is not a short dyadic rational (a
  rounded rational like 0.2 fills the 53-bit significand; one of at most ``SHORT_BITS``
  significant bits, like 0.5 or 1.5, is exact in every type),
* a node of another precision than the run's (a ``real128`` in a 256-bit run),
* a node of the run's precision whose value has 21 to 53 significant bits (it came through a
  double: ``real128(0.1)``),

and checks that the model's runtime parameters hold decimal text, exact integers or numbers
built in the run's type, never a rounded double. It walks every bundled example and variants
covering every option that adds terms, in quad and in 256 bits; ``COVERAGE`` counts the
systems × precisions walked (printed by ``-s``, asserted below).
"""

from __future__ import annotations

import copy
import math
from fractions import Fraction
from pathlib import Path

import heyoka as hy
import mpmath
import numpy as np
import pytest
import sympy

from cayley_heyoka import Scene, run
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.model import Model
from cayley_heyoka.core.precision import Precision, decimal_text
from cayley_heyoka.core.scene import read_toml

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
PRECISIONS = {"quad": "quad", "real256": {"bits": 256}}
#: Significant bits of a double that is surely meant exactly (½, 3/2, 15/8 and the like).
SHORT_BITS = 20


def _example(name: str) -> dict:
    return read_toml(EXAMPLES / f"{name}.toml")


def _variant(name: str, **tables) -> dict:
    """Example ``name`` with whole tables replaced (``None`` removes one)."""
    d = copy.deepcopy(_example(name))
    for key, value in tables.items():
        if value is None:
            d.pop(key, None)
        else:
            d[key] = value
    return d


def _with_events(d: dict, events: dict) -> dict:
    d["events"] = events
    out = d.setdefault("output", {})
    out["events"] = [*out.get("events", []), *events]
    return d


def _scenes() -> dict[str, dict]:
    scenes = {f"example:{p.stem}": read_toml(p) for p in sorted(EXAMPLES.glob("*.toml"))}
    free = _example("free_body")
    user_event = {"spin": {"expression": "p - 1/3 + r/7", "direction": "up"}}
    V = "-3*R33/5 + R31**2/7 - sin(t/11)/3 + lambda*mu/9 + (A - B)/C*R12/13"
    for formulation in ("rodrigues", "quaternion"):
        att = {"formulation": formulation}
        scenes[f"rotation:V:{formulation}"] = _with_events(
            _variant("free_body", forces={"potential": {"V": V}}, attitude=att), user_event
        )
        scenes[f"rotation:gravity_gradient:{formulation}"] = _variant(
            "free_body",
            forces={"gravity_gradient": {"gm": 3, "distance": 7, "direction": ["0.6", 0, "0.8"]}},
            attitude=att,
        )
        scenes[f"rotation:heavy_top:{formulation}"] = _variant("heavy_top", attitude=att)
    scenes["rotation:rates_only"] = _variant(
        "free_body", attitude={"formulation": "none"}, initial={"rates": free["initial"]["rates"]}
    )
    scenes["rotation:free:events"] = _with_events(_variant("free_body"), user_event)
    d = _variant("heavy_top", attitude={"formulation": "poisson"})
    d["output"]["azimuth"] = True
    scenes["rotation:heavy_top:poisson+azimuth"] = d
    # Cayley's orbit started in the reference plane: the tilted frame's equations (orbit/tilt.py),
    # with the turning plane's rates referred to it.
    d = _variant("orbit_moving_plane")
    d["orbit"]["position"] = ["1", "0", "0"]
    d["orbit"]["velocity"] = ["0", "1.1", "1e-6"]
    d["perturbations"]["zonal"].update({"J3": "-2.5e-6"})
    scenes["orbit:cayley:tilted"] = d

    for formulation in ("cayley", "quaternion", "cartesian", "encke"):
        d = _variant("orbit_moving_plane")
        d["orbit"]["formulation"] = formulation
        if formulation in ("cartesian", "encke"):
            d["orbit"].pop("sigma0")
        d["perturbations"]["zonal"].update({"J3": "-2.5e-6", "J4": "1e-6"})
        _with_events(d, {"z_level": {"expression": "z - 1/7 + x/3", "direction": "any"}})
        scenes[f"orbit:{formulation}:zonal+third+plane"] = d
    d = _variant("orbit_j2_third_body")
    d["perturbations"]["third_body"].update({"eccentricity": "0.1", "degree": 4})
    d["reference_plane"]["sigma_rate"] = "0.001"
    scenes["orbit:cayley:third_body_degree4+sigma_rate"] = d
    d = _variant("orbit_j2_third_body")
    d["orbit"]["formulation"] = "quaternion"
    d["perturbations"] = {"potential": {"Omega": "1e-6*mu*z**2/r**5/3 + sin(t/7)/1000"}}
    scenes["orbit:quaternion:Omega"] = d
    d = _variant("orbit_j2_third_body")
    d["orbit"]["formulation"] = "cartesian"
    d["orbit"].pop("sigma0")
    d["perturbations"]["third_body"] = {"gm": "0.005", "a": "3.5", "n": "0.15"}
    scenes["orbit:cartesian:circular_third_body"] = d

    proj = _example("projectile")
    _with_events(proj, {"top": {"expression": "varpi3 - 1/3", "direction": "down"}})
    scenes["hamilton:projectile:canonical+events"] = proj
    d = copy.deepcopy(proj)
    d["hamiltonian"]["formulation"] = "elements"
    scenes["hamilton:projectile:elements"] = d
    scenes["hamilton:H"] = oscillator()
    # Three bodies of masses 1, 3, 7 in the plane: the canonical equations in exact normal form
    # (cayley_heyoka.core.symbolic), whose coefficients 1/3, 1/7, 21/10 and exponent -3/2 come
    # from the text's integers.
    kinetic = "(varpi1**2 + varpi2**2)/2 + (varpi3**2 + varpi4**2)/6 + (varpi5**2 + varpi6**2)/14"
    pairs = [(1, 2, 3), (1, 3, 7), (2, 3, 21)]
    potential = " - ".join(
        f"{c}/(10*sqrt((eta{2 * i - 1} - eta{2 * j - 1})**2 + (eta{2 * i} - eta{2 * j})**2))"
        for i, j, c in pairs
    )
    scenes["hamilton:H:three_bodies"] = {
        "hamiltonian": {"H": f"{kinetic} - {potential} + 0.1*sin(t/7)*eta1/3"},
        "initial": {
            "eta": ["1", "0", "-1", "0.5", "0", "2"],
            "varpi": ["0", "1", "0.3", "0", "-0.7", "0"],
        },
        "output": {"times": {"start": 0, "stop": 1, "count": 2}, "principal_function": True},
    }
    scenes["hamilton:H1+H2:elements"] = {
        "hamiltonian": {
            "H1": "(varpi1**2 + eta1**2)/2",
            "H2": "eta1**4/20 + 3*eta1**3/7",
            "formulation": "elements",
            "flow": {
                "eta1": "chi1*cos(t) + lambda1*sin(t)",
                "varpi1": "lambda1*cos(t) - chi1*sin(t)",
            },
        },
        "initial": {"eta": ["0.5"], "varpi": ["0.25"]},
        "output": {"times": {"start": 0, "stop": 1, "count": 2}, "principal_function": True},
    }
    d = _example("planets")
    d["hamiltonian"]["formulation"] = "canonical"
    scenes["hamilton:predominant_mass:canonical"] = d
    return scenes


def oscillator(precision: object = "double", stop: str = "10") -> dict:
    """H = ϖ²/2 + η²/5: ω = √(2/5), solved in closed form by :func:`oscillator_exact`."""
    return {
        "hamiltonian": {"H": "varpi1**2/2 + eta1**2/5"},
        "initial": {"eta": ["1.25"], "varpi": ["-0.75"]},
        "integrator": {"precision": precision},
        "output": {"times": {"start": 0, "stop": stop, "count": 2}, "principal_function": True},
    }


def oscillator_exact(t: str, dps: int = 120) -> tuple[mpmath.mpf, mpmath.mpf]:
    with mpmath.workdps(dps):
        w = mpmath.sqrt(mpmath.mpf(2) / 5)
        eta0, varpi0, t = mpmath.mpf("1.25"), mpmath.mpf("-0.75"), mpmath.mpf(t)
        eta = eta0 * mpmath.cos(w * t) + varpi0 / w * mpmath.sin(w * t)
        varpi = varpi0 * mpmath.cos(w * t) - eta0 * w * mpmath.sin(w * t)
        return +eta, +varpi


SCENES = _scenes()
COVERAGE: dict[str, int] = {}
SELECT_OUTPUTS: set[str] = set()


def expressions(model: Model) -> list[tuple[str, hy.expression]]:
    """Every expression of a model that heyoka compiles, named by where it sits."""
    out = [(f"d{v}/dt", rhs) for v, rhs in model.system]
    out += [(f"event {e.name}/{e.label}", e.expression) for e in model.events]
    out += [(f"terminal {e.counter}", e.expression) for e in model.terminal]
    out += [(f"output {k}", v) for k, v in model.outputs.items()]
    for k, v in model.monitors.items():
        out += [(f"monitor {k}", x) for x in (v if isinstance(v, list) else [v])]
    return out


def inexact_numbers(expr: hy.expression, bits: int) -> list[str]:
    """The number nodes of ``expr`` that are not exactly intended in a ``bits``-bit run."""
    # evaluate(False): sympy would otherwise fold 0.5*x*0.2 into one Float of the lower
    # precision, hiding (or inventing) a double.
    with sympy.evaluate(False):
        tree = hy.to_sympy(expr)
    bad = []
    # Depth first, each node once: heyoka's trees share subexpressions (the planets' system is
    # 1.4 million nodes walked naively, a few thousand distinct ones).
    seen, stack = set(), [tree]
    while stack:
        node = stack.pop()
        if id(node) in seen:
            continue
        seen.add(id(node))
        stack.extend(node.args)
        if not isinstance(node, sympy.Float):
            continue  # integers, and the ½ of sqrt, are exact in every type
        prec, significant = node._prec, node._mpf_[3]
        if prec == 53:
            if significant > SHORT_BITS:
                bad.append(f"double {node}")
        elif prec != bits:
            bad.append(f"{prec}-bit {node}")
        elif SHORT_BITS < significant <= 53:
            bad.append(f"{node} (a double's value, {significant} bits)")
    return bad


def inexact_parameters(model: Model, precision: Precision) -> list[str]:
    """Runtime parameters whose value is not text, an integer or a number of the run's type."""
    bad = []
    for name, value in zip(model.pars.names, model.pars.values, strict=True):
        if isinstance(value, str):
            decimal_text(value)  # raises on text that is not a decimal number
        elif isinstance(value, int | Fraction):
            pass
        elif isinstance(value, precision.fp_type):
            if precision.kind == "real" and value.prec != precision.bits:
                bad.append(f"{name} = {value} has {value.prec} bits")
            x = float(value)
            if value == precision.number(x) and _significant_bits(x) > SHORT_BITS:
                bad.append(f"{name} = {value} is a double's value")
        else:
            bad.append(f"{name} = {value!r} is a {type(value).__name__}")
    return bad


def _significant_bits(x: float) -> int:
    n = Fraction(x).numerator
    return (abs(n) // (n & -n)).bit_length() if n else 0


@pytest.mark.parametrize("precision", sorted(PRECISIONS))
@pytest.mark.parametrize("name", sorted(SCENES))
def test_every_number_is_exact(name, precision):
    d = copy.deepcopy(SCENES[name])
    d.setdefault("integrator", {})["precision"] = PRECISIONS[precision]
    scene = Scene.from_dict(d)
    model = FAMILIES[scene.family].build(scene)
    bits = scene.integrator.precision.bits
    bad = {}
    for where, e in expressions(model):
        try:
            found = inexact_numbers(e, bits)
        except TypeError as exc:
            # heyoka's select (the attitude of a reduced body, Shepperd's choice: rotation/
            # azimuth.py) has no sympy form. Those outputs are checked by value instead:
            # tests/rotation/test_azimuth.py finds them within quad and MPFR round-off of a
            # run in more bits, where one double constant would leave 1e-17.
            if "select" not in str(exc) or not where.startswith("output "):
                raise
            SELECT_OUTPUTS.add(where)
            continue
        if found:
            bad[where] = found
    assert not bad, f"{name} in {precision}: inexact number nodes {bad}"
    assert not inexact_parameters(model, scene.integrator.precision)
    COVERAGE[f"{name}/{precision}"] = len(expressions(model))


def test_coverage_counts_every_system_in_both_precisions():
    """Runs after the walks (pytest keeps file order): every scene × precision was walked."""
    print(
        f"\nexactness walker: {len(COVERAGE)} systems × precisions, "
        f"{sum(COVERAGE.values())} expressions"
    )
    if len(COVERAGE) < 2 * len(SCENES):
        pytest.skip("only part of the walks ran (selected by -k)")
    # Only the reduced body's attitude outputs escape the walk (checked by value instead).
    assert SELECT_OUTPUTS == {
        f"output {n}" for n in ("qw", "qx", "qy", "qz", "lambda", "mu", "nu")
    }, SELECT_OUTPUTS
    assert len(COVERAGE) == 2 * len(SCENES)
    families = {k.split(":")[0] for k in SCENES}
    assert families == {"example", "rotation", "orbit", "hamilton"}


def test_the_walker_sees_a_double_in_a_quad_system():
    """The walker itself: the double folding of 3/5 that issue 15 measured is caught."""
    x = hy.make_vars("x")
    assert inexact_numbers(x * hy.expression(3.0) / hy.expression(5.0), 113)
    assert inexact_numbers(x * hy.expression(hy.real128(0.1)), 113)
    assert inexact_numbers(x / hy.expression(hy.real128(5)), 256)
    assert not inexact_numbers(x * hy.expression(1.5) / hy.expression(hy.real128(5)), 113)


@pytest.mark.parametrize(("precision", "bound"), [("quad", 1e-32), ({"bits": 256}, 1e-70)])
def test_oscillator_with_a_fifth_matches_its_closed_form(precision, bound):
    """H = ϖ²/2 + η²/5 at t = 10: within 1e-32 in quad, 1e-70 in 256 bits (issue 15 measured
    1.9e-16 in quad while 1/5 was folded as a double)."""
    res = run(Scene.from_dict(oscillator(precision)))
    eta, varpi = oscillator_exact("10")
    for name, exact in (("eta1", eta), ("varpi1", varpi)):
        with mpmath.workdps(120):
            error = abs(mpmath.mpf(str(res[name][-1])) - exact)
            assert error < bound, (name, error)


def test_integer_fraction_in_a_force_function_equals_its_decimal_in_quad():
    """V = -3*R33/5 and V = -0.6*R33 are the same force to quad round-off (issue 15: 17
    digits apart while 3/5 was folded as a double)."""
    results = []
    for V in ("-3*R33/5", "-0.6*R33"):
        d = _variant("heavy_top", forces={"potential": {"V": V}})
        d["integrator"] = {"precision": "quad"}
        d["output"] = {"times": {"start": 0, "stop": 5, "count": 2}}
        results.append(run(Scene.from_dict(d)))
    a, b = results
    for name in ("p", "q", "r", "lambda", "mu", "nu"):
        diff = abs(float(a[name][-1] - b[name][-1]))
        assert diff < 1e-30, (name, diff)
    assert math.isfinite(float(a["p"][-1]))
    assert np.all(a["p"] != 0)
