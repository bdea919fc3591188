"""The file of a conservation sweep: every member's drift, final values, steps and status.

Written by :func:`cayley_heyoka.workflows.sweep.run_sweep` (layout: :class:`SweepResult` and
docs/tutorials/sweeps.md); read with :func:`load_sweep`.
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.files import FORMAT_VERSION, FORMATS, OutputError, Staged, open_ours, seal, write_hdf5
from ..core.precision import Precision
from ..core.scene import Scene
from .study import Member, Study, show_number

FORMAT = FORMATS["sweep"]

#: Member status codes in :attr:`SweepResult.status`.
OK, FAILED, NOT_RUN = 0, -1, -2


# ---------------------------------------------------------------------- the result
@dataclass
class SweepResult:
    """What a sweep computed, member by member; the HDF5 sweep file in and out.

    Attributes
    ----------
    t
        The output times shared by every member (the base scene's), in its precision.
    parameters
        Each swept parameter's value per member, by dotted name: shape ``(members,)``.
    drift
        Each conserved monitor's relative drift, ``(members, len(t))`` float64: the largest
        component of ``|m(t) − m(t₀)| / |m(t₀)|`` (as :meth:`Result.drift`). NaN after a
        member stopped, for members not run, and where the member's flow does not conserve
        the monitor.
    final_names, final_state
        The result variables (the integrated state and the derived coordinates) and their
        values at the last output time, ``(members, len(final_names))`` in the precision;
        NaN for members that did not complete.
    status
        ``OK`` (0), ``FAILED`` (−1, stopped early or could not be integrated) or ``NOT_RUN``
        (−2, the sweep stopped before it).
    message
        Why each member ended.
    steps
        Taylor steps per member.
    events
        Occurrences of each recorded event per member (the scene's ``output.events``).
    precision
        The study's precision.
    study
        The study (:meth:`Study.to_dict`).
    metadata
        Versions, backend, workers, wall time, the path each member took (counts), whether
        the sweep completed.
    """

    t: np.ndarray
    parameters: dict[str, np.ndarray]
    drift: dict[str, np.ndarray]
    final_names: tuple[str, ...]
    final_state: np.ndarray
    status: np.ndarray
    message: np.ndarray
    steps: np.ndarray
    events: dict[str, np.ndarray] = field(default_factory=dict)
    precision: Precision = field(default_factory=Precision)
    study: dict[str, Any] = field(default_factory=dict)
    metadata: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.status)

    def __repr__(self) -> str:
        """One line: the study, the members and how many completed, the worst final drift."""
        title = self.study.get("title") or "untitled"
        completed = int(np.count_nonzero(self.completed))
        worst = ""
        finals = {}
        for name in self.drift:
            final = np.where(self.completed, self.final_drift(name), np.nan)
            if not np.all(np.isnan(final)):
                finals[name] = float(np.nanmax(final))
        if finals:
            name = max(finals, key=finals.get)
            worst = f", worst final drift {name} {finals[name]:.1e}"
        over = ", ".join(self.parameters) or "no parameter"
        return (
            f"<SweepResult {title!r}: {len(self)} members over {over}, {self.precision.name}, "
            f"{len(self.t)} outputs, {completed} completed{worst}>"
        )

    @property
    def completed(self) -> np.ndarray:
        """Boolean mask of the members that reached the last output time."""
        return self.status == OK

    def values(self, member: int) -> dict[str, Any]:
        """The parameter values of one member, by name."""
        return {name: column[member] for name, column in self.parameters.items()}

    def final_drift(self, name: str) -> np.ndarray:
        """Each member's drift of monitor ``name`` at the last output time."""
        d = self.drift[name]
        return d[:, -1] if d.shape[1] else np.full(len(self), np.nan)

    def worst(self, name: str) -> int | None:
        """The completed member with the largest final drift of ``name`` (None if none)."""
        final = np.where(self.completed, self.final_drift(name), np.nan)
        if np.all(np.isnan(final)):
            return None
        return int(np.nanargmax(final))

    def summary(self) -> str:
        """A one-screen account: members, paths, wall time, drifts, the worst members."""
        title = self.study.get("title") or "(untitled study)"
        sweep = self.study.get("sweep", {})
        meta = self.metadata
        n = len(self)
        counts = Counter(int(s) for s in self.status)
        names = ", ".join(self.parameters)
        lines = [title, ""]
        lines.append(
            f"  study         {sweep.get('kind')} of {n} members over {names}; "
            f"precision {self.precision.name}"
        )
        state = "completed" if meta.get("complete") else f"STOPPED: {meta.get('stopped')}"
        lines.append(
            f"  members       {counts[OK]} completed, {counts[FAILED]} failed, "
            f"{counts[NOT_RUN]} not run ({state})"
        )
        for path, k in meta.get("paths", {}).items():
            why = meta.get("why", {}).get(path)
            lines.append(f"  path          {path}: {k} members" + (f" ({why})" if why else ""))
        if meta.get("backend") == "dask":
            where = f"dask, {meta.get('cluster')}, {meta.get('workers')} workers"
        else:
            where = f"{meta.get('backend')}, {meta.get('workers')} threads"
        lines.append(
            f"  wall time     {meta.get('wall_seconds', float('nan')):.2f} s ({where}); compiling "
            f"{meta.get('compile_seconds', 0.0):.2f} s, summed over workers"
        )
        done = self.steps[self.completed]
        if len(done):
            lines.append(
                f"  steps         median {np.median(done):.0f}, max {int(np.max(done))} per member"
            )
        t_last = f"{float(self.t[-1]):.6g}" if len(self.t) else "-"
        if self.drift:
            lines.append(f"  final relative drift at t = {t_last} (completed members):")
            lines.append(f"    {'monitor':<18} {'median':>9} {'max':>9}  worst member")
            for name in self.drift:
                final = self.final_drift(name)[self.completed]
                worst = self.worst(name)
                if worst is None:
                    lines.append(f"    {name:<18} {'-':>9} {'-':>9}  (no completed member)")
                    continue
                detail = ", ".join(f"{k} = {show_number(v)}" for k, v in self.values(worst).items())
                lines.append(
                    f"    {name:<18} {np.nanmedian(final):9.2e} {np.nanmax(final):9.2e}  "
                    f"{worst} ({detail})"
                )
        for name, occurrences in self.events.items():
            done = occurrences[self.completed]
            if len(done):
                lines.append(
                    f"  event {name:<12} {int(np.min(done))}–{int(np.max(done))} occurrences "
                    "per member"
                )
        failed = np.flatnonzero(self.status == FAILED)
        for i in failed[:5]:
            detail = ", ".join(f"{k} = {show_number(v)}" for k, v in self.values(i).items())
            lines.append(f"  failed        member {i} ({detail}): {self.message[i]}")
        if len(failed) > 5:
            lines.append(f"  failed        ... and {len(failed) - 5} more (status -1 in the file)")
        return "\n".join(lines)

    # ------------------------------------------------------------------ HDF5
    def save(self, path: str | Path) -> None:
        """Write the sweep file (the layout is documented in docs/tutorials/sweeps.md).

        Atomically and with a checksum, as :meth:`Result.save`.
        """
        write_hdf5(path, lambda f: _create(f, self))

    @classmethod
    def load(cls, path: str | Path) -> SweepResult:
        """Read a sweep file (also one a stopped sweep left: its members not run have status
        ``NOT_RUN``); extended-precision values load exactly.

        Raises
        ------
        ResultFileError
            The file is missing, not a sweep file, damaged or incomplete (as
            :meth:`Result.load`).
        """
        from ..core.result import read_array

        with open_ours(path, "sweep") as f:
            prec = Precision.from_spec(json.loads(f.attrs["precision"]))
            order = json.loads(f.attrs["order"])
            return cls(
                t=read_array(f["t"], prec),
                parameters={k: read_array(f["parameters"][k], prec) for k in order["parameters"]},
                drift={k: np.asarray(f["drift"][k][()], dtype=np.float64) for k in order["drift"]},
                final_names=tuple(json.loads(f["final_state"].attrs["names"])),
                final_state=read_array(f["final_state"], prec),
                status=np.asarray(f["status"][()], dtype=int),
                message=np.array([_text(s) for s in f["message"][()]], dtype=object),
                steps=np.asarray(f["steps"][()], dtype=np.int64),
                events={k: np.asarray(f["events"][k][()], dtype=np.int64) for k in order["events"]},
                precision=prec,
                study=json.loads(f.attrs["study"]),
                metadata=json.loads(f.attrs["metadata"]),
            )


def load_sweep(path: str | Path) -> SweepResult:
    """Read a sweep file written by :func:`run_sweep` or :meth:`SweepResult.save`."""
    return SweepResult.load(path)


@dataclass(frozen=True)
class Layout:
    """The columns every member fills: from the first member's model.

    ``drift``: the conserved monitors; ``final``: the result variables; ``events``: the
    recorded events; ``n_times``: the output times.
    """

    drift: tuple[str, ...]
    final: tuple[str, ...]
    events: tuple[str, ...]
    n_times: int


@dataclass
class Chunk:
    """What :func:`propagate_members` computed for some members (rows in the order given).

    ``final`` is float64 in double precision and decimal text otherwise (so that a chunk
    crosses process boundaries without heyoka's extended types); ``paths`` counts the members
    by how they were integrated, ``why`` says why a path was taken.
    """

    index: np.ndarray
    status: np.ndarray
    message: list[str]
    steps: np.ndarray
    drift: dict[str, np.ndarray]
    final: np.ndarray
    events: dict[str, np.ndarray]
    paths: dict[str, int] = field(default_factory=dict)
    why: dict[str, str] = field(default_factory=dict)
    compile_seconds: float = 0.0

    @classmethod
    def failed(
        cls, members: Sequence[Member], layout: Layout, prec: Precision, message: str
    ) -> Chunk:
        """Every member of a task that could not run (a lost worker, say), marked failed."""
        n = len(members)
        return cls(
            index=np.array([i for i, _ in members], dtype=np.int64),
            status=np.full(n, FAILED),
            message=[message] * n,
            steps=np.zeros(n, dtype=np.int64),
            drift={k: np.full((n, layout.n_times), np.nan) for k in layout.drift},
            final=nan_final(n, len(layout.final), prec),
            events={k: np.zeros(n, dtype=np.int64) for k in layout.events},
        )


def nan_final(n: int, width: int, prec: Precision) -> np.ndarray:
    if prec.kind == "double":
        return np.full((n, width), np.nan)
    return np.full((n, width), "nan", dtype=object)


# ---------------------------------------------------------------------- internals: the file
def empty_result(study: Study, members: list, layout: Layout, prec: Precision) -> SweepResult:
    n = len(members)
    columns = list(zip(*members, strict=True)) if members else [[] for _ in study.parameters]
    grid = Scene.from_dict(study.scene).output.time_grid(prec)
    return SweepResult(
        t=grid,
        parameters={
            p.name: prec.array(column) for p, column in zip(study.parameters, columns, strict=True)
        },
        drift={k: np.full((n, layout.n_times), np.nan) for k in layout.drift},
        final_names=layout.final,
        final_state=nan_final(n, len(layout.final), prec)
        if prec.kind == "double"
        else prec.from_text(nan_final(n, len(layout.final), prec)),
        status=np.full(n, NOT_RUN),
        message=np.array(["not run"] * n, dtype=object),
        steps=np.zeros(n, dtype=np.int64),
        events={k: np.zeros(n, dtype=np.int64) for k in layout.events},
        precision=prec,
        study=study.to_dict(),
    )


def fill_chunk(result: SweepResult, part: Chunk, prec: Precision) -> None:
    rows = part.index
    result.status[rows] = part.status
    result.message[rows] = part.message
    result.steps[rows] = part.steps
    for name, d in part.drift.items():
        result.drift[name][rows] = d
    for name, c in part.events.items():
        result.events[name][rows] = c
    if len(rows):
        result.final_state[rows] = (
            part.final if prec.kind == "double" else prec.from_text(part.final)
        )


def _create(f: Any, result: SweepResult) -> None:
    from ..core.result import string_dtype, write_array

    prec = result.precision
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["precision"] = json.dumps(prec.to_spec())
    f.attrs["study"] = json.dumps(result.study)
    f.attrs["metadata"] = json.dumps(result.metadata)
    f.attrs["order"] = json.dumps(
        {
            "parameters": list(result.parameters),
            "drift": list(result.drift),
            "events": list(result.events),
        }
    )
    write_array(f, "t", result.t, prec)
    g = f.create_group("parameters")
    for name, column in result.parameters.items():
        write_array(g, name, column, prec)
    g = f.create_group("drift")
    for name, d in result.drift.items():
        g.create_dataset(name, data=d, dtype=np.float64)
    write_array(f, "final_state", result.final_state, prec)
    f["final_state"].attrs["names"] = json.dumps(list(result.final_names))
    f.create_dataset("status", data=np.asarray(result.status, dtype=np.int8))
    f.create_dataset("message", data=np.asarray(result.message, dtype=object), dtype=string_dtype())
    f.create_dataset("steps", data=np.asarray(result.steps, dtype=np.int64))
    g = f.create_group("events")
    for name, c in result.events.items():
        g.create_dataset(name, data=np.asarray(c, dtype=np.int64))


class Writer:
    """The sweep file, created with every member ``NOT_RUN`` and filled chunk by chunk.

    It is filled under a temporary name beside ``path`` and put in place by :meth:`close`
    (also when the sweep stops midway): a sweep killed outright leaves the previous file, and
    so does one whose writing failed (a full disk: :class:`OutputError`).
    """

    def __init__(self, path: str | Path, result: SweepResult) -> None:
        import h5py

        self.path = path
        self.staged = Staged(path)
        self.file = None
        try:
            self.file = h5py.File(self.staged.tmp, "w")
            _create(self.file, result)
            self.file.flush()
        except BaseException as exc:
            self._abandon(exc)

    def _abandon(self, exc: BaseException) -> None:
        """Drop the temporary (the previous file stays) and raise ``exc``."""
        if self.file is not None:
            self.file.close()
            self.file = None
        self.staged.discard()
        if isinstance(exc, OSError):
            raise OutputError.failed_write(self.path, exc) from exc
        raise exc

    def write(self, part: Chunk, prec: Precision) -> None:
        try:
            self._write(part, prec)
        except OSError as exc:
            self._abandon(exc)

    def _write(self, part: Chunk, prec: Precision) -> None:
        f, rows = self.file, np.asarray(part.index)
        if f is None or not len(rows):
            return
        # h5py's fancy indexing wants increasing indices.
        order = np.argsort(rows)
        rows = rows[order]
        f["status"][rows] = np.asarray(part.status, dtype=np.int8)[order]
        f["message"][rows] = np.asarray(part.message, dtype=object)[order]
        f["steps"][rows] = np.asarray(part.steps)[order]
        for name, d in part.drift.items():
            f["drift"][name][rows] = d[order]
        for name, c in part.events.items():
            f["events"][name][rows] = c[order]
        final = part.final[order]
        f["final_state"][rows] = final if prec.kind == "double" else final.astype(object)
        f.flush()

    def close(self, metadata: dict[str, Any]) -> None:
        if self.file is None:  # abandoned after a failed write
            return
        try:
            self.file.attrs["metadata"] = json.dumps(metadata)
            seal(self.file)
            self.file.close()
        except BaseException as exc:
            self._abandon(exc)
        self.staged.commit()


def _text(s: Any) -> str:
    return s.decode() if isinstance(s, bytes) else str(s)


__all__ = ["FAILED", "NOT_RUN", "OK", "Chunk", "Layout", "SweepResult", "load_sweep"]
