"""The hostile-input runner: run the command line on a case and classify how it ended.

Every case must end in one of four acceptable ways (README, "exit codes"):

``refused`` (exit 2)
    the last line of stderr is one ``error: ...`` line (naming the file, the field and the
    rule), nothing was integrated;
``stopped`` (exit 1)
    a clean stop that keeps its results (the ``--out`` file, if one was asked for, exists);
``interrupted`` (exit 130)
    Ctrl-C or SIGTERM; results kept as for ``stopped``;
``done`` (exit 0)
    a correct run: no ``nan`` in the printed summary, the ``--out`` file exists.

Anything else fails the case: an exception escaping ``main``, ``Traceback`` or heyoka's
``[warning]`` log lines in the output, another exit code, or a wall time beyond the case's
bound. The counts per class are printed at the end of the test session.

Use the ``hostile`` fixture::

    def test_something(hostile):
        scene = hostile.scene({"body": {...}, "output": {...}})  # or TOML text, or bytes
        hostile.run(["run", str(scene)], expect="refused", field="body.inertia")
        hostile.process(["run", str(scene), "--out", str(out)], send=signal.SIGINT,
                        wait_for="t/s", expect="interrupted", out=out)

``run`` calls ``cayley_heyoka.cli.main(argv)`` in this process with the output captured at
the file-descriptor level (so heyoka's C++ log lines are seen); ``process`` starts
``python -m cayley_heyoka.cli`` and, if ``send`` is given, sends that signal once
``wait_for`` (text or a compiled regular expression) appears in its stderr, ``delay`` seconds
later. Both return an
:class:`Outcome` after asserting the contract above, plus ``expect`` (a class or a set of
classes) and ``field`` (text that the refusal line must contain).
"""

from __future__ import annotations

import collections
import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from cayley_heyoka.cli import main

KINDS = {2: "refused", 1: "stopped", 130: "interrupted", 0: "done"}

#: Outcomes per class over the session (``FAILED`` for a broken contract).
TALLY: collections.Counter[str] = collections.Counter()


class Raw(str):
    """Text written into TOML as it is (a number kept as typed, or deliberately bad TOML)."""


@dataclass
class Outcome:
    """How one case ended."""

    argv: list[str]
    code: int | None
    stdout: str
    stderr: str
    seconds: float
    kind: str

    @property
    def error_line(self) -> str:
        """The refusal's (or stop's) ``error: ...`` line, '' if none."""
        lines = [ln for ln in self.stderr.splitlines() if "error: " in ln]
        return lines[-1] if lines else ""


class Hang(Exception):
    """A case ran past its time bound."""


def toml(data: Mapping[str, Any]) -> str:
    """A TOML document of ``data``: top-level keys, every nested table inline."""
    return "".join(f"{_key(k)} = {_value(v)}\n" for k, v in data.items())


def _key(k: str) -> str:
    return k if k and all(c.isalnum() or c in "_-" for c in k) else json.dumps(k)


def _value(v: Any) -> str:
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int | float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, Mapping):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(f"cannot write {v!r} as TOML")


