"""Hostile writes: full disks, signals during a save, damaged work directories, files rewritten
by other programs, two commands on one ``--out``.

Every file and checkpoint goes through one writer (cayley_heyoka/core/files.py): atomic, with
per-process temporaries, checksummed, carrying its run's identity, safe on a full disk and under
a signal during the write. Each case ends as conftest.py requires, and leaves no temporary, no
half file and no silently wrong number behind.
"""

from __future__ import annotations

import contextlib
import errno
import os
import re
import shutil
import signal
import subprocess
import sys
import textwrap
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from conftest import Outcome, _judge, toml

import cayley_heyoka as ch
from cayley_heyoka.core import files
from cayley_heyoka.core.files import identity_of, write_checkpoint
from cayley_heyoka.workflows.reference import WORK_LOCK, WORK_MARKER, read_certificate

ROOT = Path(__file__).resolve().parents[2]
PROJECTILE = ROOT / "examples" / "projectile.toml"
BODY = {
    "title": "hostile writes",
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["1", "0.1875", "0.25"]},
    "output": {"times": {"start": "0", "stop": "2", "count": 12}},
}


def _study(hostile) -> Path:
    scene = hostile.scene(BODY, name="member.toml")
    grid = {"initial.rates[0]": {"start": 0.5, "stop": 1.0, "count": 4}}
    return hostile.scene(
        {"scene": str(scene), "sweep": {"kind": "grid", "parameters": grid}}, name="study.toml"
    )


@pytest.fixture(scope="module")
def source(tmp_path_factory) -> Path:
    """A result file to plot (written before any write is made to fail)."""
    path = tmp_path_factory.mktemp("source") / "source.h5"
    ch.run(ch.Scene.from_dict(BODY)).save(path)
    return path


def _argv(verb: str, hostile, out: Path, source: Path | None = None) -> list[str]:
    """A quick command of ``verb`` writing ``out`` (``source``: the file ``plot`` draws)."""
    if verb == "run":
        return ["run", str(hostile.scene(BODY)), "--out", str(out), "--no-progress"]
    if verb == "check":
        return ["check", str(PROJECTILE), "--out", str(out)]
    if verb == "sweep":
        return ["sweep", str(_study(hostile)), "--out", str(out), "--no-progress"]
    if verb == "reference":
        scene = hostile.scene(BODY)
        return [
            "reference", str(scene), "--digits", "8", "--certificate", "integrate",
            "--checkpoints", "4", "--out", str(out), "--no-progress",
        ]  # fmt: skip
    if verb == "plot":
        assert source is not None
        return ["plot", str(source), "--kind", "drift", "--out", str(out)]
    raise AssertionError(verb)


def _suffix(verb: str) -> str:
    return ".png" if verb == "plot" else ".h5"


def _entries(d: Path) -> list[str]:
    return sorted(p.name for p in d.iterdir())


# ---------------------------------------------------------------------- a full disk
@contextlib.contextmanager
def _tmpfs(d: Path, size: str) -> Iterator[bool]:
    """A real file system of ``size`` mounted on ``d`` (True), or nothing (False) where this
    process may not mount one."""
    if os.geteuid() != 0 or not shutil.which("mount"):
        yield False
        return
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(d)],
        capture_output=True,
    )
    if done.returncode != 0:
        yield False
        return
    try:
        yield True
    finally:
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


def _ours(fd: int) -> bool:
    """Whether ``fd`` is open on one of the writer's temporaries (the writes to fail)."""
    try:
        return ".tmp-" in os.readlink(f"/proc/self/fd/{fd}")
    except OSError:
        return False


