"""`cayley-heyoka check` on every bundled example: each has a check, and it passes.

Parametrised over examples/*.toml, so that a new example without a consistency check fails
here. Each check is also shown to fail when the run it checks is wrong by far less than the
run's own digits (a perturbed output), so that passing means something.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import cayley_heyoka.core.engine as engine
from cayley_heyoka import Scene, load_scene
from cayley_heyoka.cli import main
from cayley_heyoka.core.consistency import CheckOptions
from cayley_heyoka.workflows.checks import check_scene

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCENES = sorted(p.name for p in EXAMPLES.glob("*.toml"))


def test_the_examples_are_found():
    assert len(SCENES) >= 8


@pytest.mark.parametrize("name", SCENES)
def test_every_example_has_a_check_and_passes_it(name, capsys):
    assert main(["check", str(EXAMPLES / name)]) == 0
    text = capsys.readouterr().out
    assert "passed" in text and "FAILED" not in text


def _formulation(scene: Scene) -> tuple:
    data = scene.to_dict()
    return tuple(
        data.get(table, {}).get(key)
        for table, key in (
            ("attitude", "formulation"),
            ("orbit", "formulation"),
            ("hamiltonian", "formulation"),
            ("integrator", "precision"),
        )
    )


def _perturbing_own_runs(monkeypatch, scene: Scene, variable: str, size: float) -> None:
    """Make every engine.run of the check in the scene's own formulation and precision (not
    its twin's) return ``variable`` off by ``size`` (relative to max(1, |value|)) at the last
    output time."""
    original = engine.run
    own = _formulation(scene)

    def run(other, *args, **kwargs):
        result = original(other, *args, **kwargs)
        if _formulation(other) == own:
            values = result.variables[variable]
            values[-1] = values[-1] + (abs(values[-1]) + 1) * size
        return result

    monkeypatch.setattr(engine, "run", run)


@pytest.mark.parametrize(
    ("name", "variable", "size"),
    [
        ("free_body_quad.toml", "qx", 1e-28),
        ("heavy_top.toml", "p", 1e-3),
        ("top_weakly_forced.toml", "r", 1e-9),
        ("orbit_moving_plane.toml", "x", 1e-9),
        ("projectile.toml", "eta2", 1e-12),
        ("planets.toml", "x2", 1e-7),
    ],
)
def test_a_check_fails_on_a_wrong_run(monkeypatch, name, variable, size):
    """Each error is far below what any plot shows, and above the row's bound."""
    scene = load_scene(EXAMPLES / name)
    _perturbing_own_runs(monkeypatch, scene, variable, size)
    report = check_scene(scene)
    assert not report.passed
    failed = [r for r in report.rows if not r.passed]
    assert failed and all(math.isfinite(r.error) for r in failed)


def test_rows_have_bounds_fixed_before_the_run():
    """Bounds are positive and finite, errors are measured (finite) and the series cover the
    output grid."""
    scene = load_scene(EXAMPLES / "free_body.toml")
    report = check_scene(scene, CheckOptions({"times": "101"}))
    assert report.passed and len(report.rows) == 4
    for row in report.rows:
        # A ratio to the bound at each time (λ near a half-turn) has bound 1; the rest are
        # absolute: 10 ε √N × a sensitivity of 20–40 over these 100 time units.
        limit = 1.0 if row.quantity.endswith("/ bound at t") else 1e-11
        assert 0 < row.bound <= limit and math.isfinite(row.error) and row.error <= row.bound
    assert report.series["t"].shape == (101,)
    assert report.series["t"][-1] == 100.0


def _short(name: str, stop: str, count: int) -> dict:
    data = load_scene(EXAMPLES / name).to_dict()
    data["output"]["times"] = {"start": "0.0", "stop": stop, "count": count}
    return data


@pytest.mark.parametrize("twin", ["quaternion", "encke", "precision"])
def test_an_orbit_checks_against_the_twin_asked_for(twin):
    scene = Scene.from_dict(_short("orbit_j2_third_body.toml", "20.0", 21))
    report = check_scene(scene, CheckOptions({"twin": twin}))
    assert report.passed
    label = {"precision": "quad"}.get(twin, twin)
    assert all(label in row.quantity for row in report.rows)


def test_a_cartesian_orbit_checks_against_a_higher_precision():
    data = _short("orbit_j2_third_body.toml", "20.0", 21)
    data["orbit"]["formulation"] = "cartesian"
    data["orbit"].pop("sigma0")
    report = check_scene(Scene.from_dict(data))
    assert report.passed and "quad" in report.title
    with pytest.raises(ValueError, match="already 'cartesian'"):
        check_scene(Scene.from_dict(data), CheckOptions({"twin": "cartesian"}))


def test_a_forced_body_can_be_asked_for_its_twin():
    data = load_scene(EXAMPLES / "top_weakly_forced.toml").to_dict()
    data["output"]["times"] = {"start": "0.0", "stop": "10.0", "count": 11}
    report = check_scene(Scene.from_dict(data), CheckOptions({"method": "twin"}))
    assert report.passed and "quaternion twin" in report.title
    assert np.all(np.isfinite(report.series["error_p"]))


def test_a_force_function_of_time_is_checked_by_the_twin():
    """Cayley's element check takes W of the state alone; left to choose, `check` takes the
    twin and says why; asked for the element check, it refuses, naming forces."""
    data = load_scene(EXAMPLES / "top_weakly_forced.toml").to_dict()
    data["forces"] = {"potential": {"V": "0.01*cos(t)*R33"}}
    data["output"]["times"] = {"start": "0.0", "stop": "10.0", "count": 11}
    scene = Scene.from_dict(data)
    report = check_scene(scene)
    assert (
        report.passed
        and "quaternion twin" in report.title
        and "depends explicitly on t" in (report.title)
    )
    with pytest.raises(ValueError, match="forces"):
        check_scene(scene, CheckOptions({"method": "elements"}))


def test_a_check_needs_a_time_span():
    data = load_scene(EXAMPLES / "projectile.toml").to_dict()
    data["output"]["times"] = ["0.0"]
    with pytest.raises(ValueError, match="output.times: a check needs a time span"):
        check_scene(Scene.from_dict(data))
