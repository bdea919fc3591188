"""``cayley-heyoka reference`` by the closed form: the file an integration would write, certified.

The closed-form route is checked against the integration route (both certificates must
cover their difference), against an independent high-precision evaluation (including the
quadrature route, free of Π), for the same bits whatever the number of workers, and for a
clean Ctrl-C that resumes to the same bits.
"""

from __future__ import annotations

import math
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
from cayley_heyoka.core.evaluation import PARALLEL_FROM, Rounding
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.reference import FreeRigidBody
from cayley_heyoka.workflows.reference import generate_reference, read_certificate

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

FREE_BODY = """
[body]
inertia = [1.0, 1.5, 2.5]
[initial]
rates = [0.125, 0.25, 1.0]
rodrigues = [0.1, 0.2, -0.3]
{attitude}
[output]
times = {{ start = 0.0, stop = {stop}, count = {count} }}
events = ["invariable_plane"]
"""
FORMULATIONS = {
    "rodrigues": "",
    "quaternion": '[attitude]\nformulation = "quaternion"',
    "rates only": '[attitude]\nformulation = "none"',
}


def free_body(stop: str = "20.0", count: int = 21, attitude: str = "") -> ch.Scene:
    return ch.Scene.from_toml(FREE_BODY.format(stop=stop, count=count, attitude=attitude))


def _mpf(x, prec: Precision) -> mpmath.mpf:
    """The exact value of ``x`` (its text is the shortest that reads back, not its value)."""
    return Rounding(prec.kind, prec.bits).read(prec.to_text(np.array([x]))[0])


def _same_bits(a: ch.Result, b: ch.Result) -> None:
    text = a.precision.to_text
    for name in [*a.variables, *a.monitors]:
        assert np.array_equal(text(a[name]), text(b[name])), name
    for name, log in a.events.items():
        assert np.array_equal(text(log.time), text(b.events[name].time)), name
        assert list(log.label) == list(b.events[name].label)


@pytest.mark.parametrize(
    "scene",
    [pytest.param(free_body(attitude=a), id=k) for k, a in FORMULATIONS.items()]
    + [pytest.param(ch.load_scene(EXAMPLES / "projectile.toml"), id="projectile")],
)
def test_closed_form_file_is_the_integrations_within_both_certificates(tmp_path, scene):
    """Same variables, monitors, events (labels, directions) as the integrated run's file;
    each certificate bounds its file's error, so together they bound the difference."""
    a = generate_reference(scene, 11, tmp_path / "closed.h5")
    b = generate_reference(scene, 11, tmp_path / "integrated.h5", method="integrate")
    assert a.certified and b.certified
    A, B = ch.load_result(a.path), ch.load_result(b.path)
    assert A.metadata["reference"]["method"] == "closed form"
    assert B.metadata["reference"]["method"] == "integration"
    assert A.precision == B.precision == Precision("double")
    assert list(A.variables) == list(B.variables) and list(A.monitors) == list(B.monitors)
    assert A.conserved == B.conserved and list(A.events) == list(B.events)
    assert np.array_equal(A.t, B.t)
    ca, cb = read_certificate(a.path), read_certificate(b.path)
    # Every variable and monitor the file writes has its error.
    assert ca["method"] == "closed form" and set(ca["errors"]) == {*A.variables, *A.monitors}
    assert set(cb["errors"]) == set(ca["errors"]) and ca["uncovered"] == cb["uncovered"] == "[]"
    # Both certificates are tight (each the exact distance to the closed form, plus a bound
    # of ~1e-29), so where the closed form lies between the files the difference equals
    # their sum: 1e-12 relative is room for the rounding of each to float64, nothing more.
    slack = 1 + 1e-12
    for name in [*A.variables, *A.monitors]:
        diff = np.abs(A[name] - B[name])
        assert np.all(diff <= (ca["errors"][name] + cb["errors"][name]) * slack), name
    for name, log in A.events.items():
        theirs = B.events[name]
        assert len(log) == len(theirs) > 0
        assert list(log.label) == list(theirs.label)
        assert list(log.direction) == list(theirs.direction)
        diff = np.abs(log.time - theirs.time)
        assert np.all(diff <= (ca["event_errors"][name] + cb["event_errors"][name]) * slack)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["closed.h5", "integrated.h5"]