class Runner:
    """The ``hostile`` fixture's object (see the module docstring)."""

    def __init__(self, tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
        self.tmp_path = tmp_path
        self._capfd = capfd
        self._n = 0

    def scene(self, content: Mapping[str, Any] | str | bytes, name: str | None = None) -> Path:
        """Write a scene file (a dict as TOML, text, or raw bytes) and return its path."""
        self._n += 1
        path = self.tmp_path / (name or f"scene{self._n}.toml")
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content if isinstance(content, str) else toml(content))
        return path

    def run(
        self,
        argv: list[str],
        *,
        expect: str | Iterable[str] | None = None,
        field: str | None = None,
        out: Path | None = None,
        seconds: float = 60.0,
    ) -> Outcome:
        """``cayley_heyoka.cli.main(argv)`` in this process; see the module docstring."""
        self._capfd.readouterr()
        old = signal.signal(signal.SIGALRM, _raise_hang)
        signal.alarm(int(seconds) + 1)
        t0 = time.perf_counter()
        escaped = None
        try:
            code = main(argv)
        except SystemExit as exc:  # argparse's own refusals
            code = exc.code if isinstance(exc.code, int) else 2
        except BaseException as exc:  # noqa: BLE001 -- the case fails, with the exception named
            code, escaped = None, exc
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, old)
        seconds_taken = time.perf_counter() - t0
        captured = self._capfd.readouterr()
        stderr = captured.err
        if escaped is not None:
            stderr += f"\n[escaped main: {type(escaped).__name__}: {escaped}]"
        outcome = Outcome(list(argv), code, captured.out, stderr, seconds_taken, "")
        return _judge(outcome, expect, field, out, seconds)

    def process(
        self,
        argv: list[str],
        *,
        send: int | None = None,
        wait_for: str | re.Pattern[str] | None = None,
        delay: float = 0.0,
        expect: str | Iterable[str] | None = None,
        field: str | None = None,
        out: Path | None = None,
        seconds: float = 120.0,
    ) -> Outcome:
        """``python -m cayley_heyoka.cli ARGV`` in a subprocess, optionally signalled."""
        env = {**os.environ, "PYTHONUNBUFFERED": "1"}
        t0 = time.perf_counter()
        proc = subprocess.Popen(
            [sys.executable, "-m", "cayley_heyoka.cli", *argv],
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        err_chunks: list[bytes] = []
        seen = threading.Event()
        pattern = re.compile(re.escape(wait_for)) if isinstance(wait_for, str) else wait_for

        def read_err() -> None:
            while chunk := proc.stderr.read1(4096):
                err_chunks.append(chunk)
                text = b"".join(err_chunks).decode(errors="replace")
                if pattern is None or pattern.search(text):
                    seen.set()
            seen.set()

        out_chunks: list[bytes] = []
        # Both pipes are read by threads (communicate() would race the stderr reader for data).
        readers = [
            threading.Thread(target=read_err, daemon=True),
            threading.Thread(target=lambda: out_chunks.append(proc.stdout.read()), daemon=True),
        ]
        for reader in readers:
            reader.start()
        try:
            if send is not None:
                if wait_for is not None:
                    seen.wait(timeout=seconds)
                time.sleep(delay)
                if proc.poll() is None:
                    proc.send_signal(send)
            code = proc.wait(timeout=seconds)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            code = None
        for reader in readers:
            reader.join(timeout=10)
        proc.stdout.close()
        proc.stderr.close()
        outcome = Outcome(
            list(argv),
            code,
            b"".join(out_chunks).decode(errors="replace"),
            b"".join(err_chunks).decode(errors="replace"),
            time.perf_counter() - t0,
            "",
        )
        return _judge(outcome, expect, field, out, seconds)


def _raise_hang(signum: int, frame: Any) -> None:
    raise Hang("the case ran past its time bound")


def _judge(
    o: Outcome,
    expect: str | Iterable[str] | None,
    field: str | None,
    out: Path | None,
    seconds: float,
) -> Outcome:
    """Classify ``o`` and assert the contract of the module docstring."""
    problems = []
    text = o.stdout + o.stderr
    if o.code not in KINDS:
        problems.append(f"exit code {o.code}")
    if "Traceback" in text or "[escaped main" in text:
        problems.append("a traceback or an exception escaping main")
    if "[warning]" in text:
        problems.append("heyoka's log lines leaked")
    if o.seconds > seconds:
        problems.append(f"took {o.seconds:.1f} s (bound {seconds} s)")
    kind = KINDS.get(o.code, "")
    if kind == "refused":
        last = o.stderr.strip().splitlines()[-1] if o.stderr.strip() else ""
        if "error: " not in last:
            problems.append("a refusal without an 'error: ...' line last on stderr")
        if field is not None and field not in last:
            problems.append(f"the refusal does not name {field!r}")
    # The summary's first line is the scene's title, which may say anything.
    if kind == "done" and "nan" in " ".join(o.stdout.lower().splitlines()[1:]).split():
        problems.append("nan in a completed run's summary")
    if kind in ("done", "stopped", "interrupted") and out is not None and not out.exists():
        problems.append(f"{out.name} was not written")
    if expect is not None:
        allowed = {expect} if isinstance(expect, str) else set(expect)
        if kind not in allowed:
            problems.append(f"ended {kind or 'badly'}, expected {' or '.join(sorted(allowed))}")
    o.kind = "FAILED" if problems else kind
    TALLY[o.kind] += 1
    if problems:
        pytest.fail(
            f"{' '.join(o.argv)}: {'; '.join(problems)}\n--- stdout\n{o.stdout[-2000:]}"
            f"\n--- stderr\n{o.stderr[-4000:]}",
            pytrace=False,
        )
    return o


@pytest.fixture
def hostile(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> Runner:
    """The runner of the module docstring, writing its files under ``tmp_path``."""
    return Runner(tmp_path, capfd)


def pytest_sessionfinish(session: pytest.Session) -> None:
    """A pytest-xdist worker hands its tally to the controller, which prints the sum
    (tests/conftest.py)."""
    output = getattr(session.config, "workeroutput", None)
    if output is not None:
        output["hostile_tally"] = dict(TALLY)


def pytest_terminal_summary(terminalreporter: Any) -> None:
    if TALLY:
        counts = ", ".join(f"{k} {v}" for k, v in sorted(TALLY.items()))
        terminalreporter.write_line(f"hostile-input cases: {counts}")
