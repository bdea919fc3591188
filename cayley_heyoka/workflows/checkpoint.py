"""Runs that survive interruption: fixed stretches, each written to disk before the next.

A :class:`CheckpointedRun` advances a :class:`~cayley_heyoka.core.engine.Propagation` to ``count``
equally spaced boundary times. After each stretch it writes, into a work directory, the rows
recorded (``segment-NNNNNN.ckpt``) and then the integrator's snapshot (``snapshot.ckpt``), which
vouches for every stretch so far by its rows and digest. Run again with the same work
directory, it continues from the last snapshot; because the boundaries are fixed by the scene
and ``count`` alone, the resumed run ends with the same bits as one never interrupted.

Layout of the work directory::

    manifest.ckpt          what is being run (scene, precision, boundaries, versions)
    segment-000001.ckpt    states and parameters recorded in stretch 1 (decimal text beyond
    ...                    double precision, so they load back bit-for-bit)
    snapshot.ckpt          the integrator after the last stretch written, its number, and
                           the rows and digest of each stretch up to it

Each file is written by :func:`cayley_heyoka.core.files.write_checkpoint`: atomically (a
process killed at any moment leaves the directory as it was after some whole stretch), with a
checksum and the identity of the run (the SHA-256 of the manifest). When resuming, every file
is verified. A file of another run (another scene, precision, boundary count or library
version — the last would not reproduce the same bits) is refused, not mixed in, naming the
file. A damaged one (cut short, edited, missing, or not what the snapshot vouches for) is not
used: the run starts again from the last state every file verifies, which is the start, and
ends with the same bits; :attr:`CheckpointedRun.notes` says what was dropped and why.
"""

from __future__ import annotations

import contextlib
import io
import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..core.engine import Progress, Propagation
from ..core.files import (
    CheckpointError,
    OutputError,
    identity_of,
    read_checkpoint,
    write_checkpoint,
)
from ..core.result import Result, versions
from ..core.scene import Scene

FORMAT = "cayley_heyoka.checkpoint"
#: Names of the files of the work directory.
MANIFEST, SNAPSHOT = "manifest.ckpt", "snapshot.ckpt"
SEGMENT = re.compile(r"segment-\d{6,}\.ckpt")
#: What older versions of this module wrote (plain JSON and npz, unchecked): never resumed.
_LEGACY = re.compile(r"manifest\.json|snapshot\.json|segment-\d{6,}\.npz")


#: Most stretches a run may be cut into: each writes a file, and each boundary ends a step.
MAX_STRETCHES = 10_000


def check_count(count: Any) -> int:
    """``count`` if it is a number of stretches in 1 … :data:`MAX_STRETCHES`, else ValueError."""
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_STRETCHES:
        raise ValueError(
            f"checkpoints (stretches of a run) must be an integer in 1 … {MAX_STRETCHES}, "
            f"got {count!r}"
        )
    return count


class CheckpointMismatch(ValueError):
    """The work directory holds a different run than the one asked for."""