@pytest.fixture
def full_disk(tmp_path, monkeypatch) -> Iterator[Path]:
    """A directory on a full disk: a real 128 kB tmpfs filled to its last 8 kB where this
    process may mount one, else every write of the one writer fails with ENOSPC."""
    d = tmp_path / "full"
    d.mkdir()
    with _tmpfs(d, "128k") as real:
        if real:
            filler = d / "filler"
            with open(filler, "wb") as f, contextlib.suppress(OSError):
                f.write(bytes(128 * 1024 - 8192))
        else:
            real_write = os.write

            def no_room(fd: int, data: bytes) -> int:
                if _ours(fd):
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
                return real_write(fd, data)

            monkeypatch.setattr(files.os, "write", no_room)
            (d / "filler").write_bytes(b"")
        yield d


@pytest.mark.covers("class:7", "class:6", "verb:run", "verb:check", "verb:sweep")
@pytest.mark.covers("verb:reference", "verb:plot", "option:run --out", "option:check --out")
@pytest.mark.covers("option:sweep --out", "option:reference --out", "option:plot --out")
@pytest.mark.parametrize("verb", ["run", "check", "sweep", "reference", "plot"])
def test_full_disk_stops_cleanly_and_leaves_nothing_behind(hostile, source, full_disk, verb):
    """No HDF5 traceback, no crash, no raw errno line, no temporary on the full disk."""
    out = full_disk / f"out{_suffix(verb)}"
    argv = _argv(verb, hostile, out, source)
    o = hostile.run(argv, expect={"stopped", "refused"})
    assert "No space left on device" in o.error_line
    assert "Errno" not in o.stderr
    left = [n for n in _entries(full_disk) if n != "filler"]
    if verb == "reference":  # its checkpoints are kept, to continue from
        assert left in ([], [out.name + ".work"])
        assert "run the same command" in o.stderr or o.kind == "refused"
    else:
        assert left == []
        assert o.kind == "stopped"
    if verb == "run":
        assert "hostile writes" in o.stdout  # what was computed is still shown
    if verb == "sweep":
        assert "4 completed" in o.stdout


@pytest.mark.covers("class:7", "verb:run")
def test_full_disk_keeps_the_previous_file(hostile, tmp_path, monkeypatch):
    out = tmp_path / "r.h5"
    argv = _argv("run", hostile, out)
    hostile.run(argv, expect="done", out=out)
    before = out.read_bytes()
    real = os.write

    def half_then_full(fd: int, data: bytes) -> int:
        if not _ours(fd):
            return real(fd, data)
        if len(data) > 1000:
            return real(fd, bytes(data[:1000]))
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "write", half_then_full)
    hostile.run(argv, expect="stopped", out=out)
    assert out.read_bytes() == before
    assert _entries(tmp_path) == ["r.h5", "scene1.toml"]


@pytest.mark.covers("class:6", "class:7", "verb:reference")
def test_reference_stopped_by_a_full_work_directory_continues_once_there_is_room(
    hostile, tmp_path, monkeypatch
):
    """The disk fills after two checkpoints: stopped, rows kept; with room again, the same
    command continues from them and writes the bits of an uninterrupted reference."""
    out = tmp_path / "r.h5"
    argv = _argv("reference", hostile, out)
    real = files.write_bytes
    writes = []

    def fills_up(path, data):
        writes.append(Path(path).name)
        if "snapshot.ckpt" in writes[-1] and writes.count("snapshot.ckpt") == 3:
            raise files.OutputError.failed_write(path, OSError(errno.ENOSPC, "No space left"))
        real(path, data)

    monkeypatch.setattr(files, "write_bytes", fills_up)
    o = hostile.run(argv, expect="stopped")
    assert "snapshot.ckpt" in o.error_line and "run the same command" in o.stderr
    monkeypatch.setattr(files, "write_bytes", real)
    o = hostile.run(argv, expect="done", out=out)
    assert "resumed after 2 of 4 stretches" in o.stdout
    whole = tmp_path / "whole.h5"
    hostile.run([*argv[:-2], str(whole), "--no-progress"], expect="done", out=whole)
    _same_bits(out, whole)


