"""Monitors written in the scene (``[monitors.NAME]``): evaluated in the run's precision,
recorded with their drift, judged by the drift helpers and sweeps, refused when malformed."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.testing import drift_envelope
from cayley_heyoka.workflows.study import Study

# Kovalevskaya's top: A = B = 2C, the centre of mass in the equatorial plane, Mg·x_G = C = 1.
# Its fourth integral, with γ = the vertical in body axes (γ₁ = R31, γ₂ = R32 from the quaternion).
GAMMA1, GAMMA2 = "2*(qx*qz - qw*qy)", "2*(qy*qz + qw*qx)"
KOVALEVSKAYA = f"(p*p - q*q - ({GAMMA1}))**2 + (2*p*q - ({GAMMA2}))**2"
# The same with one sign changed: not an integral (it must drift by O(1)).
NOT_AN_INTEGRAL = f"(p*p - q*q + ({GAMMA1}))**2 + (2*p*q - ({GAMMA2}))**2"


def kovalevskaya(precision="double", stop=20, monitors=None, **extra) -> dict:
    scene = {
        "body": {"inertia": [2, 2, 1]},
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
        "forces": {"heavy_top": {"weight": 1, "center_of_mass": [1, 0, 0], "up": [0, 0, 1]}},
        "attitude": {"formulation": "quaternion"},
        "integrator": {"precision": precision},
        "monitors": monitors
        if monitors is not None
        else {"K": {"expression": KOVALEVSKAYA}, "wrong": {"expression": NOT_AN_INTEGRAL}},
        "output": {"times": {"start": 0, "stop": stop, "count": 21}},
    }
    scene.update(extra)
    return scene


@pytest.mark.parametrize(
    ("precision", "eps"),
    [("double", 2.0**-52), ("quad", 2.0**-112), ({"bits": 160}, 2.0**-159)],
    ids=["double", "quad", "mpfr160"],
)
def test_kovalevskaya_integral_is_conserved_in_every_precision(precision, eps):
    """K stays to round-off (a few hundred ε over the run's steps); the same expression with
    one sign flipped is not an integral and drifts by O(1): the monitor is what was written."""
    result = ch.run(ch.Scene.from_dict(kovalevskaya(precision)))
    assert "K" in result.conserved and "wrong" in result.conserved
    steps = result.counters["steps"]
    k = np.array([float(abs(x)) for x in result.drift("K")])
    assert np.max(k) < 10 * eps * np.sqrt(steps) * 30, np.max(k)
    wrong = np.array([float(abs(x)) for x in result.drift("wrong")])
    assert np.max(wrong) > 0.1
    # The run's own numbers, not doubles.
    assert type(result.monitors["K"][0]) is type(result["p"][0])


def test_a_hand_written_energy_equals_the_family_one_in_quad():
    """Literals and named parameters are the run's: ½(Ap² + Bq² + Cr²) written with 0.5 and
    with /2 gives the family's energy in quad to an ulp or two, not to a double's 1e-16."""
    scene = kovalevskaya(
        "quad",
        monitors={
            "T_half": {"expression": "0.5*(A*p**2 + B*q**2 + C*r**2)", "conserved": False},
            "T_div": {"expression": "(A*p**2 + B*q**2 + C*r**2)/2", "conserved": False},
        },
        forces={},
    )
    del scene["forces"]
    result = ch.run(ch.Scene.from_dict(scene))
    energy = result.monitors["energy"]
    for name in ("T_half", "T_div"):
        diff = max(
            float(abs(a - b) / abs(b)) for a, b in zip(result.monitors[name], energy, strict=True)
        )
        assert diff < 1e-32, (name, diff)
    assert "T_half" not in result.conserved


def test_orbit_scenes_take_user_monitors():
    """Another family offers them too: the orbit's energy by hand from x, v and mu."""
    orbit = {
        "orbit": {
            "mu": "1",
            "elements": {
                "a": 1,
                "e": "0.3",
                "inclination": "0.2",
                "node": 0,
                "argument_of_pericentre": 0,
                "mean_anomaly": 0,
            },
        },
        "monitors": {
            "E": {"expression": "(vx**2 + vy**2 + vz**2)/2 - mu/sqrt(x**2 + y**2 + z**2)"}
        },
        "output": {"times": {"start": 0, "stop": 10, "count": 11}},
    }
    result = ch.run(ch.Scene.from_dict(orbit))
    assert np.allclose(result.monitors["E"], result.monitors["energy"], rtol=0, atol=1e-15)
    assert "E" in result.conserved


def test_sweeps_record_the_drift_of_a_user_monitor():
    study = Study.from_dict(
        {
            "scene": kovalevskaya(stop=5),
            "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": [0.3, 0.31]}},
        }
    )
    sweep = ch.run_sweep(study)
    assert "K" in sweep.drift and "wrong" in sweep.drift
    assert np.all(sweep.final_drift("K") < 1e-13)
    assert np.all(sweep.final_drift("wrong") > 1e-3)