class CheckpointedRun:
    """One scene integrated through fixed boundaries, resumable from its work directory.

    Parameters
    ----------
    scene
        The scene, with the precision and tolerance to run in.
    workdir
        Directory for the stretches and snapshots (created if missing).
    count
        Number of stretches: the boundaries are ``t0 + (t1 - t0) k / count``, k = 1 … count,
        built in the run's precision. Part of what the result depends on (each boundary ends
        a step), so it is kept in the manifest.
    progress
        Called with the current time after each step.

    Attributes
    ----------
    resumed
        Stretches read back from the work directory by the last :meth:`run`.
    notes
        One line per file of the work directory that :meth:`run` did not use, and why.
    """

    def __init__(
        self, scene: Scene, workdir: str | Path, count: int, progress: Progress | None = None
    ) -> None:
        self.scene = scene
        self.workdir = Path(workdir)
        self.count = check_count(count)
        self.progress = progress
        self.precision = scene.integrator.precision
        self.resumed = 0
        self.notes: list[str] = []
        self._identity = identity_of(self.manifest())

    def manifest(self) -> dict[str, Any]:
        """What identifies this run: the same manifest means the same bits."""
        return {
            "format": FORMAT,
            "scene": self.scene.to_dict(),
            "precision": self.precision.to_spec(),
            "stretches": self.count,
            "versions": versions(),
        }

    def run(self, after_stretch: Callable[[int, Any], None] | None = None) -> Result:
        """Integrate to the end, resuming from the work directory if it holds this run.

        Parameters
        ----------
        after_stretch
            Called with the stretch number and the time reached, after the stretch is safely
            on disk (a progress report, or a test's simulated interruption).

        Returns
        -------
        Result
            As :func:`cayley_heyoka.run` would return it for the boundaries used. A run that
            stops early (non-finite state, a terminal stop) returns its partial result with
            ``status = -1``; its stretches stay in the work directory.

        Raises
        ------
        CheckpointMismatch
            The work directory holds files of another run.
        OutputError
            A file of the work directory could not be written (a full disk): what was
            written before is kept, and the same run continues from it.
        """
        snapshot, records = self._prepare()
        propagation = Propagation(self.scene, self.progress, keep=False)
        grid = propagation.grid
        start = k = self.resumed = len(records)
        if snapshot is not None:
            propagation.restore(snapshot)
        for k in range(start + 1, self.count + 1):
            until = self._boundary(grid, k)
            states, pars = propagation.advance(until)
            records.append(self._write_segment(k, states, pars))
            if propagation.status != 0:
                break
            body = {"stretch": k, "propagation": propagation.snapshot(), "segments": records}
            self._write(SNAPSHOT, "snapshot", json.dumps(body).encode(), stretch=k)
            if after_stretch is not None:
                after_stretch(k, propagation.time)
        states, pars = self._load_all(records)
        return propagation.result(states, pars)

    # ------------------------------------------------------------------ resuming
    def _prepare(self) -> tuple[dict[str, Any] | None, list[dict[str, Any]]]:
        """Verify the work directory: the snapshot to continue from (None: from the start)
        and the records of the stretches it vouches for; everything else is removed."""
        try:
            self.workdir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError.failed_write(self.workdir, exc) from exc
        self.notes = []
        for path in self.workdir.iterdir():
            if _LEGACY.fullmatch(path.name) and path.is_file():
                self._drop(path, "written by an older version of cayley_heyoka")
        # Everything is verified before anything is written: a directory of another run is
        # refused as it was found.
        manifest = self._check_manifest()
        snapshot, records = self._verified_state()
        if manifest:
            self._write(MANIFEST, "manifest", manifest)
        done = len(records)
        # A stretch written after the last snapshot (killed between the two renames) is
        # recomputed: only what a snapshot vouches for is kept.
        for seg in self.workdir.glob("segment-*.ckpt"):
            if SEGMENT.fullmatch(seg.name) and int(seg.stem.split("-")[1]) > done:
                seg.unlink()
        if snapshot is None:
            (self.workdir / SNAPSHOT).unlink(missing_ok=True)
        return snapshot, records

    def _check_manifest(self) -> bytes:
        """The manifest to write ('' if the one there is this run's)."""
        try:
            read_checkpoint(self.workdir / MANIFEST, "manifest", self._identity)
            return b""
        except CheckpointError as exc:
            if exc.reason == "foreign":
                raise self._mismatch(exc) from None
            if exc.reason == "damaged":
                self.notes.append(f"{exc}; written again")
        return json.dumps(self.manifest(), indent=1).encode()

    def _verified_state(self) -> tuple[dict[str, Any] | None, list[dict[str, Any]]]:
        try:
            header, body = read_checkpoint(self.workdir / SNAPSHOT, "snapshot", self._identity)
        except CheckpointError as exc:
            if exc.reason == "foreign":
                raise self._mismatch(exc) from None
            if exc.reason == "damaged":
                self._drop_all(f"{exc}")
            return None, []
        saved = json.loads(body)
        records = saved["segments"]
        for k, record in enumerate(records, 1):
            try:
                self._read_segment(k, record)
            except CheckpointError as exc:
                if exc.reason == "foreign":
                    raise self._mismatch(exc) from None
                self._drop_all(str(exc))
                return None, []
        return saved["propagation"], records

    def _mismatch(self, exc: CheckpointError) -> CheckpointMismatch:
        found = exc.found if exc.path.name == MANIFEST else b""
        what = "its files belong to another run"
        if found:
            with contextlib.suppress(ValueError):
                mine, theirs = self.manifest(), json.loads(found)
                differ = sorted(k for k in {*mine, *theirs} if mine.get(k) != theirs.get(k))
                if differ:
                    what = f"its {', '.join(differ)} differ"
        return CheckpointMismatch(
            f"{self.workdir} holds another run ({what}: {exc.path.name} is not of this one); "
            "remove the directory to start afresh, or give this run another --out"
        )

    def _drop_all(self, why: str) -> None:
        """Start afresh: every stretch and the snapshot removed, ``why`` noted."""
        self.notes.append(f"{why}; the run starts again from the beginning")
        for path in self.workdir.iterdir():
            if path.name == SNAPSHOT or SEGMENT.fullmatch(path.name):
                path.unlink()

    def _drop(self, path: Path, why: str) -> None:
        self.notes.append(f"{path}: {why}; not used")
        path.unlink()

    # ------------------------------------------------------------------ files
    def _write(self, name: str, kind: str, body: bytes, **fields: Any) -> str:
        return write_checkpoint(self.workdir / name, kind, self._identity, body, **fields)

    def _boundary(self, grid: np.ndarray, k: int) -> Any:
        if k == self.count:
            return grid[-1]
        prec = self.precision
        a, b = grid[0], grid[-1]
        return a + (b - a) * prec.number(k) / prec.number(self.count)

    def _write_segment(self, k: int, states: np.ndarray, pars: np.ndarray) -> dict[str, Any]:
        prec = self.precision
        buffer = io.BytesIO()
        if prec.kind == "double":
            np.savez(buffer, states=states, pars=pars)
        else:
            np.savez(
                buffer,
                states=prec.to_text(states).astype(str),
                pars=prec.to_text(pars).astype(str),
            )
        rows = len(states)
        name = f"segment-{k:06d}.ckpt"
        digest = self._write(name, "segment", buffer.getvalue(), stretch=k, rows=rows)
        return {"rows": rows, "sha256": digest}

    def _read_segment(self, k: int, record: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
        """Stretch ``k``'s rows, verified against its own checksum and ``record``."""
        path = self.workdir / f"segment-{k:06d}.ckpt"
        header, body = read_checkpoint(path, "segment", self._identity)
        if header.get("stretch") != k or header.get("body_sha256") != record["sha256"]:
            raise CheckpointError(
                path, "damaged", "is not the stretch the snapshot vouches for (its digest differs)"
            )
        try:
            with np.load(io.BytesIO(body), allow_pickle=False) as data:
                states, pars = data["states"], data["pars"]
        except (ValueError, KeyError, OSError) as exc:
            raise CheckpointError(path, "damaged", f"holds no rows ({exc})") from exc
        if not len(states) == len(pars) == record["rows"]:
            raise CheckpointError(path, "damaged", "holds another number of rows")
        prec = self.precision
        if prec.kind != "double":
            states, pars = prec.from_text(states), prec.from_text(pars)
        return states, pars

    def _load_all(self, records: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
        states, pars = [], []
        for k, record in enumerate(records, 1):
            s, p = self._read_segment(k, record)
            states.append(s)
            pars.append(p)
        return _stack(states), _stack(pars)


def remove_checkpoints(workdir: str | Path) -> None:
    """Delete the files a :class:`CheckpointedRun` writes in ``workdir``, and nothing else.

    The directory itself goes if that leaves it empty; a file someone else put there keeps
    it (and itself) in place.
    """
    workdir = Path(workdir)
    if not workdir.is_dir():
        return
    for path in workdir.iterdir():
        name = re.sub(r"^\.(.*)\.tmp-\d+(-\d+)?$", r"\1", path.name).removesuffix(".tmp")
        if path.is_file() and (
            name in (MANIFEST, SNAPSHOT) or SEGMENT.fullmatch(name) or _LEGACY.fullmatch(name)
        ):
            path.unlink()
    with contextlib.suppress(OSError):  # not empty: what is left is not ours
        workdir.rmdir()


def _stack(parts: list[np.ndarray]) -> np.ndarray:
    rows = [p for p in parts if len(p)]
    return np.concatenate(rows) if rows else parts[0]
