"""Hostile numbers (issue 32, classes 1, 10, 11 and 12): one input path checks every number in
the run's precision, named by its field (or by the option or parameter that gave it), and the
progress bars, ``reference`` and ``check`` take the checked scene's grid, in any precision.

Each case ends as conftest.py requires; the Python API's cases raise the documented error, or
keep the number exactly.
"""

from __future__ import annotations

import io
import re
from decimal import Decimal
from fractions import Fraction

import heyoka as hy
import mpmath
import numpy as np
import pytest
from conftest import Raw

import cayley_heyoka as ch
from cayley_heyoka.cli.show import time_bar
from cayley_heyoka.core.errors import OptionError, SceneError
from cayley_heyoka.core.precision import exact_fraction
from cayley_heyoka.reference import FreeRigidBody

CLOSE = [Raw("0.1"), Raw("0.10000000000000000001"), Raw("1.0")]  # one double, two quads


def body(times, precision="double", max_steps=None, rates=None):
    """A torque-free body (rates alone, no attitude: compiles and steps fastest)."""
    integrator = {"precision": precision}
    if max_steps is not None:
        integrator["max_steps"] = max_steps
    return {
        "body": {"inertia": [Raw("1.0"), Raw("1.5"), Raw("2.5")]},
        "initial": {"rates": rates or [Raw("0.125"), Raw("0.25"), Raw("1.0")]},
        "integrator": integrator,
        "output": {"times": times},
    }


def grid(start, stop, count):
    return {"start": Raw(start), "stop": Raw(stop), "count": count}


# ---------------------------------------------------------------------- class 1: the bar
@pytest.mark.covers("class:1", "verb:run", "option:run --progress", "key:output.times")
@pytest.mark.parametrize(
    "times",
    [CLOSE, grid("-1e308", "1e308", 3)],
    ids=["equal-once-rounded", "span-beyond-double"],
)
def test_run_progress_refuses_what_run_refuses(hostile, times):
    """The bar built its own double grid before the scene's checks: a traceback."""
    scene = hostile.scene(body(times))
    for bar in ("--progress", "--no-progress"):
        hostile.run(["run", str(scene), bar], expect="refused", field="output.times")


@pytest.mark.covers("class:1", "verb:reference", "option:reference --progress")
def test_reference_progress_of_a_quad_scene_with_times_one_in_double(hostile, tmp_path):
    """The bar took the grid in double: a traceback for a valid quad scene."""
    scene = hostile.scene(body(CLOSE, "quad"))
    out = tmp_path / "r.h5"
    argv = ["reference", str(scene), "--digits", "25", "--out", str(out), "--progress"]
    o = hostile.run(argv, expect="done", out=out)
    assert "of 1.0" in o.stderr


@pytest.mark.covers("class:1", "option:reference --digits")
def test_reference_in_a_precision_that_cannot_hold_the_times_says_so(hostile, tmp_path):
    """5 digits choose double, where the quad scene's times are one: the refusal says that
    the reference chose double, and how to choose another."""
    scene = hostile.scene(body(CLOSE, "quad"))
    argv = ["reference", str(scene), "--digits", "5", "--out", str(tmp_path / "r.h5")]
    o = hostile.run([*argv, "--progress"], expect="refused", field="output.times")
    assert "the precision chosen for 5 digits" in o.error_line
    assert not (tmp_path / "r.h5.work").exists()


@pytest.mark.covers("class:1", "option:run --progress", "key:output.times.stop")
@pytest.mark.parametrize(
    ("precision", "times", "shown"),
    [
        # A quad span of 1e-3 at 1e15: a double cannot tell its ends apart (the bar read
        # "t = 1e+15 of 1e+15").
        ("quad", grid("1e15", "1000000000000000.001", 3), "of 1000000000000000.001"),
        # A quad span beyond double's range (the bar's total was inf: a traceback).
        ("quad", grid("0", "1e4000", 3), "of 1.0e+4000"),
        ({"bits": 128}, grid("-1e3000", "1e3000", 3), "of 1.0e+3000"),
    ],
    ids=["quad-1e15", "quad-1e4000", "mpfr-1e3000"],
)
def test_the_bar_shows_spans_a_double_cannot(hostile, precision, times, shown):
    """The step budget ends these runs (or refuses the span at once): a clean stop or refusal
    either way, with the bar drawn from the checked grid."""
    scene = hostile.scene(body(times, precision, max_steps=20))
    o = hostile.run(["run", str(scene), "--progress"], expect={"done", "stopped", "refused"})
    assert shown in o.stderr
    if o.kind == "refused":
        assert "output.times" in o.error_line and "inf" not in o.error_line


