"""Short, useful ``repr`` of scenes, results, sweeps (one line: what, span, how it ended) and of
the closed-form references (the body, its constants, the precision; a state's values and error)."""

from __future__ import annotations

from pathlib import Path

import mpmath
import pytest

import cayley_heyoka as ch
from cayley_heyoka import reference
from cayley_heyoka.workflows.study import load_study

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_scene_repr():
    text = repr(ch.load_scene(EXAMPLES / "free_body_quad.toml"))
    assert text.startswith("<Scene rotation ") and "quad" in text and "51 output times" in text
    assert "\n" not in text and len(text) < 250


def test_result_repr_says_span_steps_end_and_worst_drift():
    result = ch.run(ch.load_scene(EXAMPLES / "projectile.toml"))
    text = repr(result)
    assert text.startswith("<Result ") and "completed" in text and "worst drift energy" in text
    assert f"{result.counters['steps']} steps" in text
    assert "\n" not in text and len(text) < 300


def test_a_stopped_run_says_so():
    """A run that stops early raises, its result kept on the error."""
    data = ch.load_scene(EXAMPLES / "free_body.toml").to_dict()
    data["integrator"] = {"max_steps": 10}
    with pytest.raises(ch.IntegrationError) as err:
        ch.run(ch.Scene.from_dict(data))
    assert "stopped early" in repr(err.value.result)


def test_sweep_repr(tmp_path):
    study = load_study(EXAMPLES / "studies" / "free_body_grid.toml")
    sweep = ch.run_sweep(study, out=tmp_path / "s.h5")
    assert repr(ch.load_sweep(tmp_path / "s.h5")) == repr(sweep)
    text = repr(sweep)
    assert text.startswith("<SweepResult ") and "members over" in text and "completed" in text
    assert "\n" not in text and len(text) < 300


# -- the closed-form references ---------------------------------------------------------------
def _one_short_line(text: str, name: str) -> None:
    assert text.startswith(f"<{name} ") and text.endswith(">"), text
    assert "\n" not in text and len(text) <= 200, text


def _six(*values) -> str:
    """Values as the reprs print them: six significant digits, mpmath.nstr, comma-separated."""
    return ", ".join(mpmath.nstr(x, 6) for x in values)


def test_free_rigid_body_repr_says_the_body_its_constants_and_the_precision():
    body = reference.FreeRigidBody(("1", "2", "3"), ("0.25", "-0.15", "1.2"), dps=20)
    text = repr(body)
    _one_short_line(text, "FreeRigidBody")
    assert "asymmetric, A, B, C = 1.0, 2.0, 3.0:" in text and text.endswith(", dps 20>")
    assert f"h = {_six(body.h)}, k = {_six(body.k)}, period {_six(body.period)}" in text
    assert f"separatrix distance {_six(body.separatrix_distance)}" in text
    # A symmetric body has no separatrix, a steady rotation no period: neither is printed.
    symmetric = repr(reference.FreeRigidBody(("1", "1", "1.5"), ("1", "1", "1"), dps=20))
    steady = repr(reference.FreeRigidBody(("1", "2", "3"), ("0", "0", "1.5"), dps=20))
    assert "separatrix" not in symmetric and "period" in symmetric
    assert "period" not in steady and "separatrix" in steady
    # Beyond double's range the values print as they are, not as inf.
    huge = reference.FreeRigidBody(("1e300", "2e300", "3e300"), ("1e200", "0", "1e100"), dps=20)
    assert "h = 1.0e+700, k = 1.0e+500" in repr(huge)


def test_free_body_state_repr_says_time_rates_angles_and_worst_error():
    body = reference.FreeRigidBody(("1", "2", "3"), ("0.25", "-0.15", "1.2"), dps=20)
    state = body.at("7.5")
    text = repr(state)
    _one_short_line(text, "FreeBodyState")
    assert f"t = 7.5: p, q, r = {_six(state.p, state.q, state.r)}" in text
    assert f"φ = {_six(state.phi)}, Ψ = {_six(state.psi)}" in text
    assert text.endswith(f"error {mpmath.nstr(state.error, 2)}>")


def test_crossing_repr_says_axis_time_direction_and_error():
    body = reference.FreeRigidBody(("1", "2", "3"), ("0.25", "-0.15", "1.2"), dps=20)
    crossing = body.crossing_times("x1", "0", "5")[0]
    text = repr(crossing)
    _one_short_line(text, "Crossing")
    assert f"x1 at t = {_six(crossing.time)}, direction {crossing.direction:+d}" in text
    assert text.endswith(f"error {mpmath.nstr(crossing.error, 2)}>")


