"""Ctrl-C and SIGTERM: one policy for the command line, from the first line of its ``main``.

:func:`command_signals` holds it for the life of a command. Two phases:

* **Before any work** (parsing, imports, loading the scene, compiling): nothing has been
  computed or written, so either signal ends the process at once, exit 130, printing
  ``interrupted (SIGINT): nothing was computed``. No KeyboardInterrupt is raised there: one
  raised inside an import leaves modules half-imported (``module 'sympy' has no attribute
  'core'`` later) or is swallowed by the C code that imports, and LLVM compiles without
  returning to Python for seconds to minutes. A thread woken by the signal's byte on
  :func:`signal.set_wakeup_fd` acts at once, also while the main thread is in C++ (heyoka
  compiles without the GIL).
* **Once work has begun** (:func:`begin_work`: a propagation starts, a sweep starts
  integrating, a file is staged): a signal is Python's KeyboardInterrupt, which the commands
  turn into "interrupted", exit 130, keeping what they computed — never inside an import (a
  lazy one, h5py's when a result is saved): one that arrives there is delivered again once
  the import is done. During a propagation in the main thread it is only noted and the
  propagation ends after the current step (:class:`DeferredSignals`, :class:`Watch`).

* **Once the work is over** (:meth:`SignalPolicy.finish`: the files written, the report
  being printed): a signal ends the process at once again, exit 130.

An ignored signal (``nohup``, a background job of a shell script) stays ignored. Outside the
command line (the Python API) nothing is installed and Python's own Ctrl-C holds, with the
deferral during propagations.
"""

from __future__ import annotations

import _signal  # type: ignore[import-not-found]  # signal's C functions: see DeferredSignals
import contextlib
import os
import queue
import signal
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM)
_RAW_SIGNALS = tuple(int(sig) for sig in SIGNALS)

#: The exit status of a command ended by a signal (128 + SIGINT, as shells report Ctrl-C).
INTERRUPTED_EXIT = 130


class SignalPolicy:
    """The command line's handling of SIGINT and SIGTERM (the module docstring)."""

    def __init__(self) -> None:
        #: ``"start"`` (nothing computed), ``"work"``, ``"done"`` (everything written).
        self.phase = "start"
        self.installed = False
        self._old: dict[int, Any] = {}
        self._old_wakeup = -1
        self._wakeup: int | None = None
        self._ending = threading.Lock()
        self._again: list[threading.Timer] = []
        #: Signals a Python-level handler of ours has taken (this policy's, a propagation's, a
        #: write's), and the signals the watching thread has read from the wakeup pipe: one it
        #: reads after a handler took it is not its to act on.
        self.handled = 0
        self._arrived = 0
        # The handler as installed, so that the watching thread can tell it from another
        # one installed over it (a propagation's, a write's): those decide for themselves.
        self._handler = self._handle

    def install(self) -> None:
        """Take over both signals (main thread only; an ignored one stays ignored)."""
        if self.installed or threading.current_thread() is not threading.main_thread():
            return
        self.phase = "start"
        for sig in SIGNALS:
            if signal.getsignal(sig) is not signal.SIG_IGN:
                self._old[sig] = signal.signal(sig, self._handler)
        if self._wakeup is None:
            r, w = os.pipe()
            os.set_blocking(w, False)
            self._wakeup = w
            threading.Thread(
                target=self._watch, args=(r,), name="cayley_heyoka-signals", daemon=True
            ).start()
        self._old_wakeup = signal.set_wakeup_fd(self._wakeup, warn_on_full_buffer=False)
        self.installed = True

    def uninstall(self) -> None:
        """Give both signals back their previous handlers."""
        if not self.installed:
            return
        self.installed = False
        for again in self._again:  # the command is over: what it left undelivered is moot
            again.cancel()
        self._again.clear()
        signal.set_wakeup_fd(self._old_wakeup)
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        self._old.clear()

    def begin_work(self) -> None:
        """From now on something may be lost: a signal raises KeyboardInterrupt."""
        if self.phase == "start":
            self.phase = "work"

    def finish(self) -> None:
        """The command's work is over (its files written): a signal now ends the process at
        once, as before any work, rather than interrupting the report with a traceback."""
        self.phase = "done"

    def _handle(self, signum: int, frame: Any) -> None:
        self.handled += 1
        if self.phase != "work":
            self._end(signum)
        if _importing(frame):
            # Not inside an import (its module would stay half-made): the signal comes again
            # shortly, to whatever handles it then, until the import is done.
            again = threading.Timer(_AGAIN, os.kill, (os.getpid(), signum))
            again.daemon = True
            self._again.append(again)
            again.start()
            return
        raise KeyboardInterrupt

    def _watch(self, fd: int) -> None:
        # Python's C-level handler writes each signal's number here as it arrives, while the
        # main thread may not run Python code for a long time (an import's C part, LLVM).
        # A byte it reads late (the machine busy) may stand for a signal a handler took while
        # the command worked (a write held it, and re-raised it as KeyboardInterrupt): acting
        # on it once the work is done would end the process at once, cutting the report short.
        while data := os.read(fd, 512):
            for signum in data:
                if signum not in SIGNALS:
                    continue
                self._arrived += 1
                if (
                    self.installed
                    and self.phase != "work"
                    and signal.getsignal(signum) is self._handler
                    and self._arrived > self.handled
                ):
                    self._end(signum)

    def _end(self, signum: int) -> None:
        """End the process now: nothing is computed yet, or everything is written. The main
        thread's handler and the watcher may both come here; the second waits for the first
        to end the process."""
        self._ending.acquire()
        text = f"interrupted ({signal.Signals(signum).name})"
        text += ": nothing was computed\n" if self.phase == "start" else "\n"
        with contextlib.suppress(OSError):
            os.write(2, (("\n" if os.isatty(2) else "") + text).encode())
        os._exit(INTERRUPTED_EXIT)


