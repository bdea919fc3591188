"""Hostile moments and streams: a signal at any moment of start-up, and standard streams that
are closed, full or cut.

Before any work (parsing, imports, compiling) SIGINT or SIGTERM ends the command at once:
exit 130, ``interrupted (SIG...): nothing was computed``, no traceback, nothing written. The
moments are found from outside, in ``/proc``: the policy's SIGTERM handler installed
(``SigCgt``), heyoka's extension mapped (it then imports sympy), the progress bar drawn before
a compilation of minutes. A report that cannot be printed (stdout or stderr closed, stdout
full; a pipe whose reader has gone: tests/test_result_files.py) changes neither the exit code
nor ``--out``. Each case ends as conftest.py requires.
"""

from __future__ import annotations

import errno
import io
import os
import re
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from conftest import Outcome, _judge
from helpers import SLOW_COMPILE, SMALL_BODY

from cayley_heyoka import load_result

# Non-compact quad of a long potential: LLVM compiles it for minutes.

CLI = [sys.executable, "-m", "cayley_heyoka.cli"]


def _caught(pid: int) -> int:
    """The process's mask of caught signals (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("SigCgt:"):
                    return int(line.split()[1], 16)
    except FileNotFoundError:
        pass
    return 0


def _policy_installed(pid: int) -> bool:
    # Python catches SIGINT by itself; SIGTERM only once main's policy is installed.
    return bool(_caught(pid) & (1 << (signal.SIGTERM - 1)))


def _heyoka_mapped(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/maps") as f:
            return "heyoka/_core" in f.read()
    except FileNotFoundError:
        return True


def _signalled(
    argv: list[str], sig: int, ready: Callable[[int], bool], delay: float, seconds: float = 60
) -> Outcome:
    """Run the command line, send ``sig`` ``delay`` seconds after ``ready(pid)``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen([*CLI, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        while proc.poll() is None and not ready(proc.pid):
            if time.perf_counter() - t0 > seconds:
                break
            time.sleep(0.002)
        time.sleep(delay)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=seconds)
    finally:
        proc.kill()
        proc.wait()
    return Outcome(argv, proc.returncode, out.decode(), err.decode(), time.perf_counter() - t0, "")


def _ended_before_any_work(o: Outcome, sig: int, tmp_path: Path, scene: Path) -> None:
    _judge(o, "interrupted", None, None, 60)
    assert f"interrupted ({signal.Signals(sig).name}): nothing was computed" in o.stderr
    assert [p.name for p in tmp_path.iterdir()] == [scene.name], "something was written"


@pytest.mark.covers("class:8", "verb:run")
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_as_main_starts_ends_the_command_at_once(hostile, tmp_path, sig):
    """Sent as soon as main's policy is in place: the imports have not begun."""
    scene = hostile.scene(SMALL_BODY)
    argv = ["run", str(scene), "--out", str(tmp_path / "r.h5"), "--no-progress"]
    o = _signalled(argv, sig, _policy_installed, 0.0)
    _ended_before_any_work(o, sig, tmp_path, scene)


@pytest.mark.covers("class:8", "verb:run")
@pytest.mark.parametrize(("sig", "delay"), [(signal.SIGINT, 0.1), (signal.SIGTERM, 0.2)])
def test_a_signal_while_heyoka_imports_sympy_ends_the_command_at_once(
    hostile, tmp_path, sig, delay
):
    """A KeyboardInterrupt raised inside this import gave 'ImportError: initialization failed'
    or "module 'sympy' has no attribute 'core'" tracebacks, or was swallowed (the run went on)."""
    scene = hostile.scene(SMALL_BODY)
    argv = ["run", str(scene), "--out", str(tmp_path / "r.h5"), "--no-progress"]
    o = _signalled(argv, sig, _heyoka_mapped, delay)
    _ended_before_any_work(o, sig, tmp_path, scene)


@pytest.mark.covers("class:8", "verb:run", "option:run --progress")
def test_a_signal_while_llvm_compiles_ends_the_command_at_once(hostile, tmp_path):
    """LLVM does not return to Python for minutes; SIGTERM killed the process (-15).
    (SIGINT too: tests/test_engine_limits.py.)"""
    sig = signal.SIGTERM
    V = " + ".join(f"{i}*sin(R33*{i % 7 + 1})*cos(R13*{i % 5 + 1})" for i in range(1, 120))
    scene = hostile.scene(SLOW_COMPILE.format(V=V))
    out = tmp_path / "r.h5"
    # The bar is drawn once the scene is loaded, just before the model is built and compiled.
    o = hostile.process(
        ["run", str(scene), "--out", str(out), "--progress"],
        send=sig,
        wait_for=re.compile(r"\b0%"),
        delay=1.0,
        expect="interrupted",
        seconds=60,
    )
    assert f"interrupted ({signal.Signals(sig).name}): nothing was computed" in o.stderr
    assert [p.name for p in tmp_path.iterdir()] == [scene.name]


# ------------------------------------------------------------- standard streams


def _with_streams(argv: list[str], shell: str) -> Outcome:
    """Run the command line after ``shell`` redirections (``exec >&-``: stdout closed)."""
    t0 = time.perf_counter()
    command = " ".join(["exec", *(f"'{a}'" for a in [*CLI, *argv])])
    proc = subprocess.run(
        ["sh", "-c", f"{shell}; {command}"], capture_output=True, text=True, timeout=120
    )
    return Outcome(argv, proc.returncode, proc.stdout, proc.stderr, time.perf_counter() - t0, "")


@pytest.fixture(scope="module")
def result_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    import cayley_heyoka as ch

    out = tmp_path_factory.mktemp("result") / "r.h5"
    ch.run(ch.Scene.from_toml(SMALL_BODY)).save(out)
    return out


@pytest.mark.covers("class:12", "verb:run", "option:run --out")
def test_run_with_every_standard_stream_closed_writes_its_result(hostile, tmp_path):
    """stdout closed: 'NoneType' object has no attribute 'write', exit 1. With all three
    closed the result file took descriptor 1, where C++ logs write: it must be whole."""
    out = tmp_path / "r.h5"
    argv = ["run", str(hostile.scene(SMALL_BODY)), "--out", str(out), "--no-progress"]
    _judge(_with_streams(argv, "exec <&- >&- 2>&-"), "done", None, out, 120)
    assert len(load_result(out).t) == 3


@pytest.mark.covers("class:12", "verb:info")
def test_info_with_stdout_closed_ends_as_it_would(result_file):
    _judge(_with_streams(["info", str(result_file)], "exec >&-"), "done", None, None, 120)


@pytest.mark.covers("class:12", "verb:run")
def test_a_refusal_with_stderr_closed_still_exits_2(tmp_path):
    """Printing the refusal to a closed stderr raised, and the command exited 1."""
    o = _with_streams(["run", str(tmp_path / "missing.toml")], "exec 2>&-")
    assert o.code == 2, o


class _Full(io.TextIOBase):
    """A stdout on a full disk (``> /dev/full``): every write fails with ENOSPC."""

    def writable(self) -> bool:
        return True

    def write(self, text: str) -> int:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@pytest.mark.covers("class:12", "verb:check", "verb:sweep", "option:sweep --out")
@pytest.mark.parametrize("verb", ["check", "sweep"])
def test_a_full_stdout_changes_nothing_but_the_report(hostile, tmp_path, monkeypatch, verb):
    """'OSError: [Errno 28] No space left on device' escaped main; the work is kept and said
    to be unreported, once, on stderr."""
    scene = hostile.scene(SMALL_BODY, "free.toml")
    out = None
    argv = ["check", str(scene)]
    if verb == "sweep":
        study = hostile.scene(
            'scene = "free.toml"\n[sweep]\nkind = "grid"\n[sweep.parameters]\n'
            '"initial.rates[0]" = [0.1, 0.2]\n'
        )
        out = tmp_path / "s.h5"
        argv = ["sweep", str(study), "--out", str(out), "--no-progress"]
    monkeypatch.setattr(sys, "stdout", _Full())
    o = hostile.run(argv, expect="done", out=out)
    assert o.stderr.count("warning: stdout could not be written: [Errno 28]") == 1


@pytest.mark.covers("class:8")
def test_a_signal_a_handler_took_is_not_acted_on_again_once_the_work_is_done(monkeypatch):
    """The policy's watching thread reads every signal's byte from the wakeup pipe, perhaps
    late on a busy machine: one that a handler already took during the work (a write held it
    and re-raised it) must not end the process once the report is printing. (It did, in an
    in-process hostile case: the pytest worker died, 'node down: Not properly terminated'.)"""
    from cayley_heyoka.core import signals

    policy = signals.SignalPolicy()
    ended: list[int] = []
    monkeypatch.setattr(policy, "_end", ended.append)
    monkeypatch.setattr(signals.signal, "getsignal", lambda signum: policy._handler)
    policy.installed, policy.phase = True, "done"

    def watch(handled: int) -> list[int]:
        ended.clear()
        policy.handled, policy._arrived = handled, 0
        r, w = os.pipe()
        os.write(w, bytes([signal.SIGINT]))
        os.close(w)
        policy._watch(r)  # returns at the end of the pipe
        os.close(r)
        return list(ended)

    assert watch(handled=1) == []  # taken during the work: not the watcher's
    assert watch(handled=0) == [signal.SIGINT]  # the main thread busy in C: ends the process
