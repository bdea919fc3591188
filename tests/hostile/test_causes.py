"""Refusals at the start name the cause, not a quantity derived from it (issue 32, class 11).

A run that cannot start because a number is not finite there is refused naming the scene field
it comes from and why: moments that overflow the energy name ``body.inertia`` and
``initial.rates``; an infinite V, H or Ω names its own field and the operation of its text
that is not finite, with the values of the names it uses (``1 / eta1 divides by zero: eta1 =
0.0 (initial.eta[0])``); a user event or monitor names its ``expression``; two bodies at one
point name both bodies. Each case was blamed on ``monitors.energy`` (or a monitor, or
``integrator.precision``), ran to the end or stopped with nothing before.
"""

from __future__ import annotations

from typing import Any

import pytest
from conftest import Raw

SPAN = {"start": Raw("0.0"), "stop": Raw("1.0"), "count": 3}
PRECISIONS = ["double", "quad"]


def _free_body(**tables: Any) -> dict:
    data = {
        "body": {"inertia": [Raw("1.0"), Raw("1.5"), Raw("2.5")]},
        "initial": {"rates": [Raw("0.125"), Raw("0.25"), Raw("1.0")]},
        "output": {"times": SPAN},
    }
    data.update(tables)
    return data


def _potential(V: str, precision: str = "double", **output: Any) -> dict:
    return _free_body(
        initial={
            "rates": [Raw("0.125"), Raw("0.25"), Raw("1.0")],
            "rodrigues": [Raw("0.1"), Raw("0.2"), Raw("-0.3")],
        },
        forces={"potential": {"V": V}},
        integrator={"precision": precision},
        output={"times": SPAN, **output},
    )


def _hamiltonian(H: str, eta: list, varpi: list, precision: str = "double", **more: Any) -> dict:
    return {
        "hamiltonian": {"H": H},
        "initial": {"eta": eta, "varpi": varpi},
        "integrator": {"precision": precision},
        "output": {"times": SPAN},
        **more,
    }


def _orbit(formulation: str = "cartesian", **perturbations: Any) -> dict:
    return {
        "orbit": {
            "mu": Raw("1.0"),
            "position": [Raw("1.0"), Raw("0.0"), Raw("0.0")],
            "velocity": [Raw("0.0"), Raw("1.0"), Raw("0.2")],
            "formulation": formulation,
        },
        "perturbations": perturbations,
        "output": {"times": SPAN},
    }


def _refused(hostile, data: dict, field: str, *words: str, verb: str = "run") -> str:
    o = hostile.run([verb, str(hostile.scene(data))], expect="refused", field=field)
    line = o.error_line
    for word in words:
        assert word in line, f"{word!r} not in {line!r}"
    return line


# ---------------------------------------------------------------------- the examples
@pytest.mark.covers("class:11", "key:body.inertia", "key:initial.rates", "verb:run")
@pytest.mark.parametrize(
    ("precision", "moments", "rates"),
    [
        ("double", ["1e308", "1.5e308", "1.7e308"], ["0.125", "0.25", "1.0"]),
        ("quad", ["1e4000", "1.5e4000", "1.7e4000"], ["1e500", "2e500", "3e500"]),
    ],
)
def test_moments_that_overflow_name_the_inertia_and_the_rates(hostile, precision, moments, rates):
    data = _free_body(
        body={"inertia": [Raw(m) for m in moments]},
        initial={"rates": [Raw(w) for w in rates]},
        integrator={"precision": precision},
    )
    line = _refused(hostile, data, "body.inertia", "initial.rates", f"overflow {precision}")
    assert "monitors.energy:" not in line


@pytest.mark.covers("class:11", "key:forces.potential.V")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_force_function_that_divides_by_zero_is_named(hostile, precision):
    _refused(
        hostile,
        _potential("1/(R33 - R33)", precision),
        "forces.potential.V",
        "1 / (R33 - R33) divides by zero",
        "initial.rodrigues",
    )


@pytest.mark.covers("class:11", "key:forces.potential.V", "key:output.monitors")
def test_an_infinite_force_function_is_refused_when_the_energy_is_not_monitored(hostile):
    """Without the energy no output showed V: the run went to the end with V = inf."""
    data = _potential("1/(R33 - R33)", monitors=["momentum_squared"])
    _refused(hostile, data, "forces.potential.V", "divides by zero")


@pytest.mark.covers("class:11", "key:hamiltonian.H", "key:initial.eta")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_hamiltonian_singular_at_the_initial_coordinate_names_it(hostile, precision):
    data = _hamiltonian("varpi1**2/2 - 1/eta1", [0], [1], precision)
    _refused(hostile, data, "hamiltonian.H", "1 / eta1 divides by zero", "initial.eta[0]")


@pytest.mark.covers("class:11", "key:hamiltonian.H", "key:initial.eta")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_an_overflowing_exponential_is_named(hostile, precision):
    data = _hamiltonian("varpi1**2/2 + exp(exp(exp(3)))*eta1", [Raw("0.5")], [1], precision)
    _refused(hostile, data, "hamiltonian.H", f"exp(exp(exp(3))) overflows {precision}")


@pytest.mark.covers("class:11", "key:hamiltonian.H", "key:initial.eta")
def test_two_bodies_of_a_user_hamiltonian_at_one_point_name_both_coordinates(hostile):
    H = "(varpi1**2 + varpi2**2)/2 - 1/sqrt((eta1 - eta2)**2)"
    _refused(
        hostile,
        _hamiltonian(H, [1, 1], [0, 1]),
        "hamiltonian.H",
        "divides by zero",
        "initial.eta[0]",
        "initial.eta[1]",
    )