def test_drift_envelopes_include_user_monitors(tmp_path):
    result = ch.run(ch.Scene.from_dict(kovalevskaya(monitors={"K": {"expression": KOVALEVSKAYA}})))
    envelope = drift_envelope(result, 4)
    assert "K" in envelope.peaks
    path = tmp_path / "kov.h5"
    result.save(path)
    loaded = ch.load_result(path)
    assert np.array_equal(loaded.monitors["K"], result.monitors["K"])
    assert "K" in loaded.conserved


def test_output_monitors_may_list_them_and_must_not_forget_them():
    scene = kovalevskaya(monitors={"K": {"expression": KOVALEVSKAYA}})
    scene["output"]["monitors"] = ["energy", "K"]
    result = ch.run(ch.Scene.from_dict(scene))
    assert list(result.monitors) == ["energy", "K"]
    scene["output"]["monitors"] = ["energy"]
    with pytest.raises(ch.SceneError, match=r"monitors\.K.*not listed in output.monitors"):
        ch.run(ch.Scene.from_dict(scene))


@pytest.mark.parametrize(
    ("monitors", "field", "message"),
    [
        ([], "monitors", "table of"),
        ({"K": "p*p"}, "monitors.K", "must be a table"),
        ({"K": {}}, "monitors.K.expression", "is required"),
        ({"K": {"expression": ""}}, "monitors.K.expression", "non-empty"),
        ({"K": {"expression": 3}}, "monitors.K.expression", "non-empty"),
        ({"K": {"expression": "p", "conserved": "yes"}}, "monitors.K.conserved", "true or false"),
        ({"K": {"expression": "p", "conservd": True}}, "monitors.K.conservd", "conserved"),
        ({"2K": {"expression": "p"}}, "monitors.2K", "identifier"),
        ({"_K": {"expression": "p"}}, "monitors._K", "must not start with _"),
        ({"energy": {"expression": "p"}}, "monitors.energy", "already the built-in monitor"),
        ({"p": {"expression": "q"}}, "monitors.p", "already the built-in output p"),
        ({"K": {"expression": "p + omega"}}, "monitors.K.expression", "unknown name 'omega'"),
        ({"K": {"expression": "__import__('os')"}}, "monitors.K.expression", "unknown function"),
        ({"K": {"expression": "p^2"}}, "monitors.K.expression", "a power is written **"),
        ({"K": {"expression": "p % 2"}}, "monitors.K.expression", "Mod is not allowed; use"),
        ({"K": {"expression": "sin(" * 200 + "p" + ")" * 200}}, "monitors.K.expression", "deep"),
        ({f"K{i}": {"expression": "p"} for i in range(101)}, "monitors", "at most 100"),
    ],
)
def test_malformed_monitors_are_refused_by_name(monitors, field, message):
    with pytest.raises(ch.SceneError) as info:
        ch.run(ch.Scene.from_dict(kovalevskaya(monitors=monitors)))
    assert info.value.field == field
    assert message in str(info.value)


def test_info_describes_a_user_monitor(tmp_path):
    path = tmp_path / "kov.h5"
    ch.run(ch.Scene.from_dict(kovalevskaya(monitors={"K": {"expression": KOVALEVSKAYA}}))).save(
        path
    )
    out = subprocess.run(
        [sys.executable, "-m", "cayley_heyoka", "info", "--variables", str(path)],
        capture_output=True,
        text=True,
        check=True,
    ).stdout
    assert "user monitor (conserved): (p*p - q*q" in out


def test_hamiltonian_scenes_take_user_monitors():
    """Hamilton's projectile (1835, §5–6): H is symmetric about the vertical η₃, so the
    vertical component of η × ϖ is an integral; a horizontal one is not."""
    import tomllib
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "examples" / "projectile.toml"
    scene = tomllib.loads(path.read_text())
    scene["monitors"] = {
        "L3": {"expression": "eta1*varpi2 - eta2*varpi1"},
        "L2": {"expression": "eta3*varpi1 - eta1*varpi3"},
    }
    result = ch.run(ch.Scene.from_dict(scene))
    assert np.max(np.abs(result.drift("L3"))) < 1e-12
    assert np.max(np.abs(result.drift("L2"))) > 1e-3


def test_monitors_whose_names_are_free_keep_every_column(tmp_path):
    """A free name stays free: K and k are two monitors (every layout is case-sensitive), and
    the family's vector momentum_space keeps its three columns beside them."""
    scene = kovalevskaya(stop=1, monitors={"K": {"expression": "p*p"}, "k": {"expression": "q*q"}})
    result = ch.run(ch.Scene.from_dict(scene))
    frame = result.to_pandas()
    assert {"K", "k", "momentum_space_x", "momentum_space_y", "momentum_space_z"} <= set(frame)
    result.save(tmp_path / "r.h5")
    back = ch.load_result(tmp_path / "r.h5")
    assert np.array_equal(back["K"], result["K"]) and np.array_equal(back["k"], result["k"])
    assert not np.array_equal(back["K"], back["k"])
