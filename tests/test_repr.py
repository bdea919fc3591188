"""Short, useful ``repr`` of scenes, results and sweeps (one line: what, span, how it ended)."""

from __future__ import annotations

from pathlib import Path

import pytest

import cayley_heyoka as ch
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
