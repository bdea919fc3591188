"""Closed forms evaluated at a scene's output times, in parallel over cores.

The route of ``cayley-heyoka reference`` for scenes with a closed form
(:mod:`cayley_heyoka.workflows.reference`): each output time is evaluated independently — the free
body's :meth:`~cayley_heyoka.reference.FreeRigidBody.at`, the projectile's
:func:`~cayley_heyoka.reference.projectile_solution` — each certified by its own two working
precisions, then rounded once to the file's precision. The certificate of a written value is
what that rounding changed, measured exactly in mpmath, plus the closed form's error bound.

Times are split into chunks handed to worker processes in order, so the values are the same
bits whatever the number of workers. Workers are started with ``spawn`` (a forked copy of a
process holding LLVM's threads is not safe) and import mpmath and numpy only, not heyoka;
they ignore SIGINT, so Ctrl-C reaches the parent alone, which terminates them.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import multiprocessing
import os
import re
import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mpmath

from .signals import begin_work

#: Below this many output times the evaluation stays in the calling process: starting a
#: worker costs ~0.4 s of CPU (its imports and the closed form's constants at each working
#: precision), some 40 evaluations of the free body at 30 digits, so that fewer times gain
#: little from a second core (validation/users_reference.py, the 100-output row).
PARALLEL_FROM = 200
#: Chunks the times are split into, whatever the number of workers: enough to balance the
#: load and report progress, few enough to keep the per-chunk overhead small; each finished
#: chunk is saved when there is a work directory, so an interrupted evaluation resumes.
CHUNKS = 64
_CHUNK = re.compile(r"chunk-\d{5}\.ckpt")
#: What older versions saved (plain JSON, unchecked): never read back.
_LEGACY = re.compile(r"job\.json|chunk-\d{5}\.json")

#: What one output time gives: written values as text and their absolute errors, each a
#: list for a vector monitor.
Row = tuple[dict[str, Any], dict[str, Any]]


@dataclass(frozen=True)
class Rounding:
    """The file's precision, as the worker needs it: a kind and a number of bits."""

    kind: str  # "double", "quad" or "real"
    bits: int

    @property
    def digits(self) -> int:
        """Decimal digits that round-trip ``bits`` (as :attr:`Precision.dps`)."""
        return math.ceil(self.bits * math.log10(2.0)) + 2

    def read(self, text: str) -> mpmath.mpf:
        """The exact value of a number of this precision written as round-trip text."""
        with mpmath.workprec(self.bits):
            return mpmath.mpf(text)

    def write(self, x: mpmath.mpf) -> tuple[str, mpmath.mpf]:
        """``x`` rounded to this precision: its text, and the exact value the text stands for."""
        if not mpmath.isfinite(x):
            return (str(float(x)), x)
        with mpmath.workprec(self.bits):
            y = +x  # round to nearest
            text = repr(float(y)) if self.kind == "double" else mpmath.nstr(y, self.digits)
        return text, self.read(text)


# ---------------------------------------------------------------------- in parallel
_worker: Callable[[str], Row] | None = None


def _start_worker(job: Any) -> None:
    global _worker
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent handles Ctrl-C and ends us
    _worker = job.evaluator()


def _chunk(times: list[str]) -> list[Row]:
    assert _worker is not None
    return [_worker(t) for t in times]