@pytest.mark.covers("class:1", "key:output.times")
def test_a_double_grid_whose_steps_overflow_but_whose_times_do_not(hostile):
    """[0, 1e305] with 2000 times: (b - a) k overflows, no time does (refused as 'the grid
    overflows' at time [1798]). The grid is built scaled, so the span is judged by the step
    budget instead."""
    scene = hostile.scene(body(grid("0", "1e305", 2000), max_steps=20))
    o = hostile.run(["run", str(scene), "--progress"], expect="refused", field="output.times")
    assert "needs about" in o.error_line and "overflows" not in o.error_line
    checked = ch.load_scene(scene).time_grid
    assert checked[-1] == 1e305 and np.all(np.diff(checked) > 0)


@pytest.mark.covers("class:1", "verb:run", "key:output.times.start")
@pytest.mark.parametrize("precision", ["double", "quad"])
def test_a_start_whose_spacing_exceeds_the_steps_is_refused_not_run_for_ever(hostile, precision):
    """At t = -1e25 a double's spacing is 2³¹: heyoka's time moves in its low part only, and
    the step budget's estimate read the high part, saw no time covered and let the run take
    its 10⁹ steps (a hang of half an hour). Quad at -1e40 alike."""
    start = "-1e25" if precision == "double" else "-1e40"
    scene = hostile.scene(body(grid(start, "0", 2), precision))
    o = hostile.run(["run", str(scene)], expect="refused", field="output.times", seconds=30)
    assert "needs about" in o.error_line


@pytest.mark.covers("class:1", "key:integrator.max_step")
def test_a_step_cap_over_a_quad_span_beyond_double_is_refused_by_its_count(hostile):
    """The steps it needs (1e8000) were printed through float(): an OverflowError."""
    data = body(grid("0", "1e4000", 3), "quad")
    data["integrator"]["max_step"] = Raw('"1e-4000"')
    o = hostile.run(
        ["run", str(hostile.scene(data))], expect="refused", field="integrator.max_step"
    )
    assert "needs at least 1.0e+8000 steps" in o.error_line


@pytest.mark.covers("class:1", "api:time_bar")
@pytest.mark.parametrize(
    ("t0", "t1", "t", "fraction"),
    [
        (-1e308, 1e308, 5e307, 0.75),  # t1 - t0 overflows
        (1e15, 1e15 + 0.25, 1e15 + 0.125, 0.5),  # a double's spacing there is 0.125
        (hy.real128("1e15"), hy.real128("1000000000000000.001"), hy.real128("1e15") + 0.0005, 0.5),
        (hy.real128(0), hy.real128("1e4000"), hy.real128("2.5e3999"), 0.25),
        (hy.real("-1e5000", 256), hy.real("1e5000", 256), hy.real(0, 256), 0.5),
        (hy.real128(0), hy.real128(10), hy.real("2.5", 256), 0.25),  # another run's precision
        (0.0, 1.0, float("nan"), 0.0),
        (2.0, 2.0, 2.0, 1.0),  # one output time
    ],
)
def test_the_bar_fraction_is_safe_in_any_precision(t0, t1, t, fraction):
    bar = time_bar(t0, t1, file=io.StringIO())
    bar.update_to(t)
    assert bar.n == pytest.approx(fraction, abs=1e-12)
    assert "inf" not in bar.format_dict["t_end"] and "nan" not in bar.format_dict["t_end"]
    bar.close()


# ---------------------------------------------------------------------- class 10: Python numbers
EXACT = [
    (np.float32(1e-7), float(np.float32(1e-7))),
    (np.float16(0.1), float(np.float16(0.1))),
    (np.int64(3), 3),
    (np.longdouble(1) / np.longdouble(10), Fraction(*(np.longdouble(1) / 10).as_integer_ratio())),
    (Fraction(3, 8), Fraction(3, 8)),
    (Decimal("0.1"), Fraction(1, 10)),
    (mpmath.mpf("0.1"), Fraction(mpmath.mpf("0.1").man) * Fraction(2) ** mpmath.mpf("0.1").exp),
    (hy.real128("0.1"), None),  # checked against the quad itself below
    (10**400, 10**400),
]


