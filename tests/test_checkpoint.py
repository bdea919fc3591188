"""Checkpointed runs: an interrupted run, resumed, ends with the bits of an uninterrupted one."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.files import identity_of, read_checkpoint
from cayley_heyoka.workflows.checkpoint import CheckpointedRun, CheckpointMismatch

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


class Interrupted(Exception):
    pass


def interrupt_after(stretch: int):
    def hook(k, t):
        if k == stretch:
            raise Interrupted

    return hook


def text(result, values):
    return result.precision.to_text(values)


def assert_same_bits(a, b):
    assert list(a.variables) == list(b.variables)
    for name in [*a.variables, *a.monitors]:
        assert np.array_equal(text(a, a[name]), text(b, b[name])), name
    assert a.counters == b.counters
    assert list(a.events) == list(b.events)
    for name, log in a.events.items():
        assert np.array_equal(text(a, log.time), text(b, b.events[name].time)), name
        assert list(log.label) == list(b.events[name].label)


@pytest.mark.parametrize(
    ("scene", "precision"),
    [
        # Rodrigues chart re-basings (terminal, change state and parameters) and recorded
        # invariable-plane crossings (non-terminal, kept by their callbacks).
        ("free_body.toml", None),
        # Cayley's orbit: the revolution handler keeps its count outside the parameters.
        ("orbit_j2_third_body.toml", None),
        # Extended precision: states and heyoka's double-length time as decimal text.
        ("free_body.toml", "quad"),
        # The invariable angle Ψ: its turn count is kept by the handler, outside the parameters.
        ("free_body.toml", "psi"),
    ],
)
def test_resumed_run_ends_with_the_bits_of_an_uninterrupted_one(tmp_path, scene, precision):
    data = ch.load_scene(EXAMPLES / scene).to_dict()
    if precision == "psi":
        data["output"]["invariable_angle"] = True
    elif precision:
        data["integrator"] = {"precision": precision}
        data["output"]["times"] = {"start": 0, "stop": 20, "count": 41}
    sc = ch.Scene.from_dict(data)
    whole = CheckpointedRun(sc, tmp_path / "a", 9).run()
    with pytest.raises(Interrupted):
        CheckpointedRun(sc, tmp_path / "b", 9).run(interrupt_after(3))
    again = CheckpointedRun(sc, tmp_path / "b", 9)
    with pytest.raises(Interrupted):  # twice, the second time from a resumed run
        again.run(interrupt_after(6))
    assert again.resumed == 3 and not again.notes
    last = CheckpointedRun(sc, tmp_path / "b", 9)
    resumed = last.run()
    assert last.resumed == 6
    assert whole.success and resumed.success
    assert len(whole.t) == len(sc.output.time_grid(sc.integrator.precision))
    assert_same_bits(whole, resumed)
    if "rebasings" in whole.counters:
        assert whole.counters["rebasings"] > 0 and len(whole.events["invariable_plane"]) > 0
    if "revolutions" in whole.counters:
        assert whole.counters["revolutions"] > 3
    if "psi_turns" in whole.counters:
        assert whole.counters["psi_turns"] > 3


def test_stretch_written_after_the_last_snapshot_is_recomputed(tmp_path):
    """Killed between writing a stretch and its snapshot: that stretch is not trusted."""
    sc = ch.load_scene(EXAMPLES / "orbit_j2_third_body.toml")
    whole = CheckpointedRun(sc, tmp_path / "a", 5).run()
    with pytest.raises(Interrupted):
        CheckpointedRun(sc, tmp_path / "b", 5).run(interrupt_after(2))
    # A stray stretch 3 (garbage): it must be discarded, not read.
    (tmp_path / "b" / "segment-000003.ckpt").write_bytes(b"not a segment")
    assert_same_bits(whole, CheckpointedRun(sc, tmp_path / "b", 5).run())


def test_work_directory_of_another_run_is_refused(tmp_path):
    sc = ch.load_scene(EXAMPLES / "projectile.toml")
    with pytest.raises(Interrupted):
        CheckpointedRun(sc, tmp_path, 4).run(interrupt_after(1))
    with pytest.raises(CheckpointMismatch, match="stretches differ"):
        CheckpointedRun(sc, tmp_path, 5).run()
    other = sc.to_dict()
    other["hamiltonian"]["g"] = "2.0"
    with pytest.raises(CheckpointMismatch, match="scene differ"):
        CheckpointedRun(ch.Scene.from_dict(other), tmp_path, 4).run()
    job = CheckpointedRun(sc, tmp_path, 4)
    _, body = read_checkpoint(tmp_path / "manifest.ckpt", "manifest", identity_of(job.manifest()))
    manifest = json.loads(body)
    assert manifest["stretches"] == 4 and manifest["versions"]["heyoka"]


@pytest.mark.parametrize("count", [0, 10_001, 10**9, 2.0, True])
def test_stretch_count_must_be_in_bounds(tmp_path, count):
    sc = ch.load_scene(EXAMPLES / "projectile.toml")
    with pytest.raises(ValueError, match=r"checkpoints .* must be an integer in 1 … 10000"):
        CheckpointedRun(sc, tmp_path, count)


def test_run_that_fails_midway_returns_what_it_computed(tmp_path):
    sc = ch.Scene.from_toml(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [0.1, 0.2, 1]\n"
        '[forces.potential]\nV = "exp(100 * (t - 6)) * lambda"\n'
        "[output]\ntimes = { start = 0, stop = 20, count = 21 }\n"
    )
    partial = CheckpointedRun(sc, tmp_path, 4).run()
    assert partial.status == -1 and "non-finite" in partial.message
    assert 6 <= len(partial.t) < 21
