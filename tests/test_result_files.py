"""Our files on disk: destinations checked first, atomic saves, checksums, old versions read.

The policy is in cayley_heyoka/core/files.py and docs/scenes.md ("Files").
"""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import h5py
import numpy as np
import pytest
from helpers import free_body

from cayley_heyoka import Result, Scene, run
from cayley_heyoka.cli import main
from cayley_heyoka.cli.terminal import printable
from cayley_heyoka.core.consistency import CheckReport, CheckRow
from cayley_heyoka.core.files import (
    DIGEST,
    FORMAT_VERSION,
    OutputError,
    ResultFileError,
    check_destination,
    identify,
    seal,
    write_bytes,
)
from cayley_heyoka.workflows.reference import WORK_MARKER, generate_reference, read_certificate
from cayley_heyoka.workflows.sweep_result import load_sweep

DATA = Path(__file__).resolve().parent / "data" / "files"


@pytest.fixture(scope="module")
def result() -> Result:
    return run(Scene.from_dict(free_body(output={"events": ["invariable_plane"]})))


@pytest.fixture(scope="module")
def quad_result() -> Result:
    return run(Scene.from_dict(free_body(integrator={"precision": "quad"})))


def same(a: Result, b: Result) -> bool:
    """Bit-for-bit equal results (their numbers as exact text)."""
    p = a.precision
    if b.precision != p or list(a.variables) != list(b.variables):
        return False
    pairs = [(a.t, b.t), *((a.variables[k], b.variables[k]) for k in a.variables)]
    return all(np.array_equal(p.to_text(x).astype(str), p.to_text(y).astype(str)) for x, y in pairs)


# ---------------------------------------------------------------------- save and load
@pytest.mark.parametrize("which", ["result", "quad_result"])
def test_saved_files_carry_version_and_checksum_and_load_exactly(request, tmp_path, which):
    res = request.getfixturevalue(which)
    path = tmp_path / "r.h5"
    res.save(path)
    with h5py.File(path) as f:
        assert f.attrs["format_version"] == FORMAT_VERSION == 3
        assert len(f.attrs[DIGEST]) == 64
    assert same(Result.load(path), res)
    assert identify(path) == "result"
    assert [p.name for p in tmp_path.iterdir()] == ["r.h5"]  # no temporary left


def test_files_of_format_version_1_still_load():
    double = Result.load(DATA / "result_v1_double.h5")
    quad = Result.load(DATA / "result_v1_quad.h5")
    for res, kind in ((double, "double"), (quad, "quad")):
        assert res.precision.kind == kind and res.success
        assert [float(t) for t in res.t] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]
        assert res.final_drifts()["energy"] < 1e-13
    # The same body in two precisions: the double run agrees with quad to double's accuracy.
    assert abs(float(double["p"][-1]) - float(quad["p"][-1])) < 1e-13
    ref = Result.load(DATA / "reference_v1.h5")
    assert ref.metadata["reference"]["certified"]
    assert read_certificate(DATA / "reference_v1.h5")["digits_requested"] == 8
    sweep = load_sweep(DATA / "sweep_v1.h5")
    assert len(sweep) == 3 and sweep.completed.all()
    check = CheckReport.load(DATA / "check_v1.h5")
    assert check.passed and check.rows
    assert identify(DATA / "check_v1.h5") == "check"


def test_files_of_format_version_2_still_load():
    """Format 2 (groups ``variables`` and ``monitors``, times ``t``, checksummed) is read as
    written: the same scene as the version-1 files, so the same values."""
    double = Result.load(DATA / "result_v2_double.h5")
    quad = Result.load(DATA / "result_v2_quad.h5")
    old = Result.load(DATA / "result_v1_double.h5")
    assert double.precision.kind == "double" and quad.precision.kind == "quad"
    for name in old.variables:
        assert np.array_equal(double[name], old[name])
    assert abs(float(double["p"][-1]) - float(quad["p"][-1])) < 1e-13
    assert len(double.events["invariable_plane"]) == len(quad.events["invariable_plane"]) > 0
    ref = Result.load(DATA / "reference_v2.h5")
    assert ref.metadata["reference"]["certified"]
    assert read_certificate(DATA / "reference_v2.h5")["digits_requested"] == 8
    sweep = load_sweep(DATA / "sweep_v2.h5")
    assert len(sweep) == 3 and sweep.completed.all()
    # Version 1 came from heyoka's ensemble path, version 2 from the lanes: a few ulps apart.
    np.testing.assert_allclose(
        sweep.final_state, load_sweep(DATA / "sweep_v1.h5").final_state, rtol=0, atol=1e-15
    )


