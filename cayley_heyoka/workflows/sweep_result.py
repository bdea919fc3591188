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
from ..core.result import source_line
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

    def to_xarray(self, *, as_double: bool = False) -> Any:
        """The sweep as an :class:`xarray.Dataset`, as ``xarray.open_dataset(path,
        engine="h5netcdf")`` reads its file.

        Dimensions ``member``, ``time``, ``monitor`` (the conserved monitors), ``variable``
        (the result variables) and ``event``; each swept parameter is a coordinate over
        ``member`` (``ds["initial.rates[0]"]``). Data: ``drift`` (monitor, member, time), the
        relative drift (NaN after a member stopped); ``final_state`` (member, variable);
        ``status`` (0 completed, −1 failed, −2 not run), ``message``, ``steps``; ``events``
        (member, event), the occurrences. ``ds.drift.sel(monitor="energy")`` is one monitor's
        drift of every member.

        Parameters
        ----------
        as_double
            For a quad or multiprecision sweep, round the times, parameters and final states
            to float64 and say so (``attrs["rounded_from"]``); by default they keep their
            exact numbers and ``attrs["precision"]`` names the precision. (Drifts are float64
            in every precision.)

        Raises
        ------
        ImportError
            If xarray is not installed (``pip install "cayley_heyoka[xarray]"``).
        """
        from ..core.labelled import precision_attrs, require, values

        xr = require("xarray")
        prec = self.precision
        coords: dict[str, Any] = {
            "time": ("time", values(self.t, prec, as_double), {"long_name": "time"}),
            "member": ("member", np.arange(len(self)), {"long_name": "member of the sweep"}),
            "monitor": ("monitor", list(self.drift)),
            "variable": ("variable", list(self.final_names)),
            "event": ("event", list(self.events)),
        }
        for name, column in self.parameters.items():
            coords[name] = (
                "member",
                values(column, prec, as_double),
                {"long_name": f"swept parameter {name}"},
            )
        n, m = len(self), len(self.t)
        drift = np.stack(list(self.drift.values())) if self.drift else np.zeros((0, n, m))
        counts = np.stack(list(self.events.values()), axis=1) if self.events else np.zeros((n, 0))
        data = {
            "drift": (("monitor", "member", "time"), drift),
            "final_state": (("member", "variable"), values(self.final_state, prec, as_double)),
            "status": ("member", np.asarray(self.status, dtype=np.int8)),
            "message": ("member", np.asarray(self.message, dtype=str)),
            "steps": ("member", np.asarray(self.steps, dtype=np.int64)),
            "events": (("member", "event"), np.asarray(counts, dtype=np.int64)),
        }
        ds = xr.Dataset(data, coords=coords)
        for name, long_name in LONG_NAMES.items():
            ds[name].attrs["long_name"] = long_name
        ds.attrs.update(
            title=str(self.study.get("title") or ""),
            **precision_attrs(prec, as_double),
            study=json.dumps(self.study),
            completed=int(np.count_nonzero(self.completed)),
        )
        return ds

    def to_pandas(self, table: str = "members", *, as_double: bool = False) -> Any:
        """A table of the sweep as a :class:`pandas.DataFrame`.

        Parameters
        ----------
        table
            ``"members"``: one row per member (index ``member``): each swept parameter, the
            ``status``, ``message`` and ``steps``, ``final_drift_NAME`` for each conserved
            monitor (NaN where the member did not complete) and ``events_NAME``, the
            occurrences of each recorded event.
        as_double
            For a quad or multiprecision sweep, the parameters as float64 (said in
            ``frame.attrs``); by default their exact numbers.

        Raises
        ------
        ValueError
            If ``table`` is not ``"members"``.
        ImportError
            If pandas is not installed.
        """
        from ..core.labelled import choose, precision_attrs, require, values

        choose(table, {"members": None})
        pd = require("pandas")
        prec = self.precision
        columns: dict[str, Any] = {
            name: values(column, prec, as_double) for name, column in self.parameters.items()
        }
        columns.update(
            status=np.asarray(self.status, dtype=np.int8),
            message=np.asarray(self.message, dtype=str),
            steps=np.asarray(self.steps, dtype=np.int64),
        )
        for name in self.drift:
            columns[f"final_drift_{name}"] = np.where(
                self.completed, self.final_drift(name), np.nan
            )
        for name, counts in self.events.items():
            columns[f"events_{name}"] = np.asarray(counts, dtype=np.int64)
        frame = pd.DataFrame(columns, index=pd.RangeIndex(len(self), name="member"))
        frame.attrs.update(precision_attrs(prec, as_double))
        return frame

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
            if int(f.attrs["format_version"]) >= 3:
                order = json.loads(f.attrs["order"])
                t = read_array(f["time"], prec)
                parameters = {k: read_array(f[k], prec) for k in order["parameters"]}
                drift = {
                    k: np.asarray(f["drift"][i], dtype=np.float64)
                    for i, k in enumerate(order["drift"])
                }
                final_names = tuple(order["final"])
                counts = np.asarray(f["events"][()], dtype=np.int64)
                events = {k: counts[:, i].copy() for i, k in enumerate(order["events"])}
            else:  # format versions 1 and 2: groups of parameters, drifts and events
                order = json.loads(f.attrs["order"])
                t = read_array(f["t"], prec)
                parameters = {k: read_array(f["parameters"][k], prec) for k in order["parameters"]}
                drift = {k: np.asarray(f["drift"][k][()], dtype=np.float64) for k in order["drift"]}
                final_names = tuple(json.loads(f["final_state"].attrs["names"]))
                events = {
                    k: np.asarray(f["events"][k][()], dtype=np.int64) for k in order["events"]
                }
            return cls(
                t=t,
                parameters=parameters,
                drift=drift,
                final_names=final_names,
                final_state=read_array(f["final_state"], prec),
                status=np.asarray(f["status"][()], dtype=int),
                message=np.array([_text(s) for s in f["message"][()]], dtype=object),
                steps=np.asarray(f["steps"][()], dtype=np.int64),
                events=events,
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


#: What each array of a sweep is: the file's and the xarray view's ``long_name``.
LONG_NAMES = {
    "drift": "relative drift of each conserved monitor",
    "final_state": "the variables at the last output time",
    "status": "0 completed, -1 failed, -2 not run",
    "message": "why the member ended",
    "steps": "Taylor steps",
    "events": "occurrences of each recorded event",
}
#: Names the sweep file's layout takes for itself (a swept parameter may not take one).
LAYOUT_NAMES = (
    "time", "member", "monitor", "variable", "event", "drift", "final_state", "status",
    "message", "steps", "events",
)  # fmt: skip


def _create(f: Any, result: SweepResult) -> None:
    """The sweep file's netCDF-4 layout (format 3): dimensions ``member``, ``time``,
    ``monitor``, ``variable`` and ``event``; each swept parameter a coordinate over ``member``
    (named by the data variables' CF ``coordinates`` attribute)."""
    from ..core.result import label, string_dtype, write_array

    prec = result.precision
    names = list(result.parameters)
    if clash := sorted(set(LAYOUT_NAMES) & set(names)):
        raise ValueError(
            f"a swept parameter is named {', '.join(map(repr, clash))}, which the sweep file's "
            "layout keeps for itself"
        )
    f.attrs["format"] = FORMAT
    f.attrs["format_version"] = FORMAT_VERSION
    f.attrs["Conventions"] = "CF-1.10"
    f.attrs["title"] = str(result.study.get("title") or "")
    f.attrs["source"] = source_line(result.metadata)
    f.attrs["precision"] = json.dumps(prec.to_spec())
    f.attrs["study"] = json.dumps(result.study)
    f.attrs["metadata"] = json.dumps(result.metadata)
    f.attrs["order"] = json.dumps(
        {
            "parameters": names,
            "drift": list(result.drift),
            "events": list(result.events),
            "final": list(result.final_names),
        }
    )
    n = len(result.status)
    scales = {
        "time": write_array(f, "time", result.t, prec),
        "member": f.create_dataset("member", data=np.arange(n, dtype=np.int64)),
    }
    for dim, values in (
        ("monitor", result.drift),
        ("variable", result.final_names),
        ("event", result.events),
    ):
        scales[dim] = f.create_dataset(
            dim, data=np.array(list(values), dtype=object), dtype=string_dtype()
        )
    for dim, ds in scales.items():
        ds.make_scale(dim)
    label(scales["time"], "time")
    label(scales["member"], "member of the sweep")
    coordinates = " ".join(names)

    def over(ds: Any, dims: tuple[str, ...], long_name: str) -> None:
        for axis, dim in enumerate(dims):
            ds.dims[axis].attach_scale(scales[dim])
        label(ds, long_name)
        if "member" in dims and coordinates:
            ds.attrs["coordinates"] = coordinates

    for name, column in result.parameters.items():
        over(write_array(f, name, column, prec), ("member",), f"swept parameter {name}")
    drift = np.stack([result.drift[k] for k in result.drift]) if result.drift else None
    ds = f.create_dataset(
        "drift",
        data=drift if drift is not None else np.zeros((0, n, len(result.t))),
        dtype=np.float64,
    )
    over(ds, ("monitor", "member", "time"), LONG_NAMES["drift"])
    ds = write_array(f, "final_state", result.final_state, prec)
    over(ds, ("member", "variable"), LONG_NAMES["final_state"])
    ds = f.create_dataset("status", data=np.asarray(result.status, dtype=np.int8))
    over(ds, ("member",), LONG_NAMES["status"])
    ds = f.create_dataset(
        "message", data=np.asarray(result.message, dtype=object), dtype=string_dtype()
    )
    over(ds, ("member",), LONG_NAMES["message"])
    ds = f.create_dataset("steps", data=np.asarray(result.steps, dtype=np.int64))
    over(ds, ("member",), LONG_NAMES["steps"])
    counts = np.stack([result.events[k] for k in result.events], axis=1) if result.events else None
    ds = f.create_dataset(
        "events",
        data=counts if counts is not None else np.zeros((n, 0)),
        dtype=np.int64,
    )
    over(ds, ("member", "event"), LONG_NAMES["events"])


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
            self.file = h5py.File(self.staged.tmp, "w", track_order=True)
            _create(self.file, result)
            self.order = json.loads(self.file.attrs["order"])
            self.file.flush()
        except BaseException as exc:
            self._abandon(exc)

    def discard(self) -> None:
        """Drop the temporary: the previous file stays."""
        if self.file is not None:
            self.file.close()
            self.file = None
        self.staged.discard()

    def _abandon(self, exc: BaseException) -> None:
        """Drop the temporary (the previous file stays) and raise ``exc``."""
        self.discard()
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
        monitors, events = self.order["drift"], self.order["events"]
        for name, d in part.drift.items():
            f["drift"][monitors.index(name), rows, :] = d[order]
        for name, c in part.events.items():
            f["events"][rows, events.index(name)] = c[order]
        final = part.final[order]
        f["final_state"][rows] = final if prec.kind == "double" else final.astype(object)
        f.flush()

    def close(self, metadata: dict[str, Any]) -> None:
        if self.file is None:  # abandoned after a failed write
            return
        try:
            self.file.attrs["metadata"] = json.dumps(metadata)
            self.file.attrs["source"] = source_line(metadata)
            seal(self.file)
            self.file.close()
        except BaseException as exc:
            self._abandon(exc)
        self.staged.commit()


def _text(s: Any) -> str:
    return s.decode() if isinstance(s, bytes) else str(s)


__all__ = ["FAILED", "NOT_RUN", "OK", "Chunk", "Layout", "SweepResult", "load_sweep"]
