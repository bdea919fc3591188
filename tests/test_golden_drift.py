"""The bundled scenes' drift against golden envelopes: a change that worsens it fails here.

Each scene with conserved monitors is run and its drift envelope compared with
``tests/data/golden/<scene>.h5`` by the ``drift_golden`` fixture (cayley_heyoka's pytest plugin).
After an intended change, rewrite the files with::

    python -m pytest tests/test_golden_drift.py --update-golden
"""

from __future__ import annotations

from pathlib import Path

import mpmath
import pytest

import cayley_heyoka as ch
from cayley_heyoka.testing import DriftEnvelope, assert_drift_within

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "examples"
GOLDEN = HERE / "data" / "golden"
SCENES = sorted(p.stem for p in EXAMPLES.glob("*.toml"))


def _run(name: str, **integrator) -> ch.Result:
    scene = ch.load_scene(EXAMPLES / f"{name}.toml").to_dict()
    scene.setdefault("integrator", {}).update(integrator)
    return ch.run(ch.Scene.from_dict(scene))


@pytest.mark.parametrize("name", SCENES)
def test_bundled_scene_drift_within_golden(name, drift_golden):
    result = _run(name)
    if not result.conserved:
        pytest.skip(f"{name}: no conserved monitor")
    drift_golden(result, path=GOLDEN / f"{name}.h5")


def test_looser_tolerance_fails_the_golden_envelope():
    """The default allowance catches a real worsening: tolerance 1e-11 instead of ε."""
    with pytest.raises(AssertionError) as failure:
        assert_drift_within(_run("heavy_top", tolerance="1e-11"), GOLDEN / "heavy_top.h5")
    message = str(failure.value)
    assert f"drift exceeds the golden envelope ({GOLDEN / 'heavy_top.h5'}) for 2 of 2" in message
    assert "conserved monitors (double, ε = 2.220e-16; allowed 8 × golden + 8 ε):" in message
    assert "windows exceed; worst t in " in message and ", ratio " in message


def test_looser_tolerance_fails_the_quad_golden_envelope():
    with pytest.raises(
        AssertionError, match=r"for 3 of 3 conserved monitors \(quad, ε = 1\.926e-34;"
    ):
        assert_drift_within(_run("free_body_quad", tolerance="1e-30"), GOLDEN / "free_body_quad.h5")


def test_another_round_off_realisation_passes():
    """Initial rates moved by a few ulps (round-off as another machine makes it) still pass."""
    scene = ch.load_scene(EXAMPLES / "heavy_top.toml").to_dict()
    rates = scene["initial"]["rates"]
    with mpmath.workdps(30):
        rates[0] = mpmath.nstr(mpmath.mpf(rates[0]) * (1 + 5 * mpmath.mpf(2) ** -52), 25)
    assert rates[0] != "0.3"
    assert_drift_within(ch.run(ch.Scene.from_dict(scene)), GOLDEN / "heavy_top.h5")


def test_golden_files_are_small_and_describe_their_scene():
    files = sorted(GOLDEN.glob("*.h5"))
    assert files, f"no golden files in {GOLDEN}"
    for path in files:
        assert path.stem in SCENES, f"{path.name}: no scene examples/{path.stem}.toml"
        assert path.stat().st_size < 16_000, f"{path.name}: {path.stat().st_size} bytes"
        envelope = DriftEnvelope.load(path)
        scene = ch.load_scene(EXAMPLES / f"{path.stem}.toml")
        assert envelope.title == scene.to_dict()["title"]
        assert envelope.precision == scene.integrator.precision