# ---------------------------------------------------------------------- a signal during a save
def _signal_during_the_write(monkeypatch, signum: int, name: str) -> list[str]:
    """Send ``signum`` to this process while the first file called ``name`` is written."""
    real = os.fsync
    sent: list[str] = []

    def fsync(fd: int) -> None:
        if not sent and os.readlink(f"/proc/self/fd/{fd}").endswith(name):
            sent.append("sent")
            os.kill(os.getpid(), signum)
            time.sleep(0.05)  # the handler runs in this window
        real(fd)

    monkeypatch.setattr(files.os, "fsync", fsync)
    return sent


@pytest.mark.covers("class:8", "verb:run", "verb:check", "verb:sweep", "verb:reference")
@pytest.mark.covers("verb:plot")
@pytest.mark.parametrize("verb", ["run", "check", "sweep", "reference", "plot"])
def test_signal_during_the_save_finishes_the_file_first(
    hostile, source, tmp_path, monkeypatch, verb
):
    out = tmp_path / f"out{_suffix(verb)}"
    argv = _argv(verb, hostile, out, source)
    if verb == "reference":  # the closed form, whose only file is the result
        argv.remove("--certificate")
        argv.remove("integrate")
    sent = _signal_during_the_write(monkeypatch, signal.SIGINT, f".{out.name}.tmp-{os.getpid()}")
    o = hostile.run(argv, expect="interrupted", out=out)
    assert sent and "interrupted" in o.stderr
    if verb == "plot":
        assert files.identify(out) == "plot"
    elif verb == "check":
        assert ch.core.consistency.CheckReport.load(out).passed
    elif verb == "sweep":
        assert ch.load_sweep(out).completed.all()
    else:
        assert ch.load_result(out).success
    if verb == "reference":
        assert read_certificate(out)["certified"]
        assert "interrupted after the reference was written" in o.stderr
    assert not [n for n in _entries(tmp_path) if ".tmp-" in n]


@pytest.mark.covers("class:8", "verb:run")
def test_sigterm_during_the_save_finishes_the_file_first(hostile, tmp_path, monkeypatch):
    out = tmp_path / "r.h5"
    _signal_during_the_write(monkeypatch, signal.SIGTERM, f".r.h5.tmp-{os.getpid()}")
    hostile.run(_argv("run", hostile, out), expect="interrupted", out=out)
    assert len(ch.load_result(out).t) == 12


@pytest.mark.covers("class:6", "class:8", "verb:reference")
def test_signal_during_a_checkpoint_keeps_the_previous_rows(hostile, tmp_path, monkeypatch):
    """A Ctrl-C while a checkpoint is written: that checkpoint is finished, the command
    stops with it, and the same command continues from it."""
    out = tmp_path / "r.h5"
    argv = _argv("reference", hostile, out)
    sent = _signal_during_the_write(monkeypatch, signal.SIGINT, f".snapshot.ckpt.tmp-{os.getpid()}")
    o = hostile.run(argv, expect="interrupted")
    assert sent and "run the same command to continue" in o.stderr and not out.exists()
    monkeypatch.undo()
    o = hostile.run(argv, expect="done", out=out)
    assert "resumed after 1 of 4 stretches" in o.stdout
    assert read_certificate(out)["certified"]


# A command whose save takes a second (its fsync is slowed), which says when it starts saving.
_SLOW_SAVE = textwrap.dedent(
    """
    import os, sys, time
    from cayley_heyoka.core import files
    from cayley_heyoka.cli import main

    real = os.fsync
    slowed = []

    def slow(fd):
        if not slowed:
            slowed.append(fd)
            print("saving", file=sys.stderr, flush=True)
            time.sleep(1.0)
        real(fd)

    files.os.fsync = slow
    sys.exit(main(sys.argv[1:]))
    """
)