def test_check_files_round_trip(tmp_path):
    report = CheckReport(
        "t", tuple(CheckRow(f"q{i}", i * 1e-17, 1e-15) for i in range(12)), {"t": np.arange(3.0)}
    )
    report.save(tmp_path / "c.h5")
    back = CheckReport.load(tmp_path / "c.h5")
    assert [r.quantity for r in back.rows] == [f"q{i}" for i in range(12)]
    assert back.passed and np.array_equal(back.series["t"], [0.0, 1.0, 2.0])


def test_garbage_in_the_middle_is_refused_not_read_as_nan(tmp_path):
    res = run(Scene.from_dict(free_body(output={"times": {"start": 0, "stop": 10, "count": 3000}})))
    path = tmp_path / "r.h5"
    res.save(path)
    size = path.stat().st_size
    with open(path, "r+b") as f:
        f.seek(size // 2)
        f.write(np.random.default_rng(1).bytes(4096))
    with pytest.raises(ResultFileError, match="damaged") as info:
        Result.load(path)
    assert info.value.path == path


def test_a_changed_attribute_is_detected(tmp_path, result):
    path = tmp_path / "r.h5"
    result.save(path)
    with h5py.File(path, "a") as f:
        f.attrs["message"] = "something else"
    with pytest.raises(ResultFileError, match="do not match the checksum"):
        Result.load(path)


def test_bad_contents_under_a_valid_checksum_are_named(tmp_path, result):
    path = tmp_path / "r.h5"
    for damage, what in (
        (lambda f: f.attrs.__setitem__("metadata", "{not json"), "damaged or incomplete"),
        (lambda f: f.move("time", "times"), "damaged or incomplete"),
        (lambda f: f.attrs.__setitem__("format_version", 99), "newer than this library"),
        (lambda f: f.attrs.__delitem__(DIGEST), "not completely written"),
    ):
        result.save(path)
        with h5py.File(path, "a") as f:
            damage(f)
            if DIGEST in f.attrs:
                seal(f)
        with pytest.raises(ResultFileError, match=what):
            Result.load(path)


def test_unreadable_files_raise_result_file_error(tmp_path):
    (tmp_path / "empty.h5").write_bytes(b"")
    (tmp_path / "text.h5").write_text("thesis\n")
    with h5py.File(tmp_path / "foreign.h5", "w") as f:
        f["x"] = [1.0]
    cases = {
        "missing.h5": "no such file",
        "empty.h5": "empty file",
        "text.h5": "not an HDF5 file",
        "foreign.h5": "without a format attribute",
        ".": "is a directory",
    }
    for name, what in cases.items():
        with pytest.raises(ResultFileError, match=what):
            Result.load(tmp_path / name)
    with pytest.raises(ResultFileError, match="a sweep file, not a result file"):
        Result.load(DATA / "sweep_v1.h5")


# ---------------------------------------------------------------------- destinations
def test_destination_policy(tmp_path, result):
    ours, thesis = tmp_path / "ours.h5", tmp_path / "thesis.txt"
    result.save(ours)
    thesis.write_text("chapter 1\n")
    check_destination(tmp_path / "new.h5", "result")
    check_destination(ours, "result")  # ours, same kind: replaced without asking
    refusals = {
        (thesis, "result"): "not one of ours.*--overwrite",
        (ours, "sweep"): "a result file of ours, not a sweep file",
        (tmp_path / "nowhere" / "r.h5", "result"): "does not exist",
        (tmp_path, "result"): "is a directory",
        (thesis / "r.h5", "result"): "is not a directory",
    }
    for (path, kind), what in refusals.items():
        with pytest.raises(OutputError, match=what):
            check_destination(path, kind)
    check_destination(thesis, "result", overwrite=True)
    assert thesis.read_text() == "chapter 1\n"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_directory_is_refused(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        with pytest.raises(OutputError, match="not writable"):
            check_destination(locked / "r.h5", "result")
    finally:
        locked.chmod(0o755)


def test_symlinks_are_followed_to_their_target(tmp_path, result):
    target = tmp_path / "runs" / "r.h5"
    target.parent.mkdir()
    result.save(target)
    link = tmp_path / "latest.h5"
    link.symlink_to(target)
    check_destination(link, "result")
    result.save(link)
    assert link.is_symlink() and Result.load(target).success
    (tmp_path / "secret").write_text("keep\n")
    (tmp_path / "trap.h5").symlink_to(tmp_path / "secret")
    with pytest.raises(OutputError, match="not one of ours"):
        check_destination(tmp_path / "trap.h5", "result")
    (tmp_path / "dangling.h5").symlink_to(tmp_path / "gone" / "r.h5")
    with pytest.raises(OutputError, match="does not exist"):
        check_destination(tmp_path / "dangling.h5", "result")


# ---------------------------------------------------------------------- atomic writes
def test_a_failed_write_leaves_the_previous_file_and_no_temporary(tmp_path, result, monkeypatch):
    from cayley_heyoka.core import files

    path = tmp_path / "r.h5"
    result.save(path)
    before = path.read_bytes()
    real = os.write

    def full_disk(fd: int, data: bytes) -> int:
        if len(data) > 100:
            return real(fd, bytes(data[:100]))  # half a file, then no room
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "write", full_disk)
    with pytest.raises(OutputError, match="No space left on device"):
        write_bytes(path, b"x" * 1000)
    with pytest.raises(OutputError, match="No space left on device"):
        result.save(path)
    monkeypatch.setattr(files.os, "write", lambda fd, data: _raise(KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        write_bytes(path, b"x")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5"]


def _raise(exc: BaseException) -> None:
    raise exc


def test_run_on_a_full_disk_says_so_and_keeps_the_previous_file(
    tmp_path, capsys, monkeypatch, result
):
    scene = tmp_path / "s.toml"
    scene.write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [1, 0.1, 0.2]\n"
        "[output]\ntimes = [0, 1]\n"
    )
    out = tmp_path / "r.h5"
    # The previous file is this scene's (another scene's result is not replaced at all).
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    before = out.read_bytes()

    def full_disk(self: Result, f: h5py.File) -> None:
        f["t"] = np.zeros(1000)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Result, "fill", full_disk)
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 1
    captured = capsys.readouterr()
    assert "completed" in captured.out  # the summary is still shown
    assert f"error: {out}: could not be written (No space left on device)" in captured.err
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5", "s.toml"]


_TEXT = {"text": True, "capture_output": True, "check": True}


def test_temporaries_of_dead_processes_are_removed(tmp_path, result):
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], **_TEXT)
    dead = gone.stdout.strip()
    stale = tmp_path / f".r.h5.tmp-{dead}"
    live = tmp_path / f".r.h5.tmp-{os.getppid()}"  # a process that still runs: not touched
    stale.write_bytes(b"killed mid-save")
    live.write_bytes(b"someone else's")
    result.save(tmp_path / "r.h5")
    assert not stale.exists() and live.exists()


