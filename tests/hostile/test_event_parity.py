"""Hostile events: crossings beside a terminal event, a start on an event's zero, and an
event's expression whose Taylor coefficients are not finite at its zero.

Cayley's orbit counts its revolutions with a terminal event at Σ = 0 or π, which is where the
node is when Σ₀ is 0 or π: every crossing must be recorded once (``core/event_parity.py``),
in a lone run, its file and a sweep's counts. ``sqrt(z)`` as an event makes heyoka's steps of
size zero where z reaches 0: the run stops with a message naming it, and a signal stops it
(the state is poisoned as well as the parameters, since such steps see neither).
"""

from __future__ import annotations

import re
import signal

import pytest
from helpers import ORBIT_ELEMENTS

import cayley_heyoka as ch
from cayley_heyoka.workflows.sweep_result import load_sweep


def orbit(formulation="cayley", sigma0=None, **elements) -> dict:
    body = {"mu": "1", "formulation": formulation, "elements": {**ORBIT_ELEMENTS, **elements}}
    if sigma0 is not None:
        body["sigma0"] = sigma0
    return {
        "orbit": body,
        "output": {"times": {"start": "0", "stop": "40", "count": 11}, "events": ["node"]},
    }


def nodes(path) -> int:
    return len(ch.load_result(str(path)).events["node"])


@pytest.mark.covers(
    "class:12", "key:orbit.sigma0", "key:output.events", "verb:run", "option:run --out"
)
@pytest.mark.parametrize("sigma0", ["3.1415926535897922", "-4e-16", "-3.141592653589793"])
def test_a_file_holds_every_node_beside_the_revolution_count(hostile, sigma0):
    scene = hostile.scene(orbit(sigma0=sigma0))
    reference = hostile.scene(orbit("cartesian"))
    a, b = hostile.tmp_path / "a.h5", hostile.tmp_path / "b.h5"
    hostile.run(["run", str(scene), "--out", str(a)], expect="done", out=a)
    hostile.run(["run", str(reference), "--out", str(b)], expect="done", out=b)
    assert nodes(a) == nodes(b) == 12


@pytest.mark.covers("class:12", "key:orbit.sigma0", "key:orbit.elements.mean_anomaly", "verb:run")
@pytest.mark.parametrize("formulation", ["cayley", "quaternion"])
def test_a_start_on_the_node_and_the_revolution_count_at_once(hostile, formulation):
    """ω = M = 0 and Σ₀ = 0: the orbit starts in its reference plane, on the terminal event's
    zero; the crossing at the start is not one (Cartesian: the same nodes)."""
    start = {"argument_of_pericentre": "0"}
    scene = hostile.scene(orbit(formulation, "0", **start))
    reference = hostile.scene(orbit("cartesian", **start))
    a, b = hostile.tmp_path / "a.h5", hostile.tmp_path / "b.h5"
    hostile.run(["run", str(scene), "--out", str(a)], expect="done", out=a)
    hostile.run(["run", str(reference), "--out", str(b)], expect="done", out=b)
    assert nodes(a) == nodes(b)


@pytest.mark.covers("class:12", "key:orbit.sigma0", "verb:sweep", "option:sweep --out")
def test_a_sweep_counts_every_node_beside_the_revolution_count(hostile):
    hostile.scene(orbit(sigma0="0"), name="orbit.toml")
    study = hostile.scene(
        {
            "scene": "orbit.toml",
            "sweep": {
                "kind": "grid",
                "parameters": {"orbit.sigma0": ["0", "-4e-16", "3.1415926535897922"]},
            },
        },
        name="study.toml",
    )
    out = hostile.tmp_path / "sweep.h5"
    hostile.run(["sweep", str(study), "--out", str(out)], expect="done", out=out)
    assert list(load_sweep(out).events["node"]) == [12, 12, 12]


def singular(formulation="cartesian", **integrator) -> dict:
    """An event ``sqrt(z)``: its Taylor coefficients are not finite where z reaches 0."""
    scene = orbit(formulation, "0" if formulation == "cayley" else None, mean_anomaly="1")
    scene["events"] = {"root": {"expression": "sqrt(z)"}}
    scene["output"]["events"] = ["node", "root"]
    if integrator:
        scene["integrator"] = integrator
    return scene


@pytest.mark.covers("class:12", "key:events.*.expression", "key:integrator.max_steps", "verb:run")
def test_steps_of_size_zero_are_named(hostile):
    scene = hostile.scene(singular(max_steps=100_000))
    out = hostile.tmp_path / "r.h5"
    o = hostile.run(["run", str(scene), "--out", str(out)], expect="stopped", out=out)
    assert "step size fell to zero" in o.stderr and "'root'" in o.stderr
    assert len(ch.load_result(str(out)).t) == 1  # the first output at t = 4 is beyond it


@pytest.mark.covers("class:12", "key:events.*.expression", "verb:run", "option:run --progress")
@pytest.mark.parametrize("progress", ["--progress", "--no-progress"])
def test_steps_of_size_zero_stop_the_run_within_seconds_with_the_default_budget(hostile, progress):
    """heyoka would take 10⁹ of them: seen by the per-step callback of the progress bar (100
    in a row), or by the thread that waits for the run (the time unchanged for a second)."""
    scene = hostile.scene(singular())
    out = hostile.tmp_path / "r.h5"
    o = hostile.run(
        ["run", str(scene), "--out", str(out), progress], expect="stopped", out=out, seconds=30
    )
    assert "step size fell to zero at t = 1.77" in o.stderr


@pytest.mark.covers("key:events.*.expression", "verb:run", "class:8")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_stops_steps_that_shrink_towards_zero(hostile, sig):
    """In Cayley's orbit the same event's coefficients stay finite: the steps shrink towards
    zero without reaching it, and the run would go on to its budget."""
    scene = hostile.scene(singular("cayley"))
    out = hostile.tmp_path / "r.h5"
    hostile.process(
        ["run", str(scene), "--out", str(out), "--progress"],
        send=sig,
        # Past the bar's first draw, which comes before the compilation (seconds under load):
        # a signal then finds nothing computed yet, and the command ends without a file.
        wait_for=re.compile(r"\b[1-9]\d?%"),
        delay=2.0,
        expect="interrupted",
        out=out,
        seconds=60,
    )


@pytest.mark.covers("key:events.*.expression", "verb:sweep", "class:8")
def test_a_signal_stops_a_sweep_in_steps_of_size_zero(hostile):
    """The lanes' batch call takes steps of size zero to the budget: a signal's poison of the
    parameters does not reach them, that of the state is laid again until the call returns."""
    hostile.scene(singular(), name="orbit.toml")
    study = hostile.scene(
        {
            "scene": "orbit.toml",
            "sweep": {"kind": "grid", "parameters": {"orbit.mu": ["1", "1.01"]}},
        },
        name="study.toml",
    )
    hostile.process(
        ["sweep", str(study), "--no-progress"],
        send=signal.SIGTERM,
        wait_for=None,
        delay=4.0,
        expect="interrupted",
        seconds=60,
    )