@pytest.mark.covers("class:10", "api:Scene.from_dict", "key:initial.rates")
def test_every_kind_of_number_enters_with_its_exact_value():
    """np.float32 was 'not a number', a real128 'not a number'; now each keeps its exact
    value in a quad scene, in the model and in the source that rebuilds the scene."""
    for value, exact in EXACT:
        data = body(grid("0", "1", 2), "quad", rates=[value, Raw("0.25"), Raw("1.0")])
        scene = ch.Scene.from_dict(data)
        again = ch.Scene.from_dict(scene.to_dict())
        assert again.model.rates == scene.model.rates, value
        if exact is None:
            assert ch.Precision("quad").number(scene.model.rates[0]) == value
        else:
            assert exact_fraction(scene.model.rates[0]) == exact, value


REFUSED = [
    (True, "must be a number (an int, a float, decimal text"),
    (np.True_, "must be a number"),
    (None, "got None"),
    (1 + 2j, "got (1+2j)"),
    (Fraction(1, 3), "Fraction(1, 3) has no finite decimal expansion"),
    (np.float64("nan"), "nan is not finite"),
    (mpmath.inf, "not finite"),
    (Decimal("Infinity"), "not finite"),
]


@pytest.mark.covers("class:10", "api:Scene.from_dict", "key:initial.rates")
def test_other_values_are_refused_naming_the_field_and_the_kinds_taken():
    for value, words in REFUSED:
        data = body(grid("0", "1", 2), rates=[value, Raw("0.25"), Raw("1.0")])
        with pytest.raises(SceneError) as exc:
            ch.Scene.from_dict(data)
        assert exc.value.field == "initial.rates[0]" and words in exc.value.constraint, value


@pytest.mark.covers("class:10", "api:Scene.from_dict", "key:initial.rates")
def test_a_huge_integer_is_refused_in_double_and_shown_as_itself():
    """10**400 was reported cut to 60 digits (reading as 1e59), at run time, on
    integrator.precision."""
    data = body(grid("0", "1", 2), rates=[10**400, Raw("0.25"), Raw("1.0")])
    with pytest.raises(SceneError) as exc:
        ch.Scene.from_dict(data)
    assert exc.value.field == "initial.rates[0]"
    assert "1.00000e+400 (an integer of 401 digits)" in exc.value.constraint
    assert "0" * 60 not in exc.value.constraint


@pytest.mark.covers(
    "class:10",
    "api:run",
    "api:check_scene",
    "api:generate_reference",
    "api:propagate_ensemble",
    "api:run_sweep",
)
def test_a_dictionary_is_not_a_scene(tmp_path):
    """run(dict) raised AttributeError deep inside."""
    data = body(grid("0", "1", 2))
    calls = [
        lambda: ch.run(data),
        lambda: ch.check_scene(data),
        lambda: ch.generate_reference(data, 5, tmp_path / "r.h5"),
        lambda: ch.propagate_ensemble(data, [[0.1, 0.2, 0.3]], 1),
    ]
    for call in calls:
        with pytest.raises(TypeError, match=r"scene must be a Scene \(build it with Scene\.from_"):
            call()
    assert not (tmp_path / "r.h5").exists()
    with pytest.raises(TypeError, match=r"study must be a Study \(build it with Study\.from_"):
        ch.run_sweep({"title": "s", "scene": data, "sweep": {}})


@pytest.mark.covers("class:10", "api:propagate_ensemble")
@pytest.mark.parametrize(
    ("t_end", "error", "words"),
    [
        (10**400, ValueError, "t_end double cannot hold 1.00000e+400"),
        (True, TypeError, "t_end must be a number"),
        ("1e-400", ValueError, "t_end double cannot hold '1e-400'"),
    ],
)
def test_ensemble_end_time_is_checked_as_a_scene_number(t_end, error, words):
    scene = ch.Scene.from_dict(body(grid("0", "1", 2)))
    with pytest.raises(error, match=re.escape(words)):
        ch.propagate_ensemble(scene, [[0.125, 0.25, 1.0]], t_end, mode="serial")