def test_closed_form_values_hold_against_an_independent_evaluation(tmp_path):
    """30 digits: every written value within its certificate of the closed form at 60 digits,
    and of the quadrature route (no Π, no Jacobi functions) at two times."""
    out = generate_reference(free_body(), 30, tmp_path / "ref.h5")
    ref, cert = ch.load_result(out.path), read_certificate(out.path)
    assert out.certified and ref.precision.bits >= 113
    # Not vacuous: the certificate is the rounding to the file's precision and little more.
    assert max(float(np.max(e)) for e in cert["errors"].values()) < 1e-33
    body = FreeRigidBody(
        ("1.0", "1.5", "2.5"), ("0.125", "0.25", "1.0"), rodrigues=("0.1", "0.2", "-0.3"), dps=60
    )
    prec = ref.precision
    with mpmath.workdps(70):
        for k, t in enumerate(ref.t):
            s = body.at(_mpf(t, prec))
            want = dict(zip(("p", "q", "r"), s.rates, strict=True))
            want.update(zip(("qw", "qx", "qy", "qz"), s.quaternion, strict=True))
            want.update(zip(("lambda", "mu", "nu"), s.rodrigues, strict=True))
            for name, value in want.items():
                err = abs(_mpf(ref[name][k], prec) - value)
                assert err <= cert["errors"][name][k], (name, k)
        for k in (7, 20):
            s = body.at(_mpf(ref.t[k], prec), method="quadrature")
            for name, value in zip(("p", "q", "r"), s.rates, strict=True):
                err = abs(_mpf(ref[name][k], prec) - value)
                assert err <= cert["errors"][name][k], (name, k)
        log = ref.events["invariable_plane"]
        for axis in ("x1", "y1"):
            exact = body.crossing_times(axis, 0, _mpf(ref.t[-1], prec))
            ours = log.where(axis)
            errors = cert["event_errors"]["invariable_plane"][log.label == axis]
            assert len(ours) == len(exact) > 0
            for t, c, e in zip(ours, exact, errors, strict=True):
                assert abs(_mpf(t, prec) - c.time) <= e
        assert len(log.where("z1")) == 0  # r is the dn component: it never vanishes


def test_python_floats_are_the_numbers_the_run_integrates(tmp_path):
    """A scene built in Python with floats: the closed form starts from their binary values, as
    the run does (it used to take their decimal text, 1e-17 away: p(0) was quad(1/10))."""
    scene = ch.Scene.from_dict(
        {
            "body": {"inertia": [1.0, 1.5, 2.5]},
            "initial": {"rates": [0.1, 0.2, 0.3], "rodrigues": [0.1, 0.2, -0.3]},
            "output": {"times": [0.0, 1.0]},
        }
    )
    out = generate_reference(scene, 25, tmp_path / "ref.h5")
    ref = ch.load_result(out.path)
    assert out.certified and ref.precision.bits >= 113
    for name, value in zip("pqr", (0.1, 0.2, 0.3), strict=True):
        assert _mpf(ref[name][0], ref.precision) == mpmath.mpf(value), name
    # The attitude too: the scene's binary Rodrigues parameters, as the run reads them.
    start = scene.model.initial_quaternion(Precision("real", 200))
    cert = read_certificate(out.path)
    for k, name in enumerate(("qw", "qx", "qy", "qz")):
        with mpmath.workprec(200):
            gap = abs(_mpf(ref[name][0], ref.precision) - mpmath.mpf(str(start[k])))
        assert gap <= cert["errors"][name][0] + mpmath.mpf(2) ** -190, name


def test_lambda_at_a_half_turn_is_not_certified(tmp_path, capsys):
    """Starting a half-turn from the space frame (w = 0), λ, μ, ν are unbounded: the reference
    says so and is not certified (an ∞/∞ scaled error used to be passed over as NaN)."""
    scene = ch.Scene.from_dict(
        {
            "body": {"inertia": ["1", "1.5", "2.5"]},
            "initial": {
                "rates": ["0.125", "0.25", "1"],
                "matrix": [[-1, 0, 0], [0, -1, 0], [0, 0, 1]],
            },
            "output": {"times": ["0", "3"]},
        }
    )
    out = generate_reference(scene, 20, tmp_path / "ref.h5", max_bits=160)
    assert not out.certified
    assert out.certificate.worst[0] in ("lambda", "mu", "nu") and out.certificate.worst[1] == 0
    assert out.certificate.digits_text() == "no digits"
    cert = read_certificate(out.path)
    assert not cert["certified"] and cert["digits_certified"] == -np.inf
    # Away from the half-turn every value is proved.
    assert np.all(np.asarray(cert["errors"]["p"], dtype=float) < 1e-20)


def test_workers_give_the_same_bits(tmp_path):
    scene = free_body("30.0", PARALLEL_FROM + 16)
    one = generate_reference(scene, 25, tmp_path / "one.h5", workers=1)
    two = generate_reference(scene, 25, tmp_path / "two.h5", workers=2)
    _same_bits(ch.load_result(one.path), ch.load_result(two.path))
    c1, c2 = read_certificate(one.path), read_certificate(two.path)
    for name, err in c1["errors"].items():
        assert np.array_equal(err, c2["errors"][name]), name
    assert np.array_equal(
        c1["event_errors"]["invariable_plane"], c2["event_errors"]["invariable_plane"]
    )