#: Seconds after which a signal that arrived during an import is delivered again.
_AGAIN = 0.05


def _importing(frame: Any) -> bool:
    """Whether ``frame`` runs inside an import (importlib's frames are below it)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib._bootstrap"):
            return True
        frame = frame.f_back
    return False


POLICY = SignalPolicy()


@contextlib.contextmanager
def command_signals() -> Iterator[SignalPolicy]:
    """The command line's signal policy, for the duration of the context (:class:`SignalPolicy`).

    Entered first thing in ``main``; outside the main thread it installs nothing.
    """
    POLICY.install()
    try:
        yield POLICY
    finally:
        POLICY.uninstall()


def begin_work() -> None:
    """Say that work has begun (something computed, a file or a cluster being made): from now
    on a signal no longer ends the process at once but raises KeyboardInterrupt, which the
    work turns into a clean stop. Idempotent; outside the command line it changes nothing."""
    POLICY.begin_work()


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
        POLICY.handled += 1
        self.received = signal.Signals(signum).name
        if self.on_signal is not None:
            self.on_signal()

    def __enter__(self) -> DeferredSignals:
        # Every run enters this context: :mod:`signal`'s wrappers convert each handler to an
        # enum by a failing lookup (~8 µs a call, a third of a short run's fixed cost), so
        # the handlers are swapped with the C functions they wrap.
        begin_work()
        if threading.current_thread() is threading.main_thread():
            for sig in _RAW_SIGNALS:
                old = _signal.getsignal(sig)
                if callable(old):  # SIG_DFL and SIG_IGN keep their meaning
                    self._old[sig] = _signal.signal(sig, self._note)
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._old.items():
            _signal.signal(sig, handler)
        self._old.clear()


class Watch:
    """Propagations of the main thread run here, in one long-lived thread, while the main
    thread waits in Python, where its signal handlers run at once.

    A noted signal then sets the parameters that the right-hand sides use to NaN (and, if the
    run goes on regardless, the state: see :meth:`run`): the step under way becomes
    non-finite, and heyoka returns the outputs of the whole steps before it (``err_nf_state``;
    the rows it returns are the uninterrupted run's). The engine restores
    the parameters and reports the interruption. Equations without runtime parameters have
    their state set to NaN instead (a step under way writes it back finite, and is followed
    by the repoisoning of ``again``). No callback runs after each step, so an uninterrupted run
    costs what a run in any other thread does (measured: ``python
    validation/interrupt_cost.py``). Double precision only; other runs keep the per-step
    callback.
    """

    def __init__(self) -> None:
        self._jobs: queue.SimpleQueue = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def run(
        self,
        job: Callable[[], None],
        stop: Callable[[], None],
        again: Callable[[], bool] | None = None,
    ) -> None:
        """Run ``job`` in the watch's thread and wait for it; re-raise what it raised.

        ``stop`` is called if the wait itself is interrupted (an exception raised by another
        signal handler): the job is stopped and waited for before the exception goes on, so
        that nothing steps the integrator behind the caller's back. ``again`` is called while
        the job runs (every 0.25 s, and every :data:`REPOISON` s once it has returned true:
        a signal noted that has not stopped the job yet), to stop it harder: steps of size
        zero (:func:`.outcomes.zero_step`) do not see the poisoned parameters.
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
            wait = 0.25
            while not done.wait(wait):
                if again is not None and again():
                    wait = REPOISON
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


#: Seconds between the poisonings of a propagation that a signal has not yet stopped.
REPOISON = 0.01

WORKER = Watch()


class Cancel(threading.Event):
    """A cancel flag that also stops the batch calls in flight, as the engine's watch stops a
    scalar run (:class:`Watch`): :meth:`set` makes the parameters of the
    integrators stepping non-finite, so heyoka returns after its current step instead of at
    the end of a call that may cover a member's whole span. What those calls computed is
    dropped (their members are not finished)."""

    def __init__(self) -> None:
        super().__init__()
        self._hooks: list[Callable[[], None]] = []
        self._lock = threading.Lock()

    def watch(self, hook: Callable[[], None]) -> None:
        with self._lock:
            self._hooks.append(hook)

    def unwatch(self, hook: Callable[[], None]) -> None:
        with self._lock:
            self._hooks.remove(hook)

    def set(self) -> None:
        super().set()
        if self._poke():
            # Steps of size zero (:func:`.outcomes.zero_step`) write back the state they read
            # and do not see the parameters: poisoned again until every call has returned.
            threading.Thread(target=self._keep_poking, daemon=True).start()

    def _poke(self) -> bool:
        """Call the hooks of the calls in flight; whether there were any."""
        with self._lock:
            hooks = list(self._hooks)
        for hook in hooks:
            hook()
        return bool(hooks)

    def _keep_poking(self) -> None:
        while True:
            time.sleep(REPOISON)
            if not self._poke():
                return


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
    Entering it begins the command's work (:func:`begin_work`): what is being written is kept.
    """
    begin_work()
    if threading.current_thread() is not threading.main_thread():
        yield  # Python delivers signals to the main thread only: nothing interrupts this one
        return
    noted: list[int] = []

    def note(signum: int, frame: Any) -> None:
        POLICY.handled += 1
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
