"""Ctrl-C and SIGTERM around heyoka's C++ calls: noted during a propagation and acted on
after the current step (:class:`DeferredSignals`, :class:`Watch`, the thread the main thread's
propagations run in), or, during an LLVM compilation, ending the process at once
(:func:`signals_end_compilation`)."""

from __future__ import annotations

import contextlib
import queue
import signal
import threading
from collections.abc import Callable, Iterator
from typing import Any

_END_ON_SIGNAL = 0


SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def signals_end_compilation() -> Iterator[None]:
    """Within this context, SIGINT or SIGTERM during an LLVM compilation ends the process.

    LLVM compiles in C++ without returning to Python, so Python's handlers (Ctrl-C's
    KeyboardInterrupt) would run only when it is done — after seconds or minutes. Nothing is
    computed before the compilation, so for a command-line process ending at once loses
    nothing; the signals get their default disposition while compiling, Python's handlers
    back afterwards. Only in the main thread.
    """
    global _END_ON_SIGNAL
    _END_ON_SIGNAL += 1
    try:
        yield
    finally:
        _END_ON_SIGNAL -= 1


@contextlib.contextmanager
def signals_end_process() -> Iterator[None]:
    if not _END_ON_SIGNAL or threading.current_thread() is not threading.main_thread():
        yield
        return
    old = {sig: signal.signal(sig, signal.SIG_DFL) for sig in SIGNALS}
    try:
        yield
    finally:
        for sig, handler in old.items():
            signal.signal(sig, handler)


class DeferredSignals:
    """Within the context (in the main thread), SIGINT and SIGTERM handled by Python are only
    noted (and ``on_signal`` called); the propagation then ends after the current step.

    Python runs a signal's handler only between bytecodes of the main thread, so while heyoka
    steps there nothing would note it. Two ways out: a Python callback after each step
    (:meth:`callback`: it cost 6–18 % of the wall time of cheap double steps, the free body's
    ~1 µs, nothing measurable in quad), or heyoka stepping in another thread while the main
    thread waits in Python (:class:`Watch`, double precision: no cost measurable,
    ``python validation/interrupt_cost.py``).
    """

    def __init__(self, on_signal: Callable[[], None] | None = None) -> None:
        self.received = ""
        self.on_signal = on_signal
        self._old: dict[int, Any] = {}

    @property
    def active(self) -> bool:
        """Whether signals are being noted (the context is entered in the main thread)."""
        return bool(self._old)

    def callback(self, ta: Any) -> bool:
        return not self.received

    def _note(self, signum: int, frame: Any) -> None:
        self.received = signal.Signals(signum).name
        if self.on_signal is not None:
            self.on_signal()

    def __enter__(self) -> DeferredSignals:
        if threading.current_thread() is threading.main_thread():
            for sig in SIGNALS:
                old = signal.getsignal(sig)
                if callable(old):  # SIG_DFL and SIG_IGN keep their meaning
                    self._old[sig] = signal.signal(sig, self._note)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        self._old.clear()


class Watch:
    """Propagations of the main thread run here, in one long-lived thread, while the main
    thread waits in Python, where its signal handlers run at once.

    A noted signal then sets the parameters that the right-hand sides use to NaN: the step
    under way becomes non-finite, and heyoka returns the outputs of the whole steps before it
    (``err_nf_state``; the rows it returns are the uninterrupted run's). The engine restores
    the parameters and reports the interruption. No callback runs after each step, so an
    uninterrupted run costs what a run in any other thread does (measured:
    ``python validation/interrupt_cost.py``). Double precision with runtime parameters only;
    other runs keep the per-step callback.
    """

    def __init__(self) -> None:
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def run(self, job: Callable[[], None], stop: Callable[[], None]) -> None:
        """Run ``job`` in the watch's thread and wait for it; re-raise what it raised.

        ``stop`` is called if the wait itself is interrupted (an exception raised by another
        signal handler): the job is stopped and waited for before the exception goes on, so
        that nothing steps the integrator behind the caller's back.
        """
        with self._lock:
            if self._thread is None or not self._thread.is_alive():
                self._thread = threading.Thread(
                    target=self._serve, name="cayley_heyoka-propagation", daemon=True
                )
                self._thread.start()
        done = threading.Event()
        box: dict[str, BaseException] = {}
        self._jobs.put((job, done, box))
        try:
            while not done.wait(0.25):
                pass
        except BaseException:
            stop()
            done.wait()
            raise
        if "error" in box:
            raise box["error"]

    def _serve(self) -> None:
        while True:
            job, done, box = self._jobs.get()
            try:
                job()
            except BaseException as exc:  # handed to the waiting caller
                box["error"] = exc
            finally:
                done.set()


WORKER = Watch()


@contextlib.contextmanager
def held_signals() -> Iterator[None]:
    """Within this context (in the main thread), SIGINT and SIGTERM are noted, not acted on;
    after it they are delivered again, each once, to whatever handles them then.

    For a write that must finish once begun (:func:`cayley_heyoka.core.files.write_bytes`): a
    Ctrl-C during it arrives after the file is in place, as a KeyboardInterrupt from the end
    of the context. A signal left at its default disposition (SIGTERM outside the command
    line) is held too, and then ends the process after the write; an ignored one stays
    ignored. When the context ends by an exception, which already ends the work, a noted
    signal is not delivered again. Contexts nest: an inner one hands its signals to the outer.
    """
    if threading.current_thread() is not threading.main_thread():
        yield  # Python delivers signals to the main thread only: nothing interrupts this one
        return
    noted: list[int] = []

    def note(signum: int, frame: Any) -> None:
        if signum not in noted:
            noted.append(signum)

    old = {}
    for sig in SIGNALS:
        handler = signal.getsignal(sig)
        if handler is not signal.SIG_IGN and handler is not None:
            old[sig] = signal.signal(sig, note)
    try:
        yield
    except BaseException:
        for sig, handler in old.items():
            signal.signal(sig, handler)
        raise
    for sig, handler in old.items():
        signal.signal(sig, handler)
    for signum in noted:
        signal.raise_signal(signum)
