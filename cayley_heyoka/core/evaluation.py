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
import hashlib
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

#: Below this many output times the evaluation stays in the calling process: starting a
#: worker costs ~0.4 s of CPU (its imports and the closed form's constants at each working
#: precision), some 40 evaluations of the free body at 30 digits, so that fewer times gain
#: little from a second core (validation/users_reference.py, the 100-output row).
PARALLEL_FROM = 200
#: Chunks the times are split into, whatever the number of workers: enough to balance the
#: load and report progress, few enough to keep the per-chunk overhead small; each finished
#: chunk is saved when there is a work directory, so an interrupted evaluation resumes.
CHUNKS = 64
_CHUNK = re.compile(r"chunk-\d{5}\.json")

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
    times = list(times)
    size = max(1, math.ceil(len(times) / CHUNKS))
    chunks = [times[i : i + size] for i in range(0, len(times), size)]
    done: dict[int, list[Row]] = _saved(store, job, times) if store else {}
    resumed = len(done)
    todo = [i for i in range(len(chunks)) if i not in done]
    count = sum(len(done[i]) for i in done)

    def finished(i: int, part: list[Row]) -> None:
        nonlocal count
        done[i] = part
        if store:
            _save(store / f"chunk-{i:05d}.json", part)
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
    data = {"job": dataclasses.asdict(job), "kind": type(job).__name__, "times": times}
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def _saved(store: Path, job: Any, times: list[str]) -> dict[int, list[Row]]:
    """The chunks saved in ``store`` by the same job over the same times; others are removed."""
    ident = _identity(job, times)
    marker = store / "job.json"
    if store.is_dir() and _read(marker) != {"identity": ident}:
        remove_saved(store)
    store.mkdir(parents=True, exist_ok=True)
    _save(marker, {"identity": ident})
    done = {}
    for path in store.iterdir():
        if _CHUNK.fullmatch(path.name):
            rows = _read(path)
            if rows is not None:
                done[int(path.name[6:11])] = [(v, e) for v, e in rows]
    return done


def _read(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):  # missing, or cut short by a crash: evaluated again
        return None


def _save(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(json.dumps(data))
    os.replace(tmp, path)


def remove_saved(store: Path) -> None:
    """Delete what :func:`evaluate` saved in ``store``, and the directory if that empties it."""
    if not store.is_dir():
        return
    for path in store.iterdir():
        name = path.name.removesuffix(".tmp")
        if path.is_file() and (name == "job.json" or _CHUNK.fullmatch(name)):
            path.unlink()
    with contextlib.suppress(OSError):  # not empty: what is left is not ours
        store.rmdir()