@pytest.fixture(scope="module")
def euler():
    return reference.Euler1758(
        ("1", "2", "3"), ("0.25", "-0.15", "1.2"), ("0.48", "0.6", "0.64"), dps=20
    )


@pytest.fixture(scope="module")
def cayley():
    return reference.Cayley1846(
        ("1", "2", "3"), ("0.25", "-0.15", "1.2"), ("0.1", "0.2", "-0.3"), dps=20
    )


def test_euler1758_repr_says_the_body_p_its_constants_and_the_precision(euler):
    text = repr(euler)
    _one_short_line(text, "Euler1758")
    assert "A, B, C = 1.0, 2.0, 3.0, P = (0.48, 0.6, 0.64):" in text
    assert text.endswith(", dps 20>")
    # Euler's F = 2T and G = |L|², from the body rates at t = 0.
    assert f"F = {_six(mpmath.mpf('4.4275'))}, G = {_six(mpmath.mpf('13.1125'))}" in text
    assert f"period {_six(euler.period)}" in text
    body = reference.FreeRigidBody(("1", "2", "3"), ("0.25", "-0.15", "1.2"), dps=20)
    assert f"separatrix distance {_six(body.separatrix_distance)}" in text
    symmetric = reference.Euler1758(("1", "1", "2"), ("0.3", "0.4", "1"), ("0.6", "0", "0.8"))
    assert "separatrix" not in repr(symmetric)


def test_euler_state_repr_says_time_rates_angles_and_worst_error(euler):
    state = euler.at("7.5")
    text = repr(state)
    _one_short_line(text, "EulerState")
    assert f"t = 7.5: p, q, r = {_six(state.p, state.q, state.r)}" in text
    assert f"U = {_six(state.U)}, φ + 𝔉 = {_six(state.phi_plus_F)}" in text
    assert text.endswith(f"error {mpmath.nstr(state.error, 2)}>")


def test_cayley1846_repr_says_the_body_its_constants_and_the_precision(cayley, euler):
    text = repr(cayley)
    _one_short_line(text, "Cayley1846")
    assert "A, B, C = 1.0, 2.0, 3.0:" in text and text.endswith(", dps 20>")
    assert f"h = {_six(cayley.h)}, k = {_six(cayley.k)}" in text
    assert f"a, b, c = {_six(cayley.a, cayley.b, cayley.c)}" in text
    assert f"period {_six(euler.period)}" in text  # the same body and rates


def test_cayley1846_state_and_quadratures_repr(cayley):
    state = cayley.at("7.5")
    text = repr(state)
    _one_short_line(text, "Cayley1846State")
    assert f"t = 7.5: p, q, r = {_six(state.p, state.q, state.r)}" in text
    assert f"υ = {_six(state.upsilon)}, 2 tan⁻¹(Ω/k) = {_six(state.angle)}" in text
    assert text.endswith(f"error {mpmath.nstr(state.error, 2)}>")
    quadratures = cayley.quadratures_in_upsilon("2")
    text = repr(quadratures)
    _one_short_line(text, "UpsilonQuadratures")
    assert f"t = {_six(quadratures.t)}, angle increment {_six(quadratures.angle_increment)}" in text
    assert f"{quadratures.turning_points} turning point" in text
    assert text.endswith(f"error {mpmath.nstr(quadratures.error, 2)}>")


def test_projectile_solution_repr_says_eta_varpi_s_and_worst_error():
    e, p = ("0.1", "-0.2", "1"), ("1", "0.5", "2")
    solution = reference.projectile_solution("9.81", "0.3", "0.5", e, p, "1.5", dps=20)
    text = repr(solution)
    _one_short_line(text, "ProjectileSolution")
    assert f"η = ({_six(*solution.eta)}), ϖ = ({_six(*solution.varpi)})" in text
    assert f"S = {_six(solution.S)}" in text
    assert text.endswith(f"error {mpmath.nstr(solution.error, 2)}>")


def test_principal_function_repr_says_s_its_derivatives_and_worst_error():
    eta, e = ("1.5", "0.5", "-7"), ("0.1", "-0.2", "1")
    pf = reference.principal_function(eta, e, "1.5", "9.81", "0.3", "0.5", dps=20)
    text = repr(pf)
    _one_short_line(text, "PrincipalFunction")
    assert f"S = {_six(pf.S)}, ∂S/∂η = ({_six(*pf.d_eta)}), ∂S/∂e = ({_six(*pf.d_e)})" in text
    assert f"∂S/∂t = {_six(pf.d_t)}" in text
    assert text.endswith(f"error {mpmath.nstr(pf.error, 2)}>")
