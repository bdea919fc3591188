"""The result of a run: times, named variables, events, monitored quantities; HDF5 in and out.

The shape follows :func:`scipy.integrate.solve_ivp`'s result (``t``, ``y``, ``status``,
``message``, ``success``) so it feels familiar, with names on top: ``result["p"]``.

Arrays hold numbers of the run's precision (``float``, heyoka ``real128`` or ``real``). In the
HDF5 file, double arrays are stored as float64 and extended-precision arrays as decimal text
with enough digits to load back bit-for-bit.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .files import FORMAT_VERSION, FORMATS, open_ours, write_hdf5
from .labelled import time_attrs, variable_attrs
from .names import COMPONENTS, component_dim, layout_holder, name_problem
from .precision import Precision


def relative_drift(m: np.ndarray, vector: bool) -> np.ndarray:
    """Drifts of monitored values from their first: ``m`` is ``(members, times)``, or
    ``(members, times, k)`` for a ``vector`` of k components; each member's change divided by
    its initial value's magnitude (a vector's norm), or the change itself where that is zero
    (:meth:`Result.drift` of one member, the drifts of a sweep's members at once)."""
    if m.shape[1] == 0:
        return m
    m0 = m[:, :1]
    scale = np.sqrt(np.sum(m0 * m0, axis=-1, keepdims=True)) if vector else abs(m0)
    one = scale * 0 + 1  # in the values' own type (real128, real)
    return (m - m0) / np.where(scale == 0, one, scale)


@dataclass
class EventLog:
    """Occurrences of one event.

    Attributes
    ----------
    time
        Event times, in the run's precision.
    direction
        +1 where the event function crossed zero upwards, -1 downwards.
    label
        What fired, e.g. the body axis ``"x1"`` for an invariable-plane crossing.
    """

    time: np.ndarray
    direction: np.ndarray
    label: np.ndarray

    def __len__(self) -> int:
        return len(self.time)

    def where(self, label: str) -> np.ndarray:
        """Times of the occurrences carrying ``label``."""
        return self.time[self.label == label]


@dataclass
class Result:
    """The outcome of :func:`cayley_heyoka.run`.

    Attributes
    ----------
    t
        Output times, in the run's precision.
    variables
        Each state variable and derived coordinate on the output grid, by name.
    monitors
        Monitored quantities on the output grid (shape ``(n,)`` or ``(n, 3)``).
    conserved
        Names of the monitors that the exact flow conserves for this scene.
    events
        Event occurrences by event name.
    precision
        The floating-point precision of the run.
    status
        0 if every output time was reached, -1 if the run stopped early (a non-finite state,
        a family's stop, the step budget), -2 if it was interrupted (Ctrl-C, SIGTERM). A
        stopped run raises unless ``run(..., raise_on_failure=False)``; its result, and a
        file saved from one, keep the status.
    message
        Why the run ended.
    counters
        Integer tallies: ``steps``, ``rebasings`` (chart changes of the attitude), ...
    scene
        The scene, as the plain dictionary it can be rebuilt from.
    metadata
        Versions, wall time and compile time.
    """

    t: np.ndarray
    variables: dict[str, np.ndarray]
    monitors: dict[str, np.ndarray] = field(default_factory=dict)
    conserved: tuple[str, ...] = ()
    events: dict[str, EventLog] = field(default_factory=dict)
    precision: Precision = field(default_factory=Precision)
    status: int = 0
    message: str = ""
    counters: dict[str, int] = field(default_factory=dict)
    scene: dict[str, Any] = field(default_factory=dict)
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        """Whether every output time was reached (``status == 0``)."""
        return self.status == 0

    def __repr__(self) -> str:
        """One line: the scene, the span, the steps, how it ended, the worst conserved drift
        (REBOUND's ``Simulation`` and scipy's ``solve_ivp`` result are the models)."""
        title = self.scene.get("title") or "untitled"
        n = len(self.t)
        span = f"t = {float(self.t[0]):g} … {float(self.t[-1]):g}" if n else "no output"
        ended = "completed" if self.success else "stopped early"
        worst = ""
        drifts = {}
        for name in self.conserved if n else ():
            value, _ = self.largest_drift(name)
            if not math.isnan(value):
                drifts[name] = value
        if drifts:
            name = max(drifts, key=drifts.__getitem__)
            worst = f", worst drift {name} {drifts[name]:.1e}"
        steps = self.counters.get("steps")
        stepped = f", {steps} steps" if steps is not None else ""
        return (
            f"<Result {title!r}: {self.precision.name}, {n} outputs, {span}{stepped}, "
            f"{ended}{worst}>"
        )

    @property
    def names(self) -> list[str]:
        """Variable names, in the row order of :attr:`y`."""
        return list(self.variables)

    @property
    def y(self) -> np.ndarray:
        """The variables stacked as rows, shape ``(len(names), len(t))``, like ``solve_ivp``."""
        return np.array([self.variables[k] for k in self.variables])

    def __getitem__(self, name: str) -> np.ndarray:
        if name in self.variables:
            return self.variables[name]
        if name in self.monitors:
            return self.monitors[name]
        known = ", ".join([*self.variables, *self.monitors])
        raise KeyError(f"no variable or monitor named {name!r}; known: {known}")

    def drift(self, name: str) -> np.ndarray:
        """Relative drift of a monitored quantity from its initial value.

        Scalars: ``(m(t) - m(0)) / |m(0)|``; vectors: each component's change divided by the
        initial vector's norm. Where the initial value is zero the change itself is returned.

        Raises
        ------
        KeyError
            ``name`` is not a monitor (the message lists the monitors).
        """
        m = self.monitors.get(name)
        if m is None:
            known = ", ".join(self.monitors) or "none"
            what = "a variable, not a monitor" if name in self.variables else "no monitor"
            raise KeyError(f"drift({name!r}): {what}; the monitors are: {known}")
        return relative_drift(m[None], vector=m.ndim > 1)[0]

    def largest_drift(self, name: str) -> tuple[float, Any]:
        """The largest magnitude of a monitor's relative drift over the run (largest component
        of a vector) and the output time where it occurs (the first, if several; NaN drifts
        are skipped).

        Examples
        --------
        >>> value, at = result.largest_drift("energy")  # doctest: +SKIP
        """
        d = np.abs(np.asarray(self.drift(name), dtype=float))
        if d.ndim > 1:
            d = d.max(axis=tuple(range(1, d.ndim)))
        if not d.size or np.isnan(d).all():
            return float("nan"), None
        k = int(np.nanargmax(d))
        return float(d[k]), self.t[k]

    def final_drifts(self) -> dict[str, float]:
        """Relative drift at the last output time of each conserved monitor (largest component)."""
        out = {}
        for name in self.conserved:
            d = self.drift(name)
            out[name] = float(np.max(np.abs(d[-1]))) if len(d) else float("nan")
        return out

    # ------------------------------------------------------------------ labelled views
    def to_xarray(self, *, as_double: bool = False) -> Any:
        """The result as an :class:`xarray.Dataset` over the dimension ``time``.

        Every variable and monitor is a data variable (a vector monitor over ``(time,
        component)``, components ``x, y, z``) with its ``long_name`` and, where the scene's
        ``output.units`` gives one, ``units``; the attributes hold the title, precision,
        status, message, conserved monitors, counters and the scene (JSON). It matches what
        ``xarray.open_dataset(path, engine="h5netcdf")`` reads from the saved file (there, an
        extended-precision result is its exact decimal text). Events: ``to_pandas("events")``.

        Parameters
        ----------
        as_double
            For a quad or multiprecision result: round every number to float64, and say so
            (``attrs["rounded_from"]``). By default such a result's arrays hold its own exact
            numbers (object arrays of heyoka ``real128`` or ``real``), and
            ``attrs["precision"]`` names the precision. A double result is float64 either way.

        Raises
        ------
        ImportError
            If xarray is not installed (``pip install "cayley_heyoka[xarray]"``).
        """
        from .labelled import result_dataset

        return result_dataset(self, as_double=as_double)

    def to_pandas(self, table: str = "outputs", *, as_double: bool = False) -> Any:
        """A table of the result as a :class:`pandas.DataFrame`.

        Parameters
        ----------
        table
            ``"outputs"``: one row per output time (index ``time``), one column per variable
            and monitor, a vector monitor's components as ``NAME_x``, ``NAME_y``,
            ``NAME_z``. ``"events"``: one row per event occurrence in time order, columns
            ``event``, ``time``, ``direction`` (+1 up, −1 down) and ``label``.
        as_double
            As for :meth:`to_xarray`: extended precision stays exact (object columns) unless
            this asks for float64; ``frame.attrs["precision"]`` says which.

        Raises
        ------
        ValueError
            If ``table`` is not one of the tables above.
        ImportError
            If pandas is not installed.
        """
        from .labelled import choose, events_frame, result_frame

        build = choose(table, {"outputs": result_frame, "events": events_frame})
        return build(self, as_double=as_double)

    # ------------------------------------------------------------------ HDF5
    def save(self, path: str | Path) -> None:
        """Write the result to an HDF5 file (layout: ``docs/scenes.md``, "Files").

        The file is written under a temporary name and renamed into place, with a checksum
        of its contents (:mod:`cayley_heyoka.core.files`): a previous file at ``path`` is replaced
        whole or not at all.

        Raises
        ------
        OutputError
            When the file cannot be written (the previous one, if any, is left as it was).
        """
        write_hdf5(path, self.fill)

    def fill(self, f: Any) -> None:
        """Write the result into an open HDF5 file, in the netCDF-4 layout of format 3.

        The root group holds the output times as the dimension ``time`` and every variable
        and monitor as a dataset over it (a vector monitor over ``(time, component)``), each
        with a ``long_name`` and, where the scene gives them, ``units``; each event is a
        group ``events/NAME`` over its own ``time``. So ``xarray.open_dataset(path,
        engine="h5netcdf")`` (or any netCDF reader) sees named dimensions. Extended-precision
        arrays are decimal text (attribute ``encoding = "decimal"``), exact.
        """
        prec = self.precision
        check_names(self)
        f.attrs["format"] = FORMATS["result"]
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["Conventions"] = "CF-1.10"
        f.attrs["title"] = str(self.scene.get("title") or "")
        f.attrs["source"] = source_line(self.metadata)
        f.attrs["precision"] = json.dumps(prec.to_spec())
        f.attrs["status"] = self.status
        f.attrs["message"] = self.message
        f.attrs["counters"] = json.dumps(self.counters)
        f.attrs["conserved"] = json.dumps(list(self.conserved))
        f.attrs["scene"] = json.dumps(self.scene)
        f.attrs["metadata"] = json.dumps(self.metadata)
        f.attrs["order"] = json.dumps(
            {
                "variables": list(self.variables),
                "monitors": list(self.monitors),
                "events": list(self.events),
            }
        )
        time = write_array(f, "time", self.t, prec)
        time.make_scale("time")
        # The attributes of the labelled views, so that the file and to_xarray() agree.
        time.attrs.update(time_attrs(self))
        for role, arrays in (("variable", self.variables), ("monitor", self.monitors)):
            for name, arr in arrays.items():
                ds = write_array(f, name, arr, prec)
                ds.attrs.update(variable_attrs(self, name, role))
                ds.dims[0].attach_scale(time)
                if ds.ndim > 1:
                    ds.dims[1].attach_scale(component_scale(f, ds.shape[1]))
        events = f.create_group("events")
        for name, log in self.events.items():
            g = events.create_group(name)
            when = write_array(g, "time", log.time, prec)
            when.make_scale("time")
            label(when, f"times of the event {name}", self.unit("time"))
            direction = g.create_dataset("direction", data=np.asarray(log.direction, dtype=np.int8))
            label(direction, "+1 where the event function crossed zero upwards, -1 downwards")
            labels = g.create_dataset(
                "label", data=np.asarray(log.label, dtype=object), dtype=string_dtype()
            )
            label(labels, "what fired")
            for ds in (direction, labels):
                ds.dims[0].attach_scale(when)

    def describe(self, name: str) -> str | None:
        """What the variable or monitor ``name`` is, in its family's words (None if the family
        does not say, is not installed here, or fails to say: a description is a label, and
        a result is saved without it)."""
        from .errors import SceneError
        from .families import FAMILIES, family_of

        try:
            family = FAMILIES[family_of(self.scene)]
            return family.variables(self.scene, name) if family.variables is not None else None
        except SceneError:
            return None

    def unit(self, name: str) -> str | None:
        """The unit the scene gives ``name`` (``"time"`` for the times) in ``output.units``."""
        units = self.scene.get("output", {}).get("units", {})
        return units.get(name) if isinstance(units, dict) else None

    @classmethod
    def load(cls, path: str | Path) -> Result:
        """Read a result written by :meth:`save`; extended-precision values load exactly.

        Raises
        ------
        ResultFileError
            Naming the file and what is wrong: missing, not HDF5, not a result file, damaged
            (its checksum differs) or incomplete. Files of format version 1 load unchecked;
            files of versions 1 and 2 (groups ``variables`` and ``monitors``, times ``t``)
            load as they were written.
        """
        with open_ours(path, "result") as f:
            prec = Precision.from_spec(json.loads(f.attrs["precision"]))
            if int(f.attrs["format_version"]) >= 3:
                order = json.loads(f.attrs["order"])
                t = read_array(f["time"], prec)
                variables = {k: read_array(f[k], prec) for k in order["variables"]}
                monitors = {k: read_array(f[k], prec) for k in order["monitors"]}
                event_names = order["events"]
            else:
                t = read_array(f["t"], prec)
                variables = {
                    k: read_array(f["variables"][k], prec)
                    for k in json.loads(f["variables"].attrs["order"])
                }
                monitors = {
                    k: read_array(f["monitors"][k], prec)
                    for k in json.loads(f["monitors"].attrs["order"])
                }
                event_names = json.loads(f["events"].attrs["order"])
            events = {}
            for name in event_names:
                g = f["events"][name]
                events[name] = EventLog(
                    time=read_array(g["time"], prec),
                    direction=g["direction"][()].astype(int),
                    label=np.array([_text(s) for s in g["label"][()]], dtype=str),
                )
            return cls(
                t=t,
                variables=variables,
                monitors=monitors,
                conserved=tuple(json.loads(f.attrs["conserved"])),
                events=events,
                precision=prec,
                status=int(f.attrs["status"]),
                message=str(f.attrs["message"]),
                counters=json.loads(f.attrs["counters"]),
                scene=json.loads(f.attrs["scene"]),
                metadata=json.loads(f.attrs["metadata"]),
            )


def check_names(result: Result) -> None:
    """Refuse, before writing, a result whose names a file cannot hold (one built in Python:
    a run's names were checked when its scene was, :mod:`.names`)."""
    if twice := sorted(set(result.variables) & set(result.monitors)):
        raise ValueError(f"{twice[0]!r} is both a variable and a monitor: a file holds one")
    for kind, names in (
        ("output or monitor", [*result.variables, *result.monitors]),
        ("event", list(result.events)),
    ):
        for name in names:
            if problem := name_problem(name):
                raise ValueError(f"the {kind} {name!r} cannot be saved: {problem}")
            if kind != "event" and (holder := layout_holder(name)):
                raise ValueError(f"the {kind} {name!r} cannot be saved: it is {holder}")


def label(ds: Any, long_name: str | None, units: str | None = None) -> None:
    """Set a dataset's netCDF/CF ``long_name`` and ``units`` (each only if known)."""
    if long_name:
        ds.attrs["long_name"] = long_name
    if units:
        ds.attrs["units"] = units


def component_scale(f: Any, size: int) -> Any:
    """The dimension of a ``size``-vector's components: ``component`` (x, y, z) for three,
    ``component_N`` (unlabelled) otherwise; created on first use."""
    name = component_dim(size)
    if name not in f:
        if size == len(COMPONENTS):
            ds = f.create_dataset(
                name, data=np.array(COMPONENTS, dtype=object), dtype=string_dtype()
            )
        else:
            ds = f.create_dataset(name, data=np.arange(size, dtype=np.int64))
        ds.make_scale(name)
        label(ds, "vector component (space axes)" if size == len(COMPONENTS) else "component")
    return f[name]


def source_line(metadata: dict[str, Any]) -> str:
    """The CF ``source`` attribute: what wrote the file, with versions."""
    names = ("cayley_heyoka", "heyoka", "numpy")
    return ", ".join(f"{k} {metadata[k]}" for k in names if k in metadata) or "cayley_heyoka"


@functools.cache
def _versions() -> tuple[tuple[str, str], ...]:
    from importlib import metadata  # here, not above: ~15 ms that `info` does not need

    import heyoka

    try:
        ours = metadata.version("cayley_heyoka")
    except metadata.PackageNotFoundError:  # running from a source tree
        ours = "unknown"
    return (("cayley_heyoka", ours), ("heyoka", heyoka.__version__), ("numpy", np.__version__))


def versions() -> dict[str, str]:
    """Versions of this library and of the engine, for result metadata.

    Read once per process: looking up package metadata costs ~0.5 ms, a third of a short
    run's fixed cost.
    """
    return dict(_versions())


def string_dtype():
    """h5py's UTF-8 string type (labels, messages, decimal text)."""
    import h5py

    return h5py.string_dtype(encoding="utf-8")


def write_array(group: Any, name: str, arr: np.ndarray, prec: Precision) -> Any:
    """Write ``arr`` into an HDF5 group: float64 in double, else exact decimal text; returns
    the dataset."""
    if prec.kind == "double":
        return group.create_dataset(name, data=np.asarray(arr, dtype=np.float64))
    ds = group.create_dataset(name, data=prec.to_text(arr), dtype=string_dtype())
    ds.attrs["encoding"] = "decimal"
    ds.attrs["precision"] = prec.name
    return ds


def read_array(ds, prec: Precision) -> np.ndarray:
    """Inverse of :func:`write_array`: the values in ``prec``, bit for bit."""
    if ds.attrs.get("encoding") == "decimal":
        return prec.from_text(ds[()])
    return np.asarray(ds[()], dtype=np.float64)


def _text(s: Any) -> str:
    return s.decode() if isinstance(s, bytes) else str(s)
