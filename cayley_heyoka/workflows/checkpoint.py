"""Runs that survive interruption: fixed stretches, each written to disk before the next.

A :class:`CheckpointedRun` advances a :class:`~cayley_heyoka.core.engine.Propagation` to ``count``
equally spaced boundary times. After each stretch it writes, into a work directory, the rows
recorded (``segment-NNNNNN.npz``) and then the integrator's snapshot (``snapshot.json``); each
file is written under a temporary name and renamed into place, so a process killed at any
moment leaves the directory as it was after some whole stretch. Run again with the same work
directory, it continues from the last snapshot; because the boundaries are fixed by the
scene and ``count`` alone, the resumed run ends with the same bits as one never interrupted.

Layout of the work directory::

    manifest.json          what is being run (scene, precision, boundaries, versions)
    segment-000001.npz     states and parameters recorded in stretch 1 (decimal text beyond
    ...                    double precision, so they load back bit-for-bit)
    snapshot.json          the integrator after the last stretch written, and its number

A manifest that differs from the run asked for (another scene, precision, boundary count or
library version — the last would not reproduce the same bits) is refused rather than mixed in.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..core.engine import Progress, Propagation
from ..core.result import Result, versions
from ..core.scene import Scene

FORMAT = "cayley_heyoka.checkpoint"
#: Names of the stretch files.
SEGMENT = re.compile(r"segment-\d{6,}\.npz")


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
    """

    def __init__(
        self, scene: Scene, workdir: str | Path, count: int, progress: Progress | None = None
    ) -> None:
        self.scene = scene
        self.workdir = Path(workdir)
        self.count = check_count(count)
        self.progress = progress
        self.precision = scene.integrator.precision

    def manifest(self) -> dict[str, Any]:
        """What identifies this run: the same manifest means the same bits."""
        return {
            "format": FORMAT,
            "scene": self.scene.to_dict(),
            "stretches": self.count,
            "versions": versions(),
        }

    def completed(self) -> int:
        """Stretches already written in the work directory (0 when starting afresh)."""
        snap = self.workdir / "snapshot.json"
        return json.loads(snap.read_text())["stretch"] if snap.exists() else 0

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
        """
        self._prepare()
        propagation = Propagation(self.scene, self.progress, keep=False)
        grid = propagation.grid
        start = k = self.completed()
        if start:
            snap = json.loads((self.workdir / "snapshot.json").read_text())
            propagation.restore(snap["propagation"])
        for k in range(start + 1, self.count + 1):
            until = self._boundary(grid, k)
            states, pars = propagation.advance(until)
            self._write(f"segment-{k:06d}.npz", lambda f, s=states, p=pars: self._save(f, s, p))
            if propagation.status != 0:
                break
            snapshot = {"stretch": k, "propagation": propagation.snapshot()}
            self._write("snapshot.json", lambda f, s=snapshot: f.write(json.dumps(s).encode()))
            if after_stretch is not None:
                after_stretch(k, propagation.time)
        states, pars = self._load_all(k)
        return propagation.result(states, pars)

    # ------------------------------------------------------------------ internals
    def _prepare(self) -> None:
        self.workdir.mkdir(parents=True, exist_ok=True)
        path = self.workdir / "manifest.json"
        mine = self.manifest()
        if path.exists():
            theirs = json.loads(path.read_text())
            if theirs != mine:
                differ = sorted(k for k in {*mine, *theirs} if mine.get(k) != theirs.get(k))
                raise CheckpointMismatch(
                    f"{self.workdir} holds another run (its {', '.join(differ)} differ); "
                    "remove the directory to start afresh"
                )
        else:
            self._write("manifest.json", lambda f: f.write(json.dumps(mine, indent=1).encode()))
        # A stretch written after the last snapshot (killed between the two renames) is
        # recomputed: only what a snapshot vouches for is kept.
        done = self.completed()
        for seg in self.workdir.glob("segment-*.npz"):
            if SEGMENT.fullmatch(seg.name) and int(seg.stem.split("-")[1]) > done:
                seg.unlink()

    def _boundary(self, grid: np.ndarray, k: int) -> Any:
        if k == self.count:
            return grid[-1]
        prec = self.precision
        a, b = grid[0], grid[-1]
        return a + (b - a) * prec.number(k) / prec.number(self.count)

    def _write(self, name: str, write: Callable[[Any], None]) -> None:
        target = self.workdir / name
        tmp = target.with_name(target.name + ".tmp")
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, target)

    def _save(self, f: Any, states: np.ndarray, pars: np.ndarray) -> None:
        prec = self.precision
        if prec.kind == "double":
            np.savez(f, states=states, pars=pars)
        else:
            np.savez(
                f,
                states=prec.to_text(states).astype(str),
                pars=prec.to_text(pars).astype(str),
            )

    def _load_all(self, last: int) -> tuple[np.ndarray, np.ndarray]:
        prec = self.precision
        states, pars = [], []
        for k in range(1, last + 1):
            with np.load(self.workdir / f"segment-{k:06d}.npz") as data:
                s, p = data["states"], data["pars"]
            if prec.kind != "double":
                s, p = prec.from_text(s), prec.from_text(p)
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
        name = path.name.removesuffix(".tmp")
        if path.is_file() and (
            name in ("manifest.json", "snapshot.json") or SEGMENT.fullmatch(name)
        ):
            path.unlink()
    with contextlib.suppress(OSError):  # not empty: what is left is not ours
        workdir.rmdir()


def _stack(parts: list[np.ndarray]) -> np.ndarray:
    rows = [p for p in parts if len(p)]
    return np.concatenate(rows) if rows else parts[0]