@pytest.mark.covers("class:8", "verb:run", "option:run --out")
def test_ctrl_c_twice_keeps_the_interrupted_run(hostile, tmp_path):
    """A real process: Ctrl-C during the run, and again while its rows are saved."""
    scene = hostile.scene(
        {**BODY, "output": {"times": {"start": 0, "stop": 10**6, "count": 10**4}}}
    )
    out = tmp_path / "r.h5"
    argv = ["run", str(scene), "--out", str(out), "--progress"]
    proc = subprocess.Popen(
        [sys.executable, "-c", _SLOW_SAVE, *argv],
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    err = bytearray()
    said = {"progress": threading.Event(), "saving": threading.Event()}

    def read() -> None:
        while chunk := proc.stderr.read1(4096):
            err.extend(chunk)
            if re.search(rb"t = [1-9]", err):  # stepping: past the compilation
                said["progress"].set()
            if b"saving" in err:
                said["saving"].set()
        for event in said.values():
            event.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    t0 = time.perf_counter()
    try:
        assert said["progress"].wait(60)
        proc.send_signal(signal.SIGINT)
        assert said["saving"].wait(60)
        proc.send_signal(signal.SIGINT)
        stdout = proc.stdout.read()
        code = proc.wait(60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    reader.join(10)
    text = err.decode(errors="replace")
    o = Outcome(argv, code, stdout.decode(), text, time.perf_counter() - t0, "")
    _judge(o, "interrupted", None, out, 120)
    assert "result written to" in o.stdout
    kept = ch.load_result(out)
    assert kept.status == -2 and 0 < len(kept.t) < 10**4


# ---------------------------------------------------------------------- the work directory
def _same_bits(a: Path, b: Path) -> None:
    ra, rb = ch.load_result(a), ch.load_result(b)
    p = ra.precision
    assert np.array_equal(p.to_text(ra.t).astype(str), p.to_text(rb.t).astype(str))
    for name in [*ra.variables, *ra.monitors]:
        assert np.array_equal(p.to_text(ra[name]).astype(str), p.to_text(rb[name]).astype(str))
    assert read_certificate(a)["digits_certified"] == read_certificate(b)["digits_certified"]


@pytest.fixture(scope="module")
def kept_work(tmp_path_factory) -> dict[str, Path]:
    """A reference of each route written with its work directory kept, and the file of the
    same command run once, uninterrupted."""
    from cayley_heyoka.cli import main

    d = tmp_path_factory.mktemp("kept")
    scene = d / "body.toml"
    scene.write_text(toml(BODY))
    made = {"scene": scene}
    for route in ("integrate", "closed-form"):
        out = d / f"{route}.h5"
        argv = [
            "reference", str(scene), "--digits", "8", "--certificate", route,
            "--checkpoints", "4", "--out", str(out), "--keep-work", "--no-progress",
            "--workers", "1",
        ]  # fmt: skip
        with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet):
            assert main(argv) == 0
        made[route] = out
    return made


def _resume(hostile, kept_work, tmp_path, route: str, damage, scene: Path | None = None):
    """Damage a copy of ``route``'s kept work directory, run the command again on it."""
    out = tmp_path / f"{route}.h5"
    shutil.copytree(Path(f"{kept_work[route]}.work"), Path(f"{out}.work"))
    work = Path(f"{out}.work") / ("run-double" if route == "integrate" else "closed-form-double")
    damage(work)
    argv = [
        "reference", str(scene or kept_work["scene"]), "--digits", "8", "--certificate", route,
        "--checkpoints", "4", "--out", str(out), "--no-progress", "--workers", "1",
    ]  # fmt: skip
    return out, work, argv


def _flip_last_byte(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[-20] ^= 0x01
    path.write_bytes(bytes(data))


def _edit_segment_value(work: Path) -> None:
    """A value of stretch 2 changed in the npz body, as numpy would rewrite it."""
    import io

    path = work / "segment-000002.ckpt"
    head, body = _split(path)
    with np.load(io.BytesIO(body)) as data:
        states, pars = data["states"].copy(), data["pars"]
    states[1, 0] += 1e-3
    buffer = io.BytesIO()
    np.savez(buffer, states=states, pars=pars)
    path.write_bytes(head + buffer.getvalue())


def _split(path: Path) -> tuple[bytes, bytes]:
    data = path.read_bytes()
    first = data.index(b"\n")
    second = data.index(b"\n", first + 1)
    return data[: second + 1], data[second + 1 :]


def _resealed_without_a_row(work: Path) -> None:
    """Stretch 2 with its last row dropped, written whole by a (buggy) writer of ours."""
    import io
    import json

    path = work / "segment-000002.ckpt"
    head, body = _split(path)
    header = json.loads(head.split(b"\n")[1].split(b" ", 1)[1])
    with np.load(io.BytesIO(body)) as data:
        states, pars = data["states"][:-1], data["pars"][:-1]
    buffer = io.BytesIO()
    np.savez(buffer, states=states, pars=pars)
    write_checkpoint(
        path, "segment", header["identity"], buffer.getvalue(), stretch=2, rows=len(states)
    )


def _edit_chunk_value(work: Path) -> None:
    path = sorted(work.glob("chunk-*.ckpt"))[3]
    head, body = _split(path)
    edited = body.replace(b'"0.', b'"0.1', 1)
    assert edited != body
    path.write_bytes(head + edited)


def _drop_chunk_row(work: Path) -> None:
    import json

    path = sorted(work.glob("chunk-*.ckpt"))[0]
    head, body = _split(path)
    rows = json.loads(body)
    header = json.loads(head.split(b"\n")[1].split(b" ", 1)[1])
    write_checkpoint(
        path, "closed-form chunk", header["identity"], json.dumps(rows[:-1]).encode(), chunk=0
    )


DAMAGED = {
    "integrate": {
        "a value edited in a segment": _edit_segment_value,
        "a segment resealed without a row": _resealed_without_a_row,
        "a segment cut short": lambda w: _truncate(w / "segment-000003.ckpt", 0.5),
        "a segment deleted": lambda w: (w / "segment-000001.ckpt").unlink(),
        "a segment replaced by a pickle": lambda w: (w / "segment-000002.ckpt").write_bytes(
            b"\x80\x04\x95\x05\x00\x00\x00\x00\x00\x00\x00K\x01."
        ),
        "the snapshot cut short": lambda w: _truncate(w / "snapshot.ckpt", 0.6),
        "the snapshot replaced by JSON": lambda w: (w / "snapshot.ckpt").write_text(
            '{"stretch": 4, "propagation": {}}'
        ),
        "a byte of the snapshot flipped": lambda w: _flip_last_byte(w / "snapshot.ckpt"),
        "the manifest deleted": lambda w: (w / "manifest.ckpt").unlink(),
        "the manifest damaged": lambda w: _truncate(w / "manifest.ckpt", 0.3),
    },
    "closed-form": {
        "a value edited in a chunk": _edit_chunk_value,
        "a chunk resealed without a row": _drop_chunk_row,
        "a chunk cut short": lambda w: _truncate(sorted(w.glob("chunk-*.ckpt"))[1], 0.5),
        "a chunk replaced by garbage": lambda w: sorted(w.glob("chunk-*.ckpt"))[2].write_bytes(
            b"\x00" * 300
        ),
    },
}


def _truncate(path: Path, fraction: float) -> None:
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])


