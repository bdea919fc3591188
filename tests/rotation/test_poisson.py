"""The Euler–Poisson reduction (``formulation = "poisson"``): the rates and γ = Rᵀu alone, for
forces that see one fixed direction; against the full attitude, its integrals, its refusals."""

from __future__ import annotations

import numpy as np
import pytest

import cayley_heyoka as ch


def top(formulation, inertia=(1.0, 1.6, 2.3), com=(0.1, -0.05, 0.3), up=(0, 0, 1), **extra):
    scene = {
        "body": {"inertia": list(inertia)},
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
        "forces": {"heavy_top": {"weight": 1.0, "center_of_mass": list(com), "up": list(up)}},
        "attitude": {"formulation": formulation},
        "output": {"times": {"start": 0, "stop": 10, "count": 21}},
    }
    scene.update(extra)
    return scene


def gamma_of(result, up):
    """γ = Rᵀu from a full-attitude run's quaternion."""
    w, x, y, z = (np.asarray(result[n], dtype=float) for n in ("qw", "qx", "qy", "qz"))
    R = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    u = np.asarray(up, dtype=float) / np.linalg.norm(up)
    return np.einsum("ijn,i->jn", R, u)


@pytest.mark.parametrize("up", [(0, 0, 1), (0.48, -0.64, 0.6)])
def test_reduced_top_follows_the_full_attitude(up):
    """The heavy top (examples/heavy_top.toml's body) in the reduced model and with the
    quaternion: the same rates and the same γ to round-off over t = 10 (the top is chaotic,
    so the two drift apart later by the motion's sensitivity, not by a model difference)."""
    reduced = ch.run(ch.Scene.from_dict(top("poisson", up=up)))
    full = ch.run(ch.Scene.from_dict(top("quaternion", up=up)))
    for n in "pqr":
        assert np.max(np.abs(np.asarray(reduced[n]) - np.asarray(full[n]))) < 1e-12, n
    gamma = np.array([reduced[f"gamma{j}"] for j in (1, 2, 3)], dtype=float)
    assert np.max(np.abs(gamma - gamma_of(full, up))) < 1e-12
    assert np.max(np.abs(reduced.monitors["energy"] - full.monitors["energy"])) < 1e-14
    assert reduced.conserved == ("energy", "momentum_vertical", "direction_norm")
    for name in reduced.conserved:
        assert np.max(np.abs(reduced.drift(name))) < 1e-14, name


@pytest.mark.parametrize("precision", ["quad", {"bits": 160}])
def test_kovalevskaya_integral_in_the_reduced_model(precision):
    """Kovalevskaya's top (A = B = 2C, Mg·x_G = C = 1) by Poisson's equations in extended
    precision: its fourth integral, written in γ as a user monitor, is conserved to round-off."""
    k = "(p*p - q*q - gamma1)**2 + (2*p*q - gamma2)**2"
    scene = top(
        "poisson",
        inertia=(2, 2, 1),
        com=(1, 0, 0),
        monitors={"K": {"expression": k}},
        integrator={"precision": precision},
    )
    scene["output"]["times"] = {"start": 0, "stop": 5, "count": 6}
    result = ch.run(ch.Scene.from_dict(scene))
    eps = 2.0**-112 if precision == "quad" else 2.0**-159
    for name in ("K", "energy", "momentum_vertical", "direction_norm"):
        drift = max(abs(float(x)) for x in result.drift(name))
        assert drift < 1e4 * eps, (name, drift)


def test_lagrange_top_spins_at_a_constant_rate():
    """A = B and the centre of mass on the axis: N₃ = 0 and (A − B) = 0, so r stays exactly."""
    result = ch.run(ch.Scene.from_dict(top("poisson", inertia=(1, 1, 0.5), com=(0, 0, 0.4))))
    r = np.asarray(result["r"])
    assert np.all(r == r[0])


def test_gravity_gradient_is_reduced_too():
    forces = {"gravity_gradient": {"gm": 1.0, "distance": 2.0, "direction": [0.6, 0, 0.8]}}
    reduced = ch.run(ch.Scene.from_dict(top("poisson", forces=forces)))
    full = ch.run(ch.Scene.from_dict(top("quaternion", forces=forces)))
    gamma = np.array([reduced[f"gamma{j}"] for j in (1, 2, 3)], dtype=float)
    assert np.max(np.abs(gamma - gamma_of(full, (0.6, 0, 0.8)))) < 1e-12


def test_a_potential_of_the_vertical_is_reduced():
    """V of R31, R32, R33 (u = space z): the same motion as the heavy top it spells out."""
    forces = {"potential": {"V": "-(0.1 * R31 - 0.05 * R32 + 0.3 * R33)"}}
    reduced = ch.run(ch.Scene.from_dict(top("poisson", forces=forces)))
    heavy = ch.run(ch.Scene.from_dict(top("poisson")))
    for n in ("p", "q", "r", "gamma1", "gamma2", "gamma3"):
        assert np.max(np.abs(np.asarray(reduced[n]) - np.asarray(heavy[n]))) < 1e-13, n


@pytest.mark.parametrize(
    ("forces", "message"),
    [
        ({}, "no force"),
        ({"potential": {"V": "R11 + R33"}}, "R31, R32, R33 alone"),
        ({"potential": {"V": "lambda * R33"}}, "R31, R32, R33 alone"),
        (
            {
                "heavy_top": {"weight": 1, "center_of_mass": [0, 0, 1], "up": [0, 0, 1]},
                "gravity_gradient": {"gm": 1, "distance": 2, "direction": [1, 0, 0]},
            },
            "one fixed direction",
        ),
        (
            {
                "heavy_top": {"weight": 1, "center_of_mass": [0, 0, 1], "up": [1, 0, 0]},
                "potential": {"V": "R33"},
            },
            "one fixed direction",
        ),
    ],
)
def test_scenes_that_cannot_be_reduced_are_refused(forces, message):
    scene = top("poisson", forces=forces)
    if not forces:
        del scene["forces"]
    with pytest.raises(ch.SceneError) as info:
        ch.run(ch.Scene.from_dict(scene))
    assert info.value.field == "attitude.formulation"
    assert message in str(info.value)


def test_check_compares_the_reduction_with_its_quaternion_twin():
    """`cayley-heyoka check` of a reduced scene: the rates and γ against the quaternion twin's
    Rᵀu, within the round-off law; Cayley's element check, which needs the attitude, is
    refused by name."""
    from cayley_heyoka.core.consistency import CheckOptions
    from cayley_heyoka.workflows.checks import check_scene

    scene = ch.Scene.from_dict(top("poisson", up=(0.48, -0.64, 0.6)))
    report = check_scene(scene, CheckOptions())
    assert report.passed and len(report.rows) == 2
    assert "γ" in report.rows[1].quantity and 0 < report.rows[1].error < report.rows[1].bound
    with pytest.raises(ValueError, match="element check needs the attitude"):
        check_scene(scene, CheckOptions({"method": "elements"}))
