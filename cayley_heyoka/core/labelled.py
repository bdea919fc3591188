"""Labelled views of results for the scientific Python stack: xarray datasets, pandas tables.

The views carry what the result files carry (format 3, :mod:`cayley_heyoka.core.result`): the
dimension ``time``, ``component`` for vector monitors, each variable's ``long_name`` (its
family's description) and ``units`` where the scene's ``output.units`` gives one, and the run's
precision in the attributes.

**Precision is never lost silently.** A double result gives float64 arrays. A quad or
multiprecision result gives object arrays of its own numbers (heyoka ``real128`` or ``real``),
exact, with ``attrs["precision"]`` saying which; ``as_double=True`` asks for the float64 view
explicitly, and the view then says ``precision = "double"`` and ``rounded_from = "quad"`` (or
``"mpfr256"``, …). Neither xarray nor pandas is needed by the library itself: they are imported
when a view is asked for (``pip install "cayley_heyoka[xarray]"``).
"""

from __future__ import annotations

import json
import warnings
from typing import TYPE_CHECKING, Any

import numpy as np

from .names import COMPONENTS, columns, component_dim

if TYPE_CHECKING:  # only for annotations: the views import them when called
    import pandas as pd
    import xarray as xr

#: What the views take: a :class:`~cayley_heyoka.core.result.Result` (not imported here, so
#: that the result module may import this one).
Result = Any


def require(module: str) -> Any:
    """Import ``xarray`` or ``pandas``, or say how to install it."""
    import importlib

    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(
            f"labelled views of results need {module}: pip install 'cayley_heyoka[xarray]' "
            f"(xarray, pandas and h5netcdf)"
        ) from exc


def values(arr: np.ndarray, precision: Any, as_double: bool, name: str) -> np.ndarray:
    """``arr`` (the values of ``name``) as the view holds it: float64 in double or when asked
    (:func:`to_double`), else the exact numbers."""
    if precision.kind == "double":
        return np.asarray(arr, dtype=np.float64)
    if as_double:
        hint = "as_double=True cannot hold it (the exact view, as_double=False, can)"
        return to_double(arr, f"{name} in {precision.name}", hint)
    return np.asarray(arr, dtype=object)


#: Number types that float64 holds exactly (heyoka's real128 and real are numpy floats too).
_NARROW = (np.float16, np.float32, np.float64)


def to_double(arr: Any, name: str, hint: str = "") -> np.ndarray:
    """``arr``'s numbers, of any precision, each rounded to the nearest float64.

    A finite number beyond double's range (|x| ≥ 2¹⁰²⁴, ~1.8e308) has no nearest double: it
    raises instead of becoming ±inf. One below double's smallest (~4.9e-324) rounds to the
    nearest double, 0 or a subnormal, as every rounding does (an absolute error of at most
    half the smallest subnormal). NaN and ±inf stay as they are.

    Raises
    ------
    ValueError
        Naming ``name``, the first such number and where it is (then ``hint``).
    """
    given = np.asarray(arr)
    if given.dtype.kind in "biu" or any(given.dtype == t for t in _NARROW):
        return np.asarray(given, dtype=np.float64)
    with np.errstate(over="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an overflow is reported below
        out = np.asarray(given, dtype=np.float64)
    for i in np.flatnonzero(np.isinf(out)):
        value = given.flat[i]
        if value - value == 0:  # finite: x − x is NaN for ±inf
            at = ", ".join(map(str, np.unravel_index(i, given.shape)))
            raise ValueError(
                f"{name}: [{at}] is {value}, beyond double's range (±1.8e308)"
                + (f": {hint}" if hint else "")
            )
    return out


def precision_attrs(precision: Any, as_double: bool) -> dict[str, str]:
    """What the view's numbers are: ``precision``, and ``rounded_from`` for a double view of
    an extended-precision result."""
    if precision.kind != "double" and as_double:
        return {"precision": "double", "rounded_from": precision.name}
    return {"precision": precision.name}


def variable_attrs(result: Result, name: str, role: str) -> dict[str, str]:
    attrs = {"role": role}
    if text := result.describe(name):
        attrs["long_name"] = text
    if unit := result.unit(name):
        attrs["units"] = unit
    return attrs


def time_attrs(result: Result) -> dict[str, str]:
    attrs = {"long_name": "time"}
    if unit := result.unit("time"):
        attrs["units"] = unit
    return attrs


def result_dataset(result: Result, *, as_double: bool = False) -> xr.Dataset:
    """:meth:`Result.to_xarray`: every variable and monitor over ``time``."""
    xr = require("xarray")
    prec = result.precision
    coords: dict[str, Any] = {
        "time": ("time", values(result.t, prec, as_double, "time"), time_attrs(result))
    }
    data: dict[str, Any] = {}
    for role, arrays in (("variable", result.variables), ("monitor", result.monitors)):
        for name, arr in arrays.items():
            dims: tuple[str, ...] = ("time",)
            if arr.ndim > 1:
                dim = component_dim(arr.shape[1])
                dims = ("time", dim)
                if dim == "component":
                    coords["component"] = ("component", list(COMPONENTS))
            view = values(arr, prec, as_double, name)
            data[name] = (dims, view, variable_attrs(result, name, role))
    attrs = {
        "title": str(result.scene.get("title") or ""),
        **precision_attrs(prec, as_double),
        "status": int(result.status),
        "success": int(result.success),
        "message": result.message,
        "conserved": list(result.conserved),
        "counters": json.dumps(result.counters),
        "scene": json.dumps(result.scene),
        "events": list(result.events),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def result_frame(result: Result, *, as_double: bool = False) -> pd.DataFrame:
    """``Result.to_pandas("outputs")``: one row per output time, one column per variable and
    monitor (a vector monitor's components as ``NAME_x``, ``NAME_y``, ``NAME_z``)."""
    pd = require("pandas")
    prec = result.precision
    table: dict[str, np.ndarray] = {}
    for arrays in (result.variables, result.monitors):
        for name, arr in arrays.items():
            v = values(arr, prec, as_double, name)
            flat = v.reshape(v.shape[0], int(np.prod(v.shape[1:])))
            for i, label in enumerate(columns(name, v.shape[1:])):
                if label in table or label == "time":
                    raise ValueError(f"two columns of the table would be named {label!r}")
                table[label] = flat[:, i]
    index = pd.Index(values(result.t, prec, as_double, "time"), name="time")
    frame = pd.DataFrame(table, index=index)
    frame.attrs.update(precision_attrs(prec, as_double))
    return frame


def events_frame(result: Result, *, as_double: bool = False) -> pd.DataFrame:
    """``Result.to_pandas("events")``: one row per event occurrence, in time order, with
    columns ``event``, ``time``, ``direction`` (+1 up, −1 down) and ``label``."""
    pd = require("pandas")
    prec = result.precision
    rows = []
    for name, log in result.events.items():
        times = values(log.time, prec, as_double, f"events.{name}.time")
        for when, direction, label in zip(times, log.direction, log.label, strict=True):
            rows.append((name, when, int(direction), str(label)))
    rows.sort(key=lambda row: float(row[1]))
    frame = pd.DataFrame(rows, columns=["event", "time", "direction", "label"])
    if not rows:  # an empty frame of the same shape, numbers typed
        frame = frame.astype({"direction": "int64"})
    frame.attrs.update(precision_attrs(prec, as_double))
    return frame


def choose(table: str, tables: dict[str, Any]) -> Any:
    """The builder of ``table``, or a ValueError naming the tables there are."""
    if table not in tables:
        raise ValueError(f"table must be one of {', '.join(map(repr, tables))}, got {table!r}")
    return tables[table]
