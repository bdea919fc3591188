"""Scene numbers: one grammar in every precision, bounded before they are built, π compared
exactly, directions normalised in the run's precision (issue 15, section 1)."""

from __future__ import annotations

import copy

import mpmath
import pytest

from cayley_heyoka import Scene, SceneError, run
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.precision import (
    MAX_BITS,
    MAX_DECIMAL_EXPONENT,
    Precision,
    decimal_text,
    exact_fraction,
    exceeds_pi,
)

PRECISIONS = [Precision(), Precision("quad"), Precision("real", 256)]


def free_body(*inertia: object, precision: object = "double") -> dict:
    return {
        "body": {"inertia": list(inertia)},
        "initial": {"rates": ["0.125", "0.25", "1.0"]},
        "integrator": {"precision": precision},
        "output": {"times": [0, 1]},
    }


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1_0", "10"),
        ("1_000.000_5", "1000.0005"),
        ("2.5e1_0", "25000000000"),
        ("+.5", "0.5"),
        ("3.", "3"),
        ("-1.25E-2", "-0.0125"),
        ("007", "7"),
        ("0.0", "0"),
    ],
)
def test_one_grammar_gives_the_same_number_in_every_precision(text, value):
    """``"1_0"`` was 10 in double and a traceback in quad: now 10 in all three."""
    assert exact_fraction(text) == exact_fraction(value)
    for precision in PRECISIONS:
        assert precision.number(text) == precision.number(value), precision.name
    if exact_fraction(value) > 0:
        scene = Scene.from_dict(free_body(text, text, text, precision="quad"))
        assert exact_fraction(scene.model.inertia[0]) == exact_fraction(value)


@pytest.mark.parametrize(
    "text",
    [
        "1__0",
        "_1",
        "1_",
        "1_.5",
        "inf",
        "-inf",
        "nan",
        "0x10",
        "1e",
        "",
        "1 0",
        "١",  # an Arabic-Indic digit: Python's float() reads it, MPFR does not
        "1e999999999",
        "1e-999999999",
        f"1e{MAX_DECIMAL_EXPONENT + 1}",
        f"1e-{MAX_DECIMAL_EXPONENT + 1}",
        "1e" + "9" * 100_000,
        "1" * 5000,
    ],
)
def test_text_that_is_not_a_bounded_decimal_is_refused_naming_the_field(text):
    """Refused by the scene, in any precision, before a big integer is built (``1e999999999``
    hung building its Fraction)."""
    with pytest.raises(ValueError):
        decimal_text(text)
    for precision in ("double", "quad", {"bits": 256}):
        with pytest.raises(SceneError) as exc:
            Scene.from_dict(free_body(text, 1, 1, precision=precision))
        assert exc.value.field == "body.inertia[0]"
        assert "number" in exc.value.constraint


def test_a_number_double_cannot_hold_is_refused_in_double_and_kept_in_quad():
    """Refused when the scene is loaded, naming the field that wrote it."""
    for text, word in (("1e400", "inf"), ("1e-400", "0.0")):
        with pytest.raises(SceneError) as exc:
            Scene.from_dict(free_body(text, text, text))
        assert exc.value.field == "body.inertia[0]"
        assert "double cannot hold" in exc.value.constraint and word in exc.value.constraint
        for precision in ("quad", {"bits": 128}):
            assert run(Scene.from_dict(free_body(text, text, text, precision=precision))).success


@pytest.mark.parametrize("bits", [MAX_BITS + 1, 1_000_000, "1" * 100_000, 63, True, 256.0])
def test_precision_bits_beyond_the_documented_limit_are_refused(bits):
    with pytest.raises(SceneError) as exc:
        Scene.from_dict(free_body(1, 1, 1, precision={"bits": bits}))
    assert exc.value.field == "integrator.precision.bits"
    assert str(MAX_BITS) in exc.value.constraint
    assert len(str(exc.value)) < 300


def test_the_largest_precision_is_accepted():
    scene = Scene.from_dict(free_body(1, 1, 1, precision={"bits": MAX_BITS}))
    assert scene.integrator.precision.bits == MAX_BITS
    # The limit is the scene's: the package computes above it (guard bits of closed forms).
    assert Precision("real", 4 * MAX_BITS).bits == 4 * MAX_BITS


