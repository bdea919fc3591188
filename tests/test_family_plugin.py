"""A family from another package plugs in through the entry-point group
``cayley_heyoka.families`` (docs/overview.md, "Layout"), and the core runs it without naming it."""

from __future__ import annotations

import math
from importlib import metadata

import numpy as np
import pytest
from plugin_family import install

import cayley_heyoka as ch
from cayley_heyoka.core import families

OSCILLATOR = {
    "oscillator": {"omega": "2", "x0": "1", "v0": "0"},
    "output": {"times": {"start": 0, "stop": 10, "count": 11}},
}


def _fresh(monkeypatch, *points: metadata.EntryPoint) -> None:
    """The registry as a new process finds it, with ``points`` installed; restored after."""
    install(monkeypatch, **{p.name: p.value for p in points})


@pytest.fixture
def registered(monkeypatch):
    """The oscillator family of tests/plugin_family.py, as an installed package's entry point
    would register it."""
    _fresh(
        monkeypatch,
        metadata.EntryPoint("oscillator", "plugin_family:FAMILY", families.ENTRY_POINTS),
    )
    return families.FAMILIES


def test_without_the_package_the_family_is_unknown(monkeypatch):
    _fresh(monkeypatch)
    with pytest.raises(ch.SceneError, match="names no model family"):
        ch.Scene.from_dict(OSCILLATOR)


def test_a_plugged_in_family_runs(registered):
    assert "oscillator" in registered and "rotation" in registered
    result = ch.run(ch.Scene.from_dict(OSCILLATOR))
    t = np.asarray(result.t, dtype=float)
    assert np.max(np.abs(np.asarray(result["x"], dtype=float) - np.cos(2 * t))) < 1e-13
    assert result.drift("energy").max() < 1e-14


def test_a_plugged_in_family_in_quad(registered):
    data = {**OSCILLATOR, "integrator": {"precision": "quad"}}
    result = ch.run(ch.Scene.from_dict(data))
    x = float(np.asarray(result["x"])[-1])
    assert abs(x - math.cos(20)) < 1e-15


def test_a_family_may_not_take_one_of_our_names(monkeypatch):
    _fresh(monkeypatch, metadata.EntryPoint("orbit", "plugin_family:FAMILY", families.ENTRY_POINTS))
    with pytest.raises(ch.SceneError, match="one of cayley_heyoka's own"):
        ch.Scene.from_dict(OSCILLATOR)


def test_a_family_that_fails_to_load_is_named_and_stops_nothing_else(monkeypatch):
    _fresh(
        monkeypatch,
        metadata.EntryPoint("broken", "no_such_module_here:FAMILY", families.ENTRY_POINTS),
    )
    scene = ch.Scene.from_dict(
        {
            "body": {"inertia": ["1", "2", "3"]},
            "initial": {"rates": ["1", "0", "0"]},
            "output": {"times": [0, 1]},
        }
    )
    assert scene.family == "rotation"
    with pytest.raises(ch.SceneError, match="'broken' .* cannot be loaded: ModuleNotFoundError"):
        ch.Scene.from_dict(OSCILLATOR)
