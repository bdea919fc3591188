"""The command line: run a bundled scene, write and summarise a result file, fail clearly."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from cayley_heyoka import Result
from cayley_heyoka.cli import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.mark.parametrize("scene", sorted(p.name for p in EXAMPLES.glob("*.toml")))
def test_bundled_scenes_run(tmp_path, capsys, scene):
    out = tmp_path / "r.h5"
    assert main(["run", str(EXAMPLES / scene), "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "completed" in text and "steps" in text and "energy" in text
    result = Result.load(out)
    assert result.success and len(result.t) > 1
    assert main(["info", str(out)]) == 0


def test_bad_scene_is_reported_with_its_field(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        "[body]\ninertia = [1, 1, 3]\n[initial]\nrates = [1, 0, 0]\n[output]\ntimes = [0, 1]\n"
    )
    assert main(["run", str(bad), "--no-progress"]) == 2
    assert "body.inertia: violates the triangle inequality" in capsys.readouterr().err


def test_failed_run_saves_partial_results(tmp_path, capsys):
    scene = tmp_path / "boom.toml"
    scene.write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [0.1, 0.2, 1]\n"
        '[forces.potential]\nV = "exp(100 * (t - 6)) * lambda"\n'
        "[output]\ntimes = { start = 0, stop = 20, count = 21 }\n"
    )
    out = tmp_path / "boom.h5"
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 1
    assert "non-finite" in capsys.readouterr().err
    partial = Result.load(out)
    assert not partial.success and 6 <= len(partial.t) < 21


def test_orbit_run_through_the_reference_plane_saves_nan_angles(tmp_path, capsys):
    """A Cayley orbit whose reference plane tilts onto it (Φ = 0.5 − 0.05 t) hands over to a
    tilted frame at sin Φ = 5·10⁻⁴ (t ≈ 9.99) and back at 2·10⁻³: exit 0, every row saved, Θ
    and Σ NaN on the tilted row (t = 10) and read back as such."""
    scene = tmp_path / "equatorial.toml"
    scene.write_text(
        '[orbit]\nmu = 1\nformulation = "cayley"\n'
        "elements = { a = 1, e = 0.1, inclination = 0.5, node = 0, argument_of_pericentre = 0.3,"
        " mean_anomaly = 0 }\n"
        "[reference_plane]\nphi_rate = 0.05\n"
        "[integrator]\ncompact_mode = true\n"
        '[output]\ntimes = { start = 0, stop = 20, count = 41 }\nevents = ["equatorial"]\n'
    )
    out = tmp_path / "equatorial.h5"
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 0
    captured = capsys.readouterr()
    assert "equatorial_handovers 2" in captured.out and "approach: 1, recede: 1" in captured.out
    result = Result.load(out)
    assert result.success and len(result.t) == 41
    assert result.counters["equatorial_handovers"] == 2
    theta = np.asarray(result["Theta"], dtype=float)
    assert np.isnan(theta[20]) and np.all(np.isfinite(np.delete(theta, 20)))
    assert np.all(np.isfinite(np.asarray(result["Phi"], dtype=float)))


def test_scene_error_found_when_building_exits_2(tmp_path, capsys):
    """An unknown name in a force function is found when the model is built, not at load."""
    bad = tmp_path / "bad.toml"
    bad.write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [0.1, 0.2, 1]\n"
        '[forces.potential]\nV = "nonsense * lambda"\n[output]\ntimes = [0, 1]\n'
    )
    assert main(["run", str(bad), "--no-progress"]) == 2
    assert "forces.potential.V" in capsys.readouterr().err


@pytest.mark.parametrize("formulation", ["quaternion", "cartesian"])
def test_orbit_example_in_the_other_formulations(tmp_path, capsys, formulation):
    """The bundled orbit scene with its formulation switched runs from the command line, and
    reports the same final position as the Cayley form (to the round-off of ~20 orbits)."""
    text = (EXAMPLES / "orbit_j2_third_body.toml").read_text()
    text = text.replace('formulation = "cayley"', f'formulation = "{formulation}"')
    if formulation == "cartesian":
        text = text.replace("sigma0 = 0.0 ", "# no gauge: ")
    scene = tmp_path / "orbit.toml"
    scene.write_text(text)
    out, ref = tmp_path / "r.h5", tmp_path / "ref.h5"
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 0
    assert "completed" in capsys.readouterr().out
    example = EXAMPLES / "orbit_j2_third_body.toml"
    assert main(["run", str(example), "--out", str(ref), "--no-progress"]) == 0
    a, b = Result.load(out), Result.load(ref)
    for k in ("x", "y", "z"):
        assert abs(a[k][-1] - b[k][-1]) < 1e-11


PENDULUM = """
[hamiltonian]
H = "varpi1**2/2 - cos(eta1)"
[initial]
eta = [0.3]
varpi = [1.2]
[output]
times = { start = 0.0, stop = 6.0, count = 7 }
"""


def test_check_passes_and_writes_its_rows(tmp_path, capsys):
    import h5py

    scene = tmp_path / "pendulum.toml"
    scene.write_text(PENDULUM)
    out = tmp_path / "check.h5"
    assert main(["check", str(scene), "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "∂S/∂t + H" in text and "passed" in text
    with h5py.File(out) as f:
        assert f.attrs["passed"]
        assert len(f["rows"]) == 3 and f["series/t"].shape == (7,)


def test_check_fails_with_exit_1_when_S_is_wrong(tmp_path, capsys, monkeypatch, request):
    import cayley_heyoka.hamilton.model as model
    from cayley_heyoka.core import structures

    # The patch changes what the build compiles for the same scene: neither a structure built
    # before it nor the one built with it may serve another scene.
    structures.clear()
    request.addfinalizer(structures.clear)
    original = model.principal_rate
    monkeypatch.setattr(model, "principal_rate", lambda H, s, v: original(H, s, v) + 1e-6)
    scene = tmp_path / "pendulum.toml"
    scene.write_text(PENDULUM)
    assert main(["check", str(scene)]) == 1
    assert "FAILED" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("setting", "message"),
    [
        ("upsilon0", "--set: expected KEY=VALUE"),
        ("twin=cayley", "--set twin: unknown option"),
        ("times=1", "--set times: must be an integer in 2 … 1000000"),
    ],
)
def test_check_refuses_a_bad_option_naming_it(capsys, setting, message):
    assert main(["check", str(EXAMPLES / "free_body.toml"), "--set", setting]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("scene", ["top_weakly_forced.toml", "planets.toml"])
def test_check_of_the_bundled_scenes_that_have_one(capsys, scene):
    """Cayley's 1846 element equations along the weakly forced top; Hamilton's elements
    against the canonical equations for the two planets (1000 orbits)."""
    assert main(["check", str(EXAMPLES / scene)]) == 0
    assert "passed" in capsys.readouterr().out


def test_check_that_cannot_be_carried_through_says_why(capsys):
    """The bundled heavy top is strongly forced: the free motion through its state stops
    passing υ₀ at t ≈ 15, and Cayley's e, δ lose their passage. Asked for the element check,
    `check` says so; left to choose, it checks the twin instead (tests/test_checks_examples.py)."""
    path = str(EXAMPLES / "heavy_top.toml")
    assert main(["check", path, "--set", "method=elements"]) == 2
    assert "upsilon0" in capsys.readouterr().err


def test_progress_bar_shows_simulated_time_and_percentage(capsys):
    """planets.toml stops at 2000π: the bar prints t to six digits, not every digit of the
    float, and the percentage."""
    assert main(["run", str(EXAMPLES / "planets.toml"), "--progress"]) == 0
    err = capsys.readouterr().err
    assert "t = 6283.19 of 6283.19  100%" in err
    assert "6283.185307" not in err