# π to 40 digits is below π; the double math.pi is below both, so `<= math.pi` refused it.
with mpmath.workdps(80):
    PI40 = mpmath.nstr(mpmath.pi, 40)
    PI_PLUS = mpmath.nstr(mpmath.pi + mpmath.mpf("1e-35"), 45)


def test_pi_is_compared_exactly():
    assert not exceeds_pi(PI40) and exceeds_pi(PI_PLUS)
    assert not exceeds_pi("3.141592653589793") and not exceeds_pi(3.141592653589793)
    assert exceeds_pi("3.1415926535897932384626433832795028841972")  # π rounded up at 41
    assert not exceeds_pi("-4") and exceeds_pi("4")


def orbit(inclination: str, precision: object) -> dict:
    elements = {
        "a": "1",
        "e": "0.1",
        "inclination": inclination,
        "node": "0.2",
        "argument_of_pericentre": "0.3",
        "mean_anomaly": "0.4",
    }
    return {
        "orbit": {"mu": 1, "formulation": "quaternion", "elements": elements},
        "integrator": {"precision": precision},
        "output": {"times": [0, 1]},
    }


@pytest.mark.parametrize("precision", ["quad", {"bits": 256}])
def test_an_inclination_of_pi_to_40_digits_is_accepted_and_runs(precision):
    """Issue 15: refused in quad as "must be in [0, π]" because the check used math.pi."""
    res = run(Scene.from_dict(orbit(PI40, precision)))
    assert res.status == 0


@pytest.mark.parametrize("precision", ["double", "quad", {"bits": 256}])
def test_an_inclination_above_pi_is_refused(precision):
    with pytest.raises(SceneError) as exc:
        Scene.from_dict(orbit(PI_PLUS, precision))
    assert exc.value.field == "orbit.elements.inclination"


def test_the_third_body_and_hamiltons_bodies_compare_with_pi_exactly():
    third = {"gm": "0.005", "a": "3.5", "n": "0.15", "inclination": PI40}
    d = orbit("0.5", "quad")
    d["perturbations"] = {"third_body": third}
    Scene.from_dict(d)
    d["perturbations"]["third_body"]["inclination"] = PI_PLUS
    with pytest.raises(SceneError, match="third_body.inclination"):
        Scene.from_dict(d)
    body = {"mass": "0.001", "elements": orbit(PI40, "quad")["orbit"]["elements"]}
    ham = {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": 1,
            "central_mass": 1,
            "formulation": "canonical",
            "bodies": [body],
        },
        "integrator": {"precision": "quad"},
        "output": {"times": [0, 1]},
    }
    Scene.from_dict(ham)
    ham["hamiltonian"]["bodies"][0]["elements"]["inclination"] = PI_PLUS
    with pytest.raises(SceneError, match=r"bodies\[0\]\.inclination|inclination"):
        Scene.from_dict(ham)