# A child that starts a save, says so once the new file is written but not yet in place,
# and waits.
_SLOW_SAVE = textwrap.dedent(
    """
    import os, sys, time
    from cayley_heyoka import load_result
    from cayley_heyoka.core import files

    res = load_result(sys.argv[1])
    real = os.fsync

    def slow_fsync(fd):
        real(fd)
        print("writing", flush=True)
        time.sleep(60)

    files.os.fsync = slow_fsync
    res.save(sys.argv[2])
    """
)


def test_sigkill_during_a_save_keeps_the_previous_file(tmp_path, result, quad_result):
    path, source = tmp_path / "r.h5", tmp_path / "source.h5"
    result.save(path)
    quad_result.save(source)
    child = subprocess.Popen(
        [sys.executable, "-c", _SLOW_SAVE, str(source), str(path)],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "writing"
        tmp = tmp_path / f".r.h5.tmp-{child.pid}"
        assert tmp.stat().st_size > 0
        child.send_signal(signal.SIGKILL)
    finally:
        child.wait(timeout=30)
    assert child.returncode == -signal.SIGKILL
    assert same(Result.load(path), result)  # the previous file, whole
    assert tmp.read_bytes()[:4] == b"\x89HDF"  # the killed save's temporary, left whole
    quad_result.save(path)  # the next save cleans up after the killed one
    assert same(Result.load(path), quad_result)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.h5", "source.h5"]


def test_sweep_whose_file_cannot_be_written_keeps_the_previous_one(tmp_path, capsys, monkeypatch):
    from cayley_heyoka.core import files

    (tmp_path / "body.toml").write_text(
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [1, 0.1, 0.2]\n"
        "[output]\ntimes = [0, 1]\n"
    )
    (tmp_path / "study.toml").write_text(
        'scene = "body.toml"\n[sweep]\nkind = "grid"\n[sweep.parameters]\n'
        '"initial.rates[0]" = { start = 0.5, stop = 1.0, count = 4 }\n'
        '[run]\nbackend = "local"\n'
    )
    out = tmp_path / "sweep.h5"
    out.write_bytes((DATA / "sweep_v1.h5").read_bytes())

    def full_disk(fd: int, data: bytes) -> int:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(files.os, "write", full_disk)
    # --overwrite: the file there is another study's sweep.
    argv = ["sweep", str(tmp_path / "study.toml"), "--out", str(out), "--chunk", "2"]
    assert main([*argv, "--no-progress", "--overwrite"]) == 1
    captured = capsys.readouterr()
    assert "No space left on device); nothing changed" in captured.err
    assert "4 completed" in captured.out  # what was computed is shown
    assert out.read_bytes() == (DATA / "sweep_v1.h5").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["body.toml", "study.toml", "sweep.h5"]


# ---------------------------------------------------------------------- reference work dirs
def _reference_scene() -> Scene:
    return Scene.from_dict(free_body(output={"times": {"start": 0, "stop": 1, "count": 3}}))


def test_reference_removes_only_what_it_wrote(tmp_path):
    out = tmp_path / "ref.h5"
    work = tmp_path / "ref.h5.work"
    work.mkdir()
    (work / WORK_MARKER).write_text("")
    (work / "notes.txt").write_text("mine\n")
    (work / "run-double").mkdir()
    (work / "run-double" / "plot.png").write_bytes(b"mine too")
    outcome = generate_reference(_reference_scene(), 8, out, stretches=2)
    assert outcome.certified
    left = sorted(str(p.relative_to(work)) for p in work.rglob("*"))
    assert left == ["notes.txt", "run-double", "run-double/plot.png"]


def test_reference_refuses_a_work_directory_it_did_not_make(tmp_path):
    work = tmp_path / "ref.h5.work"
    work.mkdir()
    (work / "thesis.tex").write_text("\\chapter{}\n")
    with pytest.raises(OutputError, match="not made by"):
        generate_reference(_reference_scene(), 8, tmp_path / "ref.h5", stretches=2)
    assert sorted(p.name for p in work.iterdir()) == ["thesis.tex"]
    assert not (tmp_path / "ref.h5").exists()


def test_reference_leaves_no_work_directory_when_it_made_it(tmp_path):
    generate_reference(_reference_scene(), 8, tmp_path / "ref.h5", stretches=2)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ref.h5"]


# ---------------------------------------------------------------------- the command line
def test_run_refuses_its_destination_before_integrating(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text("this is not even TOML")  # never read: the destination is refused first
    thesis = tmp_path / "thesis.txt"
    thesis.write_text("chapter 1\n")
    assert main(["run", str(scene), "--out", str(thesis)]) == 2
    err = capsys.readouterr().err
    assert f"error: {thesis}: exists" in err and "--overwrite" in err
    assert thesis.read_text() == "chapter 1\n"


def test_titles_cannot_drive_the_terminal(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(
        'title = "\\u001b]0;pwned\\u0007\\u001b[2Jplain\\u202eevil"\n'
        "[body]\ninertia = [1, 1.5, 2.5]\n[initial]\nrates = [1, 0.1, 0.2]\n"
        "[output]\ntimes = [0, 1]\n"
    )
    out = tmp_path / "r.h5"
    assert main(["run", str(scene), "--out", str(out), "--no-progress"]) == 0
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    assert "\x1b" not in text and "\x07" not in text and "\u202e" not in text
    assert "\\x1b]0;pwned\\x07\\x1b[2Jplain\\u202eevil" in text
    assert printable("a\tb\nc\rd") == "a\tb\nc\\x0dd"


def test_info_summarises_every_kind_of_our_files(capsys):
    expected = {
        "result_v1_quad.h5": "Free body, small",
        "reference_v1.h5": "reference     certified",
        "sweep_v1.h5": "3 completed",
        "check_v1.h5": "passed",
    }
    for name, text in expected.items():
        assert main(["info", str(DATA / name)]) == 0
        assert text in capsys.readouterr().out


def test_info_piped_into_head_ends_quietly(tmp_path):
    # `info FILE | head -0`: the reader is gone before anything is printed.
    proc = subprocess.Popen(
        [sys.executable, "-m", "cayley_heyoka.cli", "info", str(DATA / "sweep_v1.h5")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    proc.stdout.close()
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 0  # info's own exit code: the report was cut, not the work
    assert err == ""


def test_version_names_both_packages(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    assert text.startswith("cayley-heyoka ") and "(heyoka 7." in text