@pytest.mark.covers("class:10", "api:FreeRigidBody")
def test_the_closed_form_takes_numpy_fractions_and_decimals():
    """np.float32, Fraction and Decimal were 'not a real number'."""
    given = FreeRigidBody(
        [np.float32(1), Fraction(3, 2), Decimal("2.5")],
        [np.float64(0.125), np.int64(1) / 4, hy.real128(1)],
        dps=10,
    )
    written = FreeRigidBody(["1", "1.5", "2.5"], ["0.125", "0.25", "1"], dps=10)
    assert given.h == written.h and given.k == written.k


# ---------------------------------------------------------------------- class 11: the right name
@pytest.mark.covers("class:11", "verb:run", "key:output.times.stop", "key:output.times")
@pytest.mark.parametrize(
    ("times", "field"),
    [
        (grid("0", "1e-400", 3), "output.times.stop"),
        (grid("-1e400", "0", 3), "output.times.start"),
        ([Raw("0"), Raw("1e-400")], "output.times[1]"),
        # Subnormal in double: held with fewer than 53 bits, refused as such.
        ([Raw("0"), Raw("1e-310")], "output.times[1]"),
    ],
)
def test_a_time_double_cannot_hold_names_its_field(hostile, times, field):
    """Refused as integrator.precision: double cannot hold '1e-400'. Quad holds each (the
    span of 1e400 is then refused for the step budget it needs, by output.times)."""
    o = hostile.run(["run", str(hostile.scene(body(times)))], expect="refused", field=field)
    assert "integrator.precision" not in o.error_line
    o = hostile.run(["run", str(hostile.scene(body(times, "quad")))], expect={"done", "refused"})
    assert o.kind == "done" or "needs about" in o.error_line


@pytest.mark.covers("class:11", "key:initial.rates")
def test_a_subnormal_is_refused_in_double_only(hostile):
    """5e-324 ran with one significant bit."""
    rates = [Raw("5e-324"), Raw("0.25"), Raw("1.0")]
    scene = hostile.scene(body(grid("0", "1", 3), rates=rates))
    o = hostile.run(["run", str(scene)], expect="refused", field="initial.rates[0]")
    assert "smallest normal number" in o.error_line and "1 of its 53 bits" in o.error_line
    for precision in ("quad", {"bits": 128}):
        scene = hostile.scene(body(grid("0", "1", 3), precision, rates=rates))
        hostile.run(["run", str(scene)], expect="done")


@pytest.mark.covers(
    "class:11",
    "verb:reference",
    "option:reference --precision",
    "option:reference --tolerance",
    "option:reference --max-bits",
)
@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--precision", "10"], "--precision (bits) must be an integer >= 64 and <= 1024"),
        (["--precision", "5000"], "--precision (bits) must be an integer >= 64 and <= 1024"),
        (["--tolerance", "inf"], "--tolerance must be a finite number: 'inf'"),
        (["--tolerance", "2"], "--tolerance must be < 1"),
        (["--tolerance", "1e-90"], "--tolerance must be >= 1e-6 x the epsilon of double"),
        (["--tolerance", "1e-400"], "--tolerance must be >= 1e-6 x the epsilon"),
        (["--max-bits", "4096"], "--max-bits must be an integer in 53 … 1024"),
    ],
)
def test_reference_options_are_refused_by_their_names(hostile, tmp_path, options, words):
    """--precision 10 and --tolerance inf blamed the scene file's integrator fields."""
    scene = hostile.scene(body(grid("0", "1", 3)))
    out = tmp_path / "r.h5"
    argv = ["reference", str(scene), "--digits", "5", "--out", str(out), *options]
    o = hostile.run(argv, expect="refused", field=words, seconds=20)
    assert "integrator." not in o.error_line and str(scene) not in o.error_line
    assert not out.exists() and not (tmp_path / "r.h5.work").exists()


@pytest.mark.covers("class:11", "api:generate_reference")
@pytest.mark.parametrize(
    ("kwargs", "error", "words"),
    [
        ({"tolerance": "0.5e1"}, OptionError, "tolerance must be < 1"),
        ({"tolerance": np.float32(1e-30)}, OptionError, "tolerance must be >= 1e-6"),
        ({"tolerance": True}, TypeError, "tolerance must be a number"),
        ({"max_bits": 10**400}, ValueError, "max_bits must be an integer in 53"),
    ],
)
def test_generate_reference_names_its_arguments(tmp_path, kwargs, error, words):
    scene = ch.Scene.from_dict(body(grid("0", "1", 3)))
    with pytest.raises(error, match=words):
        ch.generate_reference(scene, 5, tmp_path / "r.h5", **kwargs)
    assert not (tmp_path / "r.h5.work").exists()