def heavy_top(up: list, precision: object = "quad") -> dict:
    return {
        "body": {"inertia": ["1.0", "1.6", "2.3"]},
        "initial": {"rates": ["0.3", "1.0", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        "forces": {
            "heavy_top": {"weight": "1", "center_of_mass": ["0.1", "-0.05", "0.3"], "up": up}
        },
        "attitude": {"formulation": "rodrigues"},
        "integrator": {"precision": precision},
        "output": {"times": [0, 3]},
    }


def test_a_direction_is_normalised_in_the_run_precision():
    """``up`` within 1e-12 of unit length is accepted (a guard against typos) and normalised
    in the run's precision: the quad run equals the run given the unit vector to 45 digits
    (issue 15: used as written, it carried a 1e-13 error into quad gravity)."""
    up = ["0", "0.6", "0.8000000000001"]
    with mpmath.workdps(60):
        v = [mpmath.mpf(c) for c in up]
        norm = mpmath.sqrt(sum(c * c for c in v))
        unit = [mpmath.nstr(c / norm, 45) for c in v]
    scene = Scene.from_dict(heavy_top(up))
    model = FAMILIES["rotation"].build(scene)
    quad = scene.integrator.precision
    got = [quad.number(model.pars.values[model.pars.index(f"heavy_top.up[{i}]")]) for i in (1, 2)]
    assert got == [quad.number(unit[1]), quad.number(unit[2])]
    a, b = run(scene), run(Scene.from_dict(heavy_top(unit)))
    written = run(Scene.from_dict(heavy_top(["0", "0.6", "0.8"])))
    for name in ("p", "q", "r", "lambda", "mu", "nu"):
        assert abs(float(a[name][-1] - b[name][-1])) < 1e-30, name
    # The test can fail: the unnormalised vector's 1e-13 shows in the trajectory.
    assert max(abs(float(a[n][-1] - written[n][-1])) for n in ("p", "q", "r")) > 1e-16


def test_an_exact_unit_direction_is_used_as_written():
    scene = Scene.from_dict(heavy_top(["0", "0.6", "0.8"]))
    model = FAMILIES["rotation"].build(scene)
    assert [model.pars.values[model.pars.index(f"heavy_top.up[{i}]")] for i in range(3)] == [
        "0",
        "0.6",
        "0.8",
    ]


def test_a_direction_far_from_unit_is_refused():
    d = heavy_top(["0", "0", "1.1"])
    with pytest.raises(SceneError) as exc:
        Scene.from_dict(copy.deepcopy(d))
    assert exc.value.field == "forces.heavy_top.up"


@pytest.mark.parametrize("value", [10**4001, -(10**10_000)], ids=["1e4001", "-1e10000"])
def test_an_integer_beyond_the_limit_is_refused_without_printing_it(value):
    with pytest.raises(SceneError) as exc:
        Scene.from_dict(free_body(value, 1, 1))
    assert exc.value.field == "body.inertia[0]"
    assert "beyond 1e±4000" in exc.value.constraint and len(str(exc.value)) < 200


def test_huge_numbers_give_clear_refusals_not_overflow_errors():
    """Checks made with float() overflowed past 1e308 (OverflowError tracebacks): the
    triangle inequality, unit lengths of quaternions, rows and directions."""
    cases = [
        (free_body("1e400", 1, 1), "body.inertia"),
        (heavy_top(["1e400", "0", "0"]), "forces.heavy_top.up"),
    ]
    q = free_body(1, 1, 1)
    q["initial"]["quaternion"] = ["1e400", "0", "0", "0"]
    cases.append((q, "initial.quaternion"))
    m = free_body(1, 1, 1)
    m["initial"]["matrix"] = [["1e400", "0", "0"], ["0", "1", "0"], ["0", "0", "1"]]
    cases.append((m, "initial.matrix"))
    for d, field in cases:
        with pytest.raises(SceneError) as exc:
            Scene.from_dict(d)
        assert exc.value.field == field
    with pytest.raises(SceneError, match=r"1e400 \+ 1 < 1|1 \+ 1 < 1e400"):
        Scene.from_dict(free_body(1, 1, "1e400"))


@pytest.mark.parametrize("anomaly", ["1e25", "123456789012345678901234567.5", "1e400"])
def test_a_huge_angle_is_reduced_exactly(anomaly):
    """The mean anomaly 1e400 made Kepler's equation fail (ArithmeticError), and 1e25 came
    back as noise: reduced at the working precision only. Now it equals its exact reduction."""
    from cayley_heyoka.mechanics import kepler as el

    with mpmath.workdps(600):
        x = mpmath.mpf(anomaly)
        reduced = mpmath.nstr(x - 2 * mpmath.pi * mpmath.nint(x / (2 * mpmath.pi)), 60)
    with mpmath.workdps(40):
        a = el.elements_to_cartesian(el.Elements("1", "0.1", "0.3", "0.2", "0.4", anomaly), "1")
        b = el.elements_to_cartesian(el.Elements("1", "0.1", "0.3", "0.2", "0.4", reduced), "1")
        assert max(abs(u - w) for u, w in zip(a[0], b[0], strict=True)) < mpmath.mpf(10) ** -38


def test_mpfr_precisions_are_named_by_their_bits_never_as_heyokas_quad():
    """heyoka's ``real128`` is IEEE quad (113 bits); an MPFR precision of 128 bits is not it."""
    assert Precision("quad").name == "quad"
    assert Precision("real", 128).name == "mpfr128" and Precision("real", 256).name == "mpfr256"
    assert all(Precision("real", b).name != "real128" for b in (113, 128))