def test_closed_form_escalates_from_a_precision_too_coarse(tmp_path):
    out = generate_reference(free_body(), 20, tmp_path / "ref.h5", precision=Precision("double"))
    first, last = out.attempts[0], out.attempts[-1]
    assert first["precision"] == "double" and first["scaled_error"] > 1e-20
    assert out.certified and last["precision"] == "quad" and last["scaled_error"] <= 1e-20


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"workers": 0}, "workers must be an integer >= 1"),
        ({"method": "closed-form", "tolerance": "1e-20"}, "tolerance applies to an integration"),
    ],
)
def test_bad_closed_form_arguments_are_named(tmp_path, kwargs, message):
    with pytest.raises(ValueError, match=message):
        generate_reference(free_body(), 20, tmp_path / "ref.h5", **kwargs)
    assert not any(tmp_path.iterdir())


def _children(pid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                stat = Path(f"/proc/{entry}/stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry))
    return found


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="lists processes through /proc")
def test_ctrl_c_ends_workers_and_the_same_command_resumes_to_the_same_bits(tmp_path):
    """Ctrl-C (SIGINT to the whole process group, as a terminal sends it) mid-evaluation:
    exit 130, no file, no worker left; run again, it reads back the saved chunks and writes
    what one uninterrupted evaluation writes."""
    scene = tmp_path / "body.toml"
    scene.write_text(FREE_BODY.format(stop="500.0", count=256, attitude=""))
    out = tmp_path / "ref.h5"
    command = [
        *(sys.executable, "-m", "cayley_heyoka.cli", "reference", str(scene)),
        *("--digits", "30", "--out", str(out), "--no-progress"),
    ]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    store = tmp_path / "ref.h5.work" / "closed-form-mpfr128"
    proc = subprocess.Popen(
        command, env=env, start_new_session=True, stderr=subprocess.PIPE, text=True
    )
    deadline, workers = time.monotonic() + 120, []
    while time.monotonic() < deadline and proc.poll() is None:
        workers = _children(proc.pid)
        if store.is_dir() and len(list(store.glob("chunk-*.ckpt"))) >= 2:
            break
        time.sleep(0.01)
    else:
        raise AssertionError("the command ended or stalled before two chunks were saved")
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "interrupted" in err
    assert not out.exists() and len(workers) >= 2
    deadline = time.monotonic() + 10
    while any(_alive(p) for p in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(_alive(p) for p in workers)
    saved = len(list(store.glob("chunk-*.ckpt")))
    assert 2 <= saved < 64

    done = subprocess.run(command, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "resumed after" in done.stdout and "certified" in done.stdout
    assert not (tmp_path / "ref.h5.work").exists()
    whole = generate_reference(ch.load_scene(scene), 30, tmp_path / "whole.h5", workers=1)
    _same_bits(ch.load_result(out), ch.load_result(whole.path))
    ca, cb = read_certificate(out), read_certificate(whole.path)
    for name, err in ca["errors"].items():
        assert np.array_equal(err, cb["errors"][name]), name


def test_the_command_line_passes_workers(tmp_path):
    """``--workers N`` reaches the evaluation (a count below 1 is refused by name)."""
    from cayley_heyoka.cli import main

    path = tmp_path / "body.toml"
    path.write_text(FREE_BODY.format(stop="30.0", count=PARALLEL_FROM + 16, attitude=""))
    one, two = tmp_path / "one.h5", tmp_path / "two.h5"
    argv = ["reference", str(path), "--digits", "25", "--no-progress"]
    assert main([*argv, "--out", str(one), "--workers", "1"]) == 0
    assert main([*argv, "--out", str(two), "--workers", "2"]) == 0
    _same_bits(ch.load_result(one), ch.load_result(two))
    with pytest.raises(SystemExit):
        main([*argv, "--out", str(tmp_path / "x.h5"), "--workers", "0"])


def test_the_worst_error_is_placed_at_a_time_only_when_it_has_one():
    """An event's error is of its time: the summary names the event, not "at t = nan"."""
    from cayley_heyoka.core.certificate import Certificate
    from cayley_heyoka.workflows.reference import _where

    cert = Certificate("closed form", "the closed form's bound", {}, {})
    cert.worst = ("p", 2.5)
    assert _where(cert) == "p at t = 2.5"
    cert.worst = ("event invariable_plane", math.nan)
    assert _where(cert) == "event invariable_plane"