@pytest.mark.covers("class:11", "verb:check", "option:check --set")
@pytest.mark.parametrize("value", ["1e400", "1e-400", "inf", "abc"])
def test_check_number_option_is_named_by_the_option(hostile, value):
    """--set upsilon0=1e400 blamed integrator.precision (or gave no field at all)."""
    top = {
        "body": {"inertia": [Raw("1.0"), Raw("1.5"), Raw("2.5")]},
        "initial": {"rates": [Raw("0.5"), Raw("0.25"), Raw("1.0")]},
        "forces": {"heavy_top": {"weight": Raw("0.01"), "center_of_mass": [0, 0, Raw("0.1")]}},
        "output": {"times": grid("0", "1", 3)},
    }
    argv = ["check", str(hostile.scene(top)), "--set", f"upsilon0={value}"]
    hostile.run(argv, expect="refused", field="--set upsilon0:")


@pytest.mark.covers("class:11", "verb:sweep", "study-key:sweep.parameters")
@pytest.mark.parametrize(
    ("spec", "field"),
    [
        ({"start": Raw("0.1"), "stop": Raw("1e400"), "count": 3}, '"initial.rates[0]".stop'),
        ([Raw("0.1"), Raw("1.0000000000000000000000000000001e400")], '"initial.rates[0]"[1]'),
        ([Raw("0.1"), Raw("1e-310")], '"initial.rates[0]"[1]'),
    ],
)
def test_sweep_values_are_held_in_the_scene_precision_by_their_names(hostile, spec, field):
    """Refused per member, naming the member's field (and a long value's text overflowed
    the member's description: a traceback)."""
    scene = hostile.scene(body(grid("0", "1", 3)))
    sweep = {"kind": "grid", "parameters": {"initial.rates[0]": spec}}
    study = hostile.scene({"title": "s", "scene": str(scene), "sweep": sweep})
    hostile.run(["sweep", str(study)], expect="refused", field=f"sweep.parameters.{field}")


# ---------------------------------------------------------------------- class 12: π in a precision
with mpmath.workdps(200):
    _PI = mpmath.nstr(+mpmath.pi, 150, strip_zeros=False)
PI36, PI49 = _PI[:38], _PI[:51]  # truncations: below π, each rounded above it once before


def orbit(inclination: str, precision) -> dict:
    elements = {
        "a": Raw("1.0"),
        "e": Raw("0.1"),
        "inclination": inclination,
        "node": Raw("0.2"),
        "argument_of_pericentre": Raw("0.3"),
        "mean_anomaly": Raw("0.4"),
    }
    return {
        "orbit": {"mu": Raw("1.0"), "elements": elements},
        "integrator": {"precision": precision},
        "output": {"times": grid("0", "1", 3)},
    }


@pytest.mark.covers("class:12", "key:orbit.elements.inclination")
@pytest.mark.parametrize("precision", ["double", "quad", {"bits": 128}])
def test_an_inclination_of_pi_to_36_digits_runs(hostile, precision):
    """Accepted exactly (below π), then rounded twice at 30 digits, above mpmath's π: the
    element conversion raised ValueError with a traceback."""
    hostile.run(["run", str(hostile.scene(orbit(PI36, precision)))], expect="done")


@pytest.mark.covers("class:12", "key:hamiltonian.bodies")
def test_a_hamilton_body_inclined_at_pi_to_49_digits_runs(hostile):
    """The same at the 40 digits of Hamilton's body checks."""
    scene = {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": Raw("1.0"),
            "central_mass": Raw("1.0"),
            "bodies": [
                {
                    "mass": Raw("0.001"),
                    "elements": {
                        "a": Raw("1.0"),
                        "e": Raw("0.05"),
                        "inclination": PI49,
                        "node": Raw("0.3"),
                        "argument_of_pericentre": Raw("1.1"),
                        "mean_anomaly": Raw("0.4"),
                    },
                }
            ],
        },
        "output": {"times": grid("0", "1", 3)},
    }
    hostile.run(["run", str(hostile.scene(scene))], expect="done")
