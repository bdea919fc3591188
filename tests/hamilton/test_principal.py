"""∂S/∂η = ϖ, ∂S/∂e = −p, ∂S/∂t = −H on runs, through heyoka's variational equations."""

from __future__ import annotations

import math

import numpy as np
import pytest

import cayley_heyoka.hamilton.model as model
from cayley_heyoka import Scene
from cayley_heyoka.core import structures
from cayley_heyoka.hamilton.principal import check_principal_function

EPS = {"double": 2.0**-52, "quad": 2.0**-112}


def projectile(precision: str, stop: str = "12", count: int = 7) -> dict:
    return {
        "hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3", "nu": "0.45"},
        "initial": {"eta": ["0.2", "-0.4", "1.5"], "varpi": ["0.7", "0.3", "2.1"]},
        "integrator": {"precision": precision},
        "output": {"times": {"start": "0", "stop": stop, "count": count}},
    }


def assert_within(check, eps: float, scale: float) -> None:
    """Each residual is a few roundings of quantities of size ``scale``, amplified by the
    chain rule's condition (‖(∂η/∂p)⁻¹‖ times the Jacobian's size): 64 ε · scale · cond."""
    bound = 64 * eps * scale * check.condition[1:]
    for name in ("eta", "e", "time"):
        residual = getattr(check, name)[1:]
        assert np.all(residual < bound), (name, residual, bound)


@pytest.mark.parametrize("precision", ["double", "quad"])
def test_projectile_principal_function_identities(precision):
    check = check_principal_function(Scene.from_dict(projectile(precision)))
    # At t₀ S(η, e, t) does not exist (∂η/∂p = 0): reported, not judged.
    assert math.isinf(check.condition[0]) and np.isnan(check.eta[0])
    assert_within(check, EPS[precision], scale=4.0)  # |ϖ|, |p|, |H| ≤ 4 here


def test_a_nonlinear_hamiltonian():
    """The pendulum H = ϖ²/2 − cos η: no closed form is used, only the identities.

    Near t = 8 ∂η/∂p passes close to 0 (a 1×1 matrix: its condition number stays 1); the
    check's condition sees it, and the bound with it."""
    d = {
        "hamiltonian": {"H": "varpi1**2/2 - cos(eta1)"},
        "initial": {"eta": ["0.3"], "varpi": ["1.2"]},
        "output": {"times": {"start": "0", "stop": "24", "count": 25}},
    }
    check = check_principal_function(Scene.from_dict(d))
    assert_within(check, EPS["double"], scale=2.0)


def test_conjugate_point_is_reported_by_its_condition():
    """sin μt = 0 at t = π/μ: the boundary-value problem has no unique solution there."""
    t_star = math.pi / 0.3
    d = projectile("double")
    d["output"]["times"] = ["0", "1", repr(t_star)]
    check = check_principal_function(Scene.from_dict(d))
    assert check.condition[1] < 10 and check.condition[2] > 1e12


def test_a_wrong_principal_function_is_caught(monkeypatch, request):
    """Negative control: integrate T + U + 1e-6 instead of T + U; ∂S/∂t then misses by 1e-6."""
    # The patch changes what the build compiles for the same scene: neither a structure built
    # before it nor the one built with it may serve another scene.
    structures.clear()
    request.addfinalizer(structures.clear)
    original = model.principal_rate
    monkeypatch.setattr(model, "principal_rate", lambda H, s, v: original(H, s, v) + 1e-6)
    check = check_principal_function(Scene.from_dict(projectile("double")))
    assert np.all(np.abs(check.time[1:] - 1e-6) < 1e-12)


def test_principal_function_of_relative_motion():
    """Check N7: δS = Σ m(x′·δξ − a′·δa) for two planets about a predominant
    mass, in (F2.)'s canonical heliocentric coordinates (whose outputs use parameters the
    equations do not)."""
    elements = {"e": "0.05", "inclination": "0.05", "node": "0.3"}
    elements |= {"argument_of_pericentre": "1.1", "mean_anomaly": "0.4"}
    bodies = [
        {"mass": "0.001", "elements": {"a": "1", **elements}},
        {"mass": "0.0003", "elements": {"a": "1.8", **elements, "e": "0.08"}},
    ]
    d = {
        "hamiltonian": {"model": "predominant_mass", "G": "1", "central_mass": "1"},
        "output": {"times": {"start": "0", "stop": "6", "count": 7}},
    }
    d["hamiltonian"]["bodies"] = bodies
    check = check_principal_function(Scene.from_dict(d))
    assert np.all(np.isfinite(check.condition[1:]))
    assert_within(check, EPS["double"], scale=check.scale)


def test_variational_equations_that_end_early_are_refused_not_read_as_rows():
    """A radial fall H = ϖ²/2 − 1/η reaches η = 0 near t = 1.11: the variational run ends
    there, and the check says so instead of reading the grid's unreached rows (NaN)."""
    d = {
        "hamiltonian": {"H": "varpi1**2/2 - 1/eta1"},
        "initial": {"eta": ["1"], "varpi": ["0"]},
        "output": {"times": {"start": "0", "stop": "3", "count": 4}},
    }
    with pytest.raises(ValueError, match="variational equations of the principal function ended"):
        check_principal_function(Scene.from_dict(d))