@pytest.mark.covers("class:11", "key:hamiltonian.bodies[*].position", "key:hamiltonian.model")
@pytest.mark.parametrize("formulation", ["canonical", "elements"])
def test_two_bodies_at_one_point_in_the_precision_name_both(hostile, formulation):
    """Apart in the scene, one point in double: H is infinite there."""
    bodies = [
        {
            "mass": Raw("0.001"),
            "position": [Raw(x), Raw("0.0"), Raw("0.1")],
            "velocity": [Raw("0.0"), Raw(v), Raw("0.0")],
        }
        for x, v in (("1.0", "1.0"), ("1.0000000000000000001", "0.9"))
    ]
    data = {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": Raw("1.0"),
            "central_mass": Raw("1.0"),
            "formulation": formulation,
            "bodies": bodies,
        },
        "output": {"times": SPAN},
    }
    _refused(hostile, data, "hamiltonian.bodies[", "hamiltonian.bodies[0]")


# ---------------------------------------------------------------------- every family and kind
@pytest.mark.covers("class:11", "key:perturbations.potential.Omega", "key:orbit.formulation")
@pytest.mark.parametrize("formulation", ["cartesian", "cayley"])
def test_a_disturbing_function_that_divides_by_zero_is_named(hostile, formulation):
    data = _orbit(formulation, potential={"Omega": "1e-6/(x - 1)"})
    _refused(hostile, data, "perturbations.potential.Omega", "divides by zero", "x = 1")


@pytest.mark.covers("class:11", "key:perturbations.third_body.a", "key:orbit.position")
def test_a_perturber_starting_at_the_orbits_position_is_named(hostile):
    third = {"gm": Raw("0.005"), "a": Raw("1.0"), "n": Raw("0.15"), "mean_anomaly0": Raw("0.0")}
    _refused(hostile, _orbit(third_body=third), "perturbations.third_body", "orbit.position")


@pytest.mark.covers("class:11", "key:perturbations.zonal.radius", "key:perturbations.zonal.J4")
def test_a_zonal_coefficient_that_overflows_is_named_not_the_precision(hostile):
    line = _refused(
        hostile,
        _orbit(zonal={"J4": Raw("1.0"), "radius": Raw("1e100")}),
        "perturbations.zonal",
        "double cannot hold",
    )
    assert "integrator.precision" not in line


@pytest.mark.covers(
    "class:11", "key:forces.heavy_top.weight", "key:forces.heavy_top.center_of_mass"
)
def test_a_heavy_top_whose_force_function_overflows_names_its_numbers(hostile):
    top = {
        "weight": Raw("1e300"),
        "center_of_mass": [Raw("1e300"), Raw("0.0"), Raw("1e300")],
    }
    data = _free_body(
        initial={
            "rates": [Raw("0.125"), Raw("0.25"), Raw("1.0")],
            "rodrigues": [Raw("0.1"), Raw("0.2"), Raw("-0.3")],
        },
        forces={"heavy_top": top},
    )
    _refused(hostile, data, "forces.heavy_top", "overflow double")


@pytest.mark.covers("class:11", "key:events.*.expression", "key:output.events")
@pytest.mark.parametrize(
    ("family", "expression", "where"),
    [
        ("rotation", "1/(p - 0.125)", "initial.rates[0]"),
        ("orbit", "log(x - 1)", "x = 1"),
        ("hamiltonian", "sqrt(eta1 - 1)", "initial.eta[0]"),
    ],
)
def test_a_user_event_not_finite_at_the_start_is_refused(hostile, family, expression, where):
    """heyoka finds no zero of a function that is NaN or infinite: the run reported none."""
    data = {
        "rotation": _free_body(),
        "orbit": _orbit(),
        "hamiltonian": _hamiltonian("varpi1**2/2 + eta1**2/2", [Raw("0.5")], [1]),
    }[family]
    data["events"] = {"bad": {"expression": expression}}
    data["output"] = {"times": SPAN, "events": ["bad"]}
    _refused(hostile, data, "events.bad.expression", where)


@pytest.mark.covers("class:11", "key:monitors.*.expression", "key:monitors")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_user_monitor_infinite_at_the_start_names_its_expression(hostile, precision):
    data = _free_body(
        monitors={"k": {"expression": "1/(p - 0.125)"}}, integrator={"precision": precision}
    )
    _refused(hostile, data, "monitors.k.expression", "divides by zero", "initial.rates[0]")


@pytest.mark.covers("class:11", "key:hamiltonian.H", "key:initial.eta")
def test_a_hamiltonian_whose_slope_is_infinite_at_the_start_is_refused(hostile):
    """H = 1/2 there, its derivative infinite: the first step failed and nothing was kept."""
    data = _hamiltonian("varpi1**2/2 + sqrt(eta1)", [0], [1])
    _refused(hostile, data, "hamiltonian.H", "derivative", "sqrt(eta1)", "initial.eta[0]")


@pytest.mark.covers("class:11", "key:forces.potential.V", "verb:check")
def test_check_names_the_force_function_too(hostile):
    _refused(hostile, _potential("1/(R33 - R33)"), "forces.potential.V", verb="check")


# ---------------------------------------------------------------------- counts beyond double
@pytest.mark.covers("key:integrator.max_step", "key:integrator.precision")
def test_a_step_count_beyond_double_is_told_not_a_traceback(hostile):
    """max_step 1e-300 over 1e300 in quad: 1e600 steps, beyond the double the message used."""
    data = _free_body(
        integrator={"precision": "quad", "max_step": Raw("1e-300")},
        output={"times": {"start": Raw("0.0"), "stop": Raw("1e300"), "count": 3}},
    )
    _refused(hostile, data, "integrator.max_step", "1.0e+600 steps")
