"""``cayley-heyoka reference``: certified reference files, and runs that survive interruption."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import mpmath
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.cli import main
from cayley_heyoka.core.certificate import next_precision, precision_for
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.reference import FreeRigidBody
from cayley_heyoka.workflows.reference import generate_reference, read_certificate

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

FREE_BODY = """
title = "free body for reference tests"
[body]
inertia = [1.0, 1.5, 2.5]
[initial]
rates = [0.125, 0.25, 1.0]
rodrigues = [0.1, 0.2, -0.3]
[output]
times = {{ start = 0.0, stop = {stop}, count = {count} }}
events = ["invariable_plane"]
"""


def free_body(stop="20.0", count=21) -> ch.Scene:
    return ch.Scene.from_toml(FREE_BODY.format(stop=stop, count=count))


def test_precision_ladder():
    assert precision_for(10).name == "double"
    assert precision_for(20).name == "quad"
    assert precision_for(34).kind == "real" and precision_for(34).bits >= 34 * np.log2(10)
    assert next_precision(Precision("double")).name == "quad"
    assert next_precision(Precision("quad")).bits >= 113 + 32


def test_two_precision_certificate_bounds_the_true_error(tmp_path):
    """Certified without the closed form, then checked against it (independent code)."""
    sc = free_body()
    out = generate_reference(sc, 20, tmp_path / "ref.h5", method="two-precisions")
    assert out.certified and out.certificate.method == "two precisions"
    ref = ch.load_result(tmp_path / "ref.h5")
    cert = read_certificate(tmp_path / "ref.h5")
    assert cert["certified"] and cert["compared_with"] == "quad"
    assert ref.precision.bits > 113
    body = FreeRigidBody(
        ("1.0", "1.5", "2.5"), ("0.125", "0.25", "1.0"), rodrigues=("0.1", "0.2", "-0.3"), dps=50
    )
    with mpmath.workdps(60):
        for k, t in enumerate(ref.t):
            exact = body.at(mpmath.mpf(str(t)))
            for name in ("p", "q", "r"):
                err = abs(mpmath.mpf(str(ref[name][k])) - getattr(exact, name))
                assert err <= cert["errors"][name][k], (name, float(t))
    # The difference estimates the quad run's error: far above the written run's, and the
    # size a quad run has.
    assert 1e-35 < max(float(np.max(e)) for e in cert["errors"].values()) < 1e-25
    assert len(cert["event_errors"]["invariable_plane"]) == len(ref.events["invariable_plane"])


def test_closed_form_certificate_catches_a_loose_run_and_escalates(tmp_path):
    """A quad run at tolerance 1e-12 cannot carry 25 digits: the closed form says so, and the
    precision goes up until it can. (A tolerance asks for an integration: "auto" integrates.)"""
    out = generate_reference(free_body(), 25, tmp_path / "ref.h5", tolerance="1e-12")
    first, last = out.attempts[0], out.attempts[-1]
    assert first["tolerance"] == "1e-12" and first["scaled_error"] > 1e-20
    assert out.certified and last["scaled_error"] <= 1e-25 and len(out.attempts) >= 2
    cert = read_certificate(tmp_path / "ref.h5")
    assert cert["method"] == "closed form" and cert["digits_certified"] >= 25
    assert len(cert["event_errors"]["invariable_plane"]) > 0
    assert ch.load_result(out.path).metadata["reference"]["method"] == "integration"


def test_projectile_reference_matches_the_notes_and_reproduces_from_its_metadata(tmp_path):
    sc = ch.load_scene(EXAMPLES / "projectile.toml")
    out = generate_reference(sc, 30, tmp_path / "a.h5", command=["test"])
    assert out.certified
    ref = ch.load_result(tmp_path / "a.h5")
    # Case R1 at t = 2.5 of tests/hamilton/test_projectile.py (20 digits there).
    want = ("1.7368282138292105663", "0.38896321247380581221", "2.0483420256785479340")
    with mpmath.workdps(40):
        for i, w in enumerate(want):
            assert abs(mpmath.mpf(str(ref[f"eta{i + 1}"][-1])) - mpmath.mpf(w)) < 1e-19
        assert abs(mpmath.mpf(str(ref["S"][-1])) - mpmath.mpf("-6.0981388215878366413")) < 1e-18
    meta = ref.metadata["reference"]
    assert meta["digits"] == 30 and meta["certified"] and meta["method"] == "closed form"
    assert meta["environment"]["mpmath"] and ref.metadata["heyoka"]
    again = generate_reference(ch.Scene.from_dict(ref.scene), meta["digits"], tmp_path / "b.h5")
    twin = ch.load_result(again.path)
    for name in ref.variables:
        assert np.array_equal(ref.precision.to_text(ref[name]), twin.precision.to_text(twin[name]))


def test_uncertified_reference_is_written_and_marked(tmp_path, capsys):
    code = main(
        [
            "reference",
            str(EXAMPLES / "free_body.toml"),
            "--digits",
            "15",
            "--precision",
            "double",
            "--max-bits",
            "64",
            "--out",
            str(tmp_path / "r.h5"),
            "--no-progress",
        ]
    )
    assert code == 1
    assert "NOT CERTIFIED" in capsys.readouterr().out
    cert = read_certificate(tmp_path / "r.h5")
    assert not cert["certified"] and cert["digits_certified"] < 15
    assert not (tmp_path / "r.h5.work").exists()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--digits", "0"], "--digits must be an integer in 1 … 303"),
        (["--digits", "20", "--tolerance", "0"], "tolerance must be a number > 0"),
        (["--digits", "20", "--precision", "huge"], "--precision must be double, quad or"),
        (["--digits", "60", "--max-bits", "128"], "--max-bits (128) is below the precision needed"),
    ],
)
def test_bad_arguments_are_named(tmp_path, capsys, args, message):
    code = main(
        [
            "reference",
            str(EXAMPLES / "projectile.toml"),
            "--out",
            str(tmp_path / "r.h5"),
            "--no-progress",
            *args,
        ]
    )
    assert code == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "r.h5").exists()


def test_closed_form_is_refused_where_there_is_none(tmp_path):
    with pytest.raises(ValueError, match="method 'closed-form': this scene has none"):
        generate_reference(
            ch.load_scene(EXAMPLES / "heavy_top.toml"), 20, tmp_path / "r.h5", method="closed-form"
        )


def _command(scene: Path, out: Path) -> list[str]:
    return [
        sys.executable,
        "-m",
        "cayley_heyoka.cli",
        "reference",
        str(scene),
        "--digits",
        "25",
        "--certificate",
        "integrate",
        "--out",
        str(out),
        "--no-progress",
    ]


def _stretch(work: Path) -> int:
    """The stretch of the snapshot in ``work`` (its header says it), 0 if none yet."""
    try:
        header = (work / "snapshot.ckpt").read_bytes().split(b"\n")[1].split(b" ", 1)[1]
    except (FileNotFoundError, IndexError):
        return 0
    return json.loads(header)["stretch"]


def _wait_for_stretch(work: Path, proc: subprocess.Popen, at_least: int) -> None:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if _stretch(work) >= at_least:
            return
        time.sleep(0.005)
    raise AssertionError("the run ended or stalled before the checkpoint looked for")


def test_killed_and_interrupted_command_resumes_to_the_same_file(tmp_path):
    """SIGKILL mid-run, then Ctrl-C (SIGINT) mid-run, then to the end: the same bits as one
    uninterrupted command."""
    scene = tmp_path / "body.toml"
    scene.write_text(FREE_BODY.format(stop="60.0", count=31))
    out = tmp_path / "ref.h5"
    work = tmp_path / "ref.h5.work" / "run-quad"
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}

    proc = subprocess.Popen(_command(scene, out), env=env)
    _wait_for_stretch(work, proc, 2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    killed_at = _stretch(work)
    assert 2 <= killed_at < 64 and not out.exists()

    proc = subprocess.Popen(_command(scene, out), env=env, stderr=subprocess.PIPE, text=True)
    _wait_for_stretch(work, proc, killed_at + 2)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted" in err and "run the same command to continue" in err

    done = subprocess.run(_command(scene, out), env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "resumed after" in done.stdout and "certified" in done.stdout
    assert not (tmp_path / "ref.h5.work").exists()

    whole = tmp_path / "whole.h5"
    assert subprocess.run(_command(scene, whole), env=env, capture_output=True).returncode == 0
    a, b = ch.load_result(out), ch.load_result(whole)
    for name in [*a.variables, *a.monitors]:
        assert np.array_equal(a.precision.to_text(a[name]), b.precision.to_text(b[name])), name
    assert np.array_equal(
        a.precision.to_text(a.events["invariable_plane"].time),
        b.precision.to_text(b.events["invariable_plane"].time),
    )
    assert a.counters == b.counters
    ca, cb = read_certificate(out), read_certificate(whole)
    for name, err in ca["errors"].items():
        assert np.array_equal(err, cb["errors"][name])


def test_two_precision_certificate_catches_a_loose_run_and_escalates(tmp_path):
    """Without a closed form the loose run is caught by the second precision; the more precise
    run then becomes the one checked, against a third."""
    out = generate_reference(
        free_body(), 20, tmp_path / "ref.h5", tolerance="1e-12", method="two-precisions"
    )
    first, last = out.attempts[0], out.attempts[-1]
    assert first["precision"] == "quad" and first["scaled_error"] > 1e-15
    assert out.certified and len(out.attempts) == 2
    assert last["precision"] != "quad" and last["scaled_error"] <= 1e-20
    assert ch.load_result(out.path).precision.bits > int(last["precision"].removeprefix("mpfr"))


def test_failed_run_is_reported_not_certified(tmp_path, capsys):
    scene = tmp_path / "boom.toml"
    scene.write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [0.1, 0.2, 1]\n"
        '[forces.potential]\nV = "exp(100 * (t - 6)) * lambda"\n'
        "[output]\ntimes = { start = 0, stop = 20, count = 21 }\n"
    )
    code = main(
        [
            "reference",
            str(scene),
            "--digits",
            "10",
            "--out",
            str(tmp_path / "r.h5"),
            "--no-progress",
        ]
    )
    assert code == 1
    err = capsys.readouterr().err
    assert "run stopped" in err and "non-finite" in err and "not certified" in err
    partial = ch.load_result(tmp_path / "r.h5")
    assert not partial.success and 6 <= len(partial.t) < 21
    cert = read_certificate(tmp_path / "r.h5")
    assert not cert["certified"] and cert["digits_certified"] == -np.inf


def test_a_full_disk_at_the_end_keeps_the_checkpoints_and_the_rerun_writes(
    tmp_path, capsys, monkeypatch
):
    import errno

    from cayley_heyoka.workflows import reference as reference_run

    scene = tmp_path / "s.toml"
    scene.write_text(FREE_BODY.format(stop="2.0", count=3))
    out = tmp_path / "r.h5"
    argv = ["reference", str(scene), "--digits", "12", "--out", str(out), "--no-progress"]
    real = reference_run.write_hdf5

    def full_disk(path, fill):
        raise ch.OutputError.failed_write(path, OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))

    monkeypatch.setattr(reference_run, "write_hdf5", full_disk)
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "No space left on device" in err and "checkpoints are kept" in err
    assert not out.exists() and any((tmp_path / "r.h5.work").iterdir())
    monkeypatch.setattr(reference_run, "write_hdf5", real)
    assert main(argv) == 0
    assert read_certificate(out)["certified"]
    assert not (tmp_path / "r.h5.work").exists()