@pytest.mark.covers("class:6", "verb:reference", "option:reference --checkpoints")
@pytest.mark.covers("option:reference --keep-work", "option:reference --certificate")
@pytest.mark.parametrize(("route", "case"), [(r, c) for r, cases in DAMAGED.items() for c in cases])
def test_damaged_work_directory_is_never_mixed_in(hostile, kept_work, tmp_path, route, case):
    """Whatever was done to the work directory, the file written has the bits of an
    uninterrupted reference (the damaged part is computed again), or the command refuses."""
    out, work, argv = _resume(hostile, kept_work, tmp_path, route, DAMAGED[route][case])
    o = hostile.run(argv, expect="done", out=out)
    _same_bits(out, kept_work[route])
    assert "Traceback" not in o.stderr
    if route == "integrate" and case != "the manifest deleted":
        assert "work directory: " in o.stdout and "not of this one" not in o.stdout
    assert not Path(f"{out}.work").exists()


@pytest.mark.covers("class:6", "verb:reference")
def test_another_scene_resumed_without_the_manifest_is_refused(hostile, kept_work, tmp_path):
    """The manifest deleted and the command run with another scene: the snapshot and the
    stretches are of the first scene, and are refused rather than written as the second's."""
    other = hostile.scene({**BODY, "initial": {"rates": ["1", "0.2", "0.25"]}})
    out, work, argv = _resume(
        hostile, kept_work, tmp_path, "integrate", lambda w: (w / "manifest.ckpt").unlink(), other
    )
    before = _entries(work)
    hostile.run(argv, expect="refused", field="holds another run")
    assert not out.exists() and _entries(work) == before  # left as it was