def default_workers() -> int:
    """Every core this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def evaluate(
    job: Any,
    times: Sequence[str],
    workers: int | None = None,
    progress: Callable[[int], None] | None = None,
    meanwhile: Callable[[], Any] | None = None,
    store: Path | None = None,
) -> tuple[list[Row], Any, int]:
    """Evaluate ``job`` at each of ``times`` (text of the file's precision), in order.

    Parameters
    ----------
    job
        A :class:`FreeBodyJob` or :class:`ProjectileJob`.
    times
        The output times.
    workers
        Processes to use; default: every core. The rows are the same whatever the count.
    progress
        ``progress(done)`` after each chunk, with the number of times evaluated so far.
    meanwhile
        Work for this process while the workers evaluate (the events' crossing times).
    store
        A directory where each finished chunk is saved and, when the same job is evaluated
        again (an interrupted command run again), read back instead of evaluated.

    Returns
    -------
    rows, extra, resumed
        One row per time, what ``meanwhile`` returned (None without it), and how many chunks
        were read back from ``store``.

    Raises
    ------
    PrecisionNotReached
        From the closed form, when its digits cannot be certified at some time.
    KeyboardInterrupt
        On Ctrl-C; the workers are terminated first.
    """
    workers = default_workers() if workers is None else workers
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    # Values are computed and saved, perhaps by worker processes, from here: a signal stops
    # the evaluation (the workers terminated first) instead of ending the process at once.
    begin_work()
    times = list(times)
    size = max(1, math.ceil(len(times) / CHUNKS))
    chunks = [times[i : i + size] for i in range(0, len(times), size)]
    sizes = [len(c) for c in chunks]
    done: dict[int, list[Row]] = _saved(store, job, times, sizes) if store else {}
    ident = _identity(job, times) if store else ""
    resumed = len(done)
    todo = [i for i in range(len(chunks)) if i not in done]
    count = sum(len(done[i]) for i in done)

    def finished(i: int, part: list[Row]) -> None:
        nonlocal count
        done[i] = part
        if store:
            _save(store / f"chunk-{i:05d}.ckpt", i, ident, part)
        count += len(part)
        if progress:
            progress(count)

    left = sum(len(chunks[i]) for i in todo)
    workers = min(workers, len(todo), max(1, left // (PARALLEL_FROM // 2)))
    if workers <= 1 or left < PARALLEL_FROM:
        if todo:
            at = job.evaluator()
            for i in todo:
                finished(i, [at(t) for t in chunks[i]])
        extra = meanwhile() if meanwhile else None
    else:
        pool = multiprocessing.get_context("spawn").Pool(
            workers, initializer=_start_worker, initargs=(job,)
        )
        try:
            parts = pool.imap(_chunk, [chunks[i] for i in todo])  # every chunk is queued now
            extra = meanwhile() if meanwhile else None
            for i, part in zip(todo, parts, strict=True):
                finished(i, part)
            pool.close()
        except BaseException:
            pool.terminate()
            raise
        finally:
            pool.join()
    rows = [row for i in range(len(chunks)) for row in done[i]]
    return rows, extra, resumed


# ---------------------------------------------------------------------- resuming
def _identity(job: Any, times: list[str]) -> str:
    from .files import identity_of

    return identity_of({"job": dataclasses.asdict(job), "kind": type(job).__name__, "times": times})


def _saved(store: Path, job: Any, times: list[str], sizes: list[int]) -> dict[int, list[Row]]:
    """The chunks saved in ``store`` by the same job over the same times, each verified (its
    checksum, the job's identity, its number of rows); any other chunk file is removed, and
    that chunk evaluated again."""
    from .files import OutputError, read_checkpoint

    ident = _identity(job, times)
    try:
        store.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError.failed_write(store, exc) from exc
    done = {}
    for path in store.iterdir():
        if _LEGACY.fullmatch(path.name) and path.is_file():
            path.unlink()
        if not _CHUNK.fullmatch(path.name):
            continue
        i = int(path.name[6:11])
        try:
            header, body = read_checkpoint(path, "closed-form chunk", ident)
            rows = json.loads(body)
            if header.get("chunk") != i or i >= len(sizes) or len(rows) != sizes[i]:
                raise ValueError("not the chunk its name says")
            done[i] = [(v, e) for v, e in rows]
        except ValueError:  # damaged, another job's, or not what it claims: evaluated again
            path.unlink()
    return done


def _save(path: Path, i: int, ident: str, part: list[Row]) -> None:
    from .files import write_checkpoint

    write_checkpoint(path, "closed-form chunk", ident, json.dumps(part).encode(), chunk=i)


def remove_saved(store: Path) -> None:
    """Delete what :func:`evaluate` saved in ``store``, and the directory if that empties it."""
    if not store.is_dir():
        return
    for path in store.iterdir():
        name = re.sub(r"^\.(.*)\.tmp-\d+(-\d+)?$", r"\1", path.name).removesuffix(".tmp")
        if path.is_file() and (_CHUNK.fullmatch(name) or _LEGACY.fullmatch(name)):
            path.unlink()
    with contextlib.suppress(OSError):  # not empty: what is left is not ours
        store.rmdir()