@pytest.mark.covers("class:6", "verb:reference")
def test_a_segment_of_another_run_is_refused(hostile, kept_work, tmp_path):
    """A stretch copied in from another run's work directory is named, not read."""

    def foreign(work: Path) -> None:
        path = work / "segment-000002.ckpt"
        _, body = _split(path)
        write_checkpoint(path, "segment", identity_of({"another": "run"}), body, stretch=2)

    out, work, argv = _resume(hostile, kept_work, tmp_path, "integrate", foreign)
    hostile.run(argv, expect="refused", field="segment-000002.ckpt")
    assert not out.exists()


@pytest.mark.covers("class:6", "verb:reference", "option:reference --out")
def test_two_references_on_one_out(hostile, tmp_path):
    """The second command on the same --out is refused at once, naming the first; the first
    goes on to write its file."""
    out = tmp_path / "r.h5"
    argv = _argv("reference", hostile, out)
    first = subprocess.Popen(
        [sys.executable, "-m", "cayley_heyoka.cli", *argv],
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = first.stdout.readline()  # "plan: ...": it holds the work directory now
        assert line.startswith("plan:"), line + first.stderr.read()
        first.send_signal(signal.SIGSTOP)
        o = hostile.run(argv, expect="refused", field="in use by another")
        assert f"process {first.pid}" in o.error_line
        first.send_signal(signal.SIGCONT)
        rest, err = first.communicate(timeout=120)
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    assert first.returncode == 0, err
    assert read_certificate(out)["certified"] and not Path(f"{out}.work").exists()


@pytest.mark.covers("class:6", "verb:reference")
def test_a_lock_left_by_a_killed_reference_does_not_block(hostile, tmp_path):
    out = tmp_path / "r.h5"
    argv = _argv("reference", hostile, out)
    work = Path(f"{out}.work")
    work.mkdir()
    (work / WORK_MARKER).write_text("")
    (work / WORK_LOCK).write_text("99999999\n")  # a process that is gone holds no flock
    hostile.run(argv, expect="done", out=out)
    assert not work.exists()


# ---------------------------------------------------------------------- rewritten by others
@pytest.mark.covers("class:12", "verb:info")
@pytest.mark.parametrize(("engine", "module"), [("h5netcdf", "h5netcdf"), ("netcdf4", "netCDF4")])
def test_a_file_rewritten_by_xarray_is_refused_as_such(hostile, tmp_path, engine, module):
    xr = pytest.importorskip("xarray")
    pytest.importorskip(module)
    ours = tmp_path / "r.h5"
    ch.run(ch.Scene.from_dict(BODY)).save(ours)
    rewritten = tmp_path / "rewritten.h5"
    with xr.open_dataset(ours, engine="h5netcdf") as ds:
        ds.load().to_netcdf(rewritten, engine=engine)
    o = hostile.run(["info", str(rewritten)], expect="refused", field="rewritten by another")
    assert str(rewritten) in o.error_line and "array" in o.error_line
