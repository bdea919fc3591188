"""Test helpers: compare a run with a reference trajectory, or its drift with a golden envelope.

Two checks for test suites, ours or yours, each raising :class:`AssertionError` with a message
that says where and by how much:

* :func:`assert_trajectory_close` compares the variables of a run with a reference result
  (a higher-precision run, or a file written by ``cayley-heyoka reference`` whose certified
  error bounds widen the allowed difference), in the higher of the two precisions.
* :func:`assert_drift_within` compares the drift of the conserved quantities with a golden
  :class:`DriftEnvelope`: the largest drift in log-spaced time windows, in units of the
  precision's ε. Single samples of a drift differ between machines (CPU, LLVM, libm change the
  round-off, not its size); the envelope of a window does not move by more than a small factor.

The pytest plugin (:mod:`cayley_heyoka.workflows.pytest_plugin`) wraps the second in a
``drift_golden`` fixture that writes the golden files under ``--update-golden``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import mpmath
import numpy as np

from ..core.exact import difference, exact, exact_array, is_nan
from ..core.precision import Precision
from ..core.result import Result

DRIFT_FORMAT = "cayley_heyoka.drift"
DRIFT_FORMAT_VERSION = 1

#: Defaults of :func:`assert_drift_within`, from ``validation/drift_margins.py`` (REPORT.md,
#: "drift_margins"): over 24 re-runs of every bundled scene with conserved quantities, the
#: initial state moved by 3 to 72 ε (another round-off realisation, as another CPU or LLVM
#: version gives), no window needed a factor above 4.2 over the golden run above a floor of
#: 8 ε (the chaotic heavy top, whose golden drift is small; the other scenes at most 1.6). The
#: default doubles that worst case; a tolerance of 1e-11 instead of the default needs 212 to
#: 2510, still 25× beyond it (the free body and the tops; the planets' drift does not grow
#: with it).
DRIFT_FACTOR = 8.0
DRIFT_FLOOR = 8.0

#: Output times of two runs of one grid agree to this many ε of the coarser precision (relative
#: to the largest |t|): the grid is computed in each run's own precision.
_TIME_ULPS = 4


# ---------------------------------------------------------------------- trajectories
def assert_trajectory_close(
    result: Result | str | Path,
    reference: Result | str | Path,
    *,
    variables: Sequence[str] | str | None = None,
    rtol: float = 1e-9,
    atol: float = 1e-12,
) -> None:
    """Fail unless ``result`` follows ``reference`` within the allowed difference.

    At every output time and for every variable compared, ``|result - reference|`` must not
    exceed ``atol + rtol * |reference| + bound``, where ``bound`` is the certified absolute error
    bound of the reference at that time (the ``certificate`` group of a file written by
    ``cayley-heyoka reference``; zero when absent) — a proved bound for a closed-form reference
    (the free body, the projectile: ``certificate.proved``), an estimate otherwise. Differences
    are computed in the higher of the two precisions, from the exact values, so a quad run
    compared with a quad reference resolves differences far below double's ε. A value that
    is NaN in both (undefined there by design: an orbit's Θ and Σ on the tilted frame,
    docs/orbits.md) agrees; one that is NaN in one of them only fails
    (:mod:`cayley_heyoka.core.exact`).

    Parameters
    ----------
    result, reference
        :class:`~cayley_heyoka.core.result.Result` objects or paths of result files.
    variables
        Names to compare (variables or monitors); default: every variable both hold.
    rtol, atol
        Relative and absolute allowed differences, ≥ 0. The defaults suit a double run of an
        order-one scene against a higher-precision reference over tens of periods.

    Raises
    ------
    AssertionError
        The output times differ, or some difference exceeds the allowed one: the message names
        each failing variable, its worst point (time, output index, ``|Δ|`` against allowed), how
        many points fail out of how many, and the first failing time.
    ValueError, TypeError
        Bad arguments, or a certificate whose shape does not match its variable.
    """
    __tracebackhide__ = True  # pytest shows the caller's line and the message
    rtol = _nonneg_number(rtol, "rtol")
    atol = _nonneg_number(atol, "atol")
    res, _ = _load(result, "result")
    ref, certificate = _load(reference, "reference")
    names = _variable_names(res, ref, variables)
    _check_times(res, ref)

    failures = []
    for name in names:
        a, b = np.asarray(res[name]), np.asarray(ref[name])
        if a.shape != b.shape:
            raise AssertionError(
                f"variable {name!r}: result has shape {a.shape}, reference {b.shape}"
            )
        bound = certificate.get(name)
        if bound is not None and bound.shape != b.shape:
            raise ValueError(
                f"reference certificate {name!r} has shape {bound.shape}, its variable {b.shape}"
            )
        cmp = _compare(a, b, bound, res.precision, ref.precision, rtol, atol)
        if cmp.failing.any():
            failures.append(_describe_failure(name, cmp, ref.t))
    if failures:
        cert = "with" if certificate else "without"
        raise AssertionError(
            f"trajectory differs from the reference in {len(failures)} of {len(names)} "
            f"variables (allowed = atol + rtol·|reference| + certified bound; atol = {atol:g}, "
            f"rtol = {rtol:g}, reference {cert} certificate, precisions "
            f"{res.precision.name} vs {ref.precision.name}):\n" + "\n".join(failures)
        )


@dataclass
class _Comparison:
    diff: np.ndarray  # |Δ| as float64 (for reporting)
    allowed: np.ndarray  # as float64
    ratio: np.ndarray  # |Δ| / allowed (inf where allowed = 0 < |Δ|, or non-finite)
    failing: np.ndarray  # bool
    undefined: np.ndarray  # "result" or "reference" where NaN on that side only, else ""


def _compare(
    a: np.ndarray,
    b: np.ndarray,
    bound: np.ndarray | None,
    pa: Precision,
    pb: Precision,
    rtol: float,
    atol: float,
) -> _Comparison:
    """``a`` against ``b`` point by point. Where both are NaN (undefined in both results:
    :mod:`cayley_heyoka.core.exact`) they agree; a NaN on one side only fails."""
    extra = np.zeros(b.shape) if bound is None else bound
    nan_a = np.vectorize(is_nan, otypes=[bool])(a) if a.size else np.zeros(a.shape, bool)
    nan_b = np.vectorize(is_nan, otypes=[bool])(b) if b.size else np.zeros(b.shape, bool)
    undefined = np.where(nan_a & ~nan_b, "result", np.where(nan_b & ~nan_a, "reference", ""))
    if pa.kind == "double" and pb.kind == "double":
        with np.errstate(invalid="ignore"):
            diff = np.where(nan_a & nan_b, 0.0, np.abs(a - b))
            allowed = atol + rtol * np.where(nan_b, 0.0, np.abs(b)) + extra
            failing = ~(diff <= allowed) & ~(nan_a & nan_b)  # NaN on one side fails
        ratio = np.divide(diff, allowed, out=np.where(diff > 0, np.inf, 0.0), where=allowed > 0)
        ratio[~np.isfinite(diff)] = np.inf
        return _Comparison(diff, allowed, ratio, failing, undefined)
    # Exact inputs, and enough bits that |Δ| keeps its leading digits however small it is.
    work = max(pa.bits, pb.bits) + 32
    flat_a, flat_b = exact_array(a), exact_array(b)
    flat_x = np.ravel(extra)
    gaps = np.ravel(difference(a, b))
    n = len(flat_a)
    diff, allowed, ratio = gaps, np.empty(n), np.empty(n)
    failing = np.zeros(n, dtype=bool)
    with mpmath.workprec(work):
        mp_rtol, mp_atol = exact(rtol), exact(atol)
        for i in range(n):
            x, y = flat_a[i], flat_b[i]
            both = mpmath.isnan(x) and mpmath.isnan(y)
            d = mpmath.mpf(0) if both else abs(mpmath.fsub(x, y, exact=True))
            size = mpmath.mpf(0) if mpmath.isnan(y) else abs(y)
            allow = mp_atol + mp_rtol * size + exact(float(flat_x[i]))
            failing[i] = not (mpmath.isfinite(d) and d <= allow)  # NaN fails
            if not mpmath.isfinite(d):
                ratio[i] = math.inf
            elif allow > 0:
                ratio[i] = float(d / allow)
            else:
                ratio[i] = math.inf if d > 0 else 0.0
            allowed[i] = float(allow)
    shape = a.shape
    return _Comparison(
        diff.reshape(shape),
        allowed.reshape(shape),
        ratio.reshape(shape),
        failing.reshape(shape),
        undefined,
    )


def _describe_failure(name: str, cmp: _Comparison, t: np.ndarray) -> str:
    failing = cmp.failing
    worst = np.unravel_index(np.argmax(np.where(failing, cmp.ratio, -1.0)), failing.shape)
    first = np.argwhere(failing)[0]
    where = _point(worst, t)
    ratio = cmp.ratio[worst]
    times = failing.reshape(len(failing), -1).any(axis=1)
    side = cmp.undefined[worst]
    gap = f"|Δ| = {cmp.diff[worst]:.3e}, allowed {cmp.allowed[worst]:.3e} ({ratio:.3g}×)"
    if side:
        gap = f"undefined (NaN) in the {side} only"
    return (
        f"  {name}: {int(times.sum())} of {len(times)} output times fail; worst at {where}: "
        f"{gap}; first failure at {_point(tuple(first), t)}"
    )


def _point(index: tuple, t: np.ndarray) -> str:
    text = f"t = {float(t[index[0]]):.10g} (index {int(index[0])}"
    if len(index) > 1:
        text += f", component {int(index[1])}"
    return text + ")"


def _check_times(res: Result, ref: Result) -> None:
    __tracebackhide__ = True
    ta, tb = res.t, ref.t
    if len(ta) != len(tb):
        ends = ""
        if len(ta) and len(tb):
            ends = f" (result ends at t = {float(ta[-1]):.10g}, reference at {float(tb[-1]):.10g})"
        raise AssertionError(
            f"output times differ: result has {len(ta)}, reference {len(tb)}{ends}"
        )
    if not len(ta):
        return
    coarse = min(res.precision, ref.precision, key=lambda p: p.bits)
    work = max(res.precision.bits, ref.precision.bits) + 32
    with mpmath.workprec(work):
        xa, xb = exact_array(ta), exact_array(tb)
        scale = max(max(abs(v) for v in xa), max(abs(v) for v in xb))
        tol = _TIME_ULPS * exact(coarse.epsilon) * scale
        for i, (x, y) in enumerate(zip(xa, xb, strict=True)):
            if abs(x - y) > tol:
                raise AssertionError(
                    f"output times differ from index {i} on: result t = {float(x):.17g}, "
                    f"reference t = {float(y):.17g} (allowed {float(tol):.3e}, "
                    f"{_TIME_ULPS} ε of {coarse.name} times the largest |t|)"
                )


def _variable_names(res: Result, ref: Result, variables: Sequence[str] | str | None) -> list[str]:
    if variables is None:
        names = [k for k in res.variables if k in ref.variables]
        if not names:
            raise AssertionError(
                f"result and reference share no variable (result: {', '.join(res.variables)}; "
                f"reference: {', '.join(ref.variables)})"
            )
        return names
    names = [variables] if isinstance(variables, str) else variables
    if not isinstance(names, Sequence) or not names or not all(isinstance(k, str) for k in names):
        raise TypeError(f"variables must be a non-empty sequence of names, got {variables!r}")
    for k in names:
        for label, r in (("result", res), ("reference", ref)):
            if k not in r.variables and k not in r.monitors:
                known = ", ".join([*r.variables, *r.monitors])
                raise ValueError(f"variables: {label} has no variable {k!r}; known: {known}")
    return list(names)


def _load(obj: Result | str | Path, what: str) -> tuple[Result, dict[str, np.ndarray]]:
    """A result and its certificate (absolute error bound per variable, possibly empty)."""
    if isinstance(obj, Result):
        return obj, {}
    if not isinstance(obj, str | Path):
        raise TypeError(f"{what} must be a Result or a path, got {type(obj).__name__}")
    import h5py

    result = Result.load(obj)
    certificate = {}
    with h5py.File(obj, "r") as f:
        group = f.get("certificate")
        for name in group or ():
            # Datasets are the variables' bounds; the "events" subgroup bounds event times.
            if isinstance(group[name], h5py.Dataset):
                certificate[name] = np.asarray(group[name][()], dtype=np.float64)
    return result, certificate


def _nonneg_number(value: Any, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise TypeError(f"{name} must be a number, got {value!r}")
    value = float(value)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
    return value


# ---------------------------------------------------------------------- drift envelopes
@dataclass
class DriftEnvelope:
    """The largest drift of each conserved quantity in log-spaced time windows.

    Attributes
    ----------
    windows
        Shape ``(k, 2)``: window ``j`` holds the output times ``windows[j, 0] < t <=
        windows[j, 1]`` (the first also its start time). As :func:`drift_envelope` makes them,
        each window is twice as long as the one before and the last ends at the final time.
    peaks
        For each conserved monitor, shape ``(k,)``: the largest ``|drift|`` (largest component
        for vector monitors; :meth:`Result.drift`) in each window, in units of ``epsilon``.
    precision
        The precision of the run.
    title
        The scene's title.
    metadata
        Versions and integrator settings of the run.
    """

    windows: np.ndarray
    peaks: dict[str, np.ndarray]
    precision: Precision
    title: str = ""
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def epsilon(self) -> float:
        """Machine epsilon of :attr:`precision` (the unit of :attr:`peaks`)."""
        return self.precision.epsilon

    def save(self, path: str | Path) -> None:
        """Write the envelope to an HDF5 file (``attrs["format"] = "cayley_heyoka.drift"``),
        atomically, as every file of ours (:func:`cayley_heyoka.core.files.write_hdf5`)."""
        from ..core.files import write_hdf5

        def fill(f: Any) -> None:
            f.attrs["format"] = DRIFT_FORMAT
            f.attrs["format_version"] = DRIFT_FORMAT_VERSION
            f.attrs["title"] = self.title
            f.attrs["precision"] = json.dumps(self.precision.to_spec())
            f.attrs["metadata"] = json.dumps(self.metadata)
            f.create_dataset("windows", data=np.asarray(self.windows, dtype=np.float64))
            g = f.create_group("peaks")
            g.attrs["units"] = "epsilon"
            g.attrs["order"] = json.dumps(list(self.peaks))
            for name, values in self.peaks.items():
                g.create_dataset(name, data=np.asarray(values, dtype=np.float64))

        write_hdf5(path, fill)

    @classmethod
    def load(cls, path: str | Path) -> DriftEnvelope:
        """Read an envelope written by :meth:`save`."""
        import h5py

        path = Path(path)
        if not path.is_file():  # a FIFO would block the open; say what it is instead
            raise ValueError(f"{path}: {'no such file' if not path.exists() else 'not a file'}")
        try:
            f = h5py.File(path, "r")
        except OSError as exc:
            raise ValueError(f"{path}: not an HDF5 file ({exc})") from None
        with f:
            if f.attrs.get("format") != DRIFT_FORMAT:
                raise ValueError(f"{path}: not a {DRIFT_FORMAT} file")
            try:
                g = f["peaks"]
                return cls(
                    windows=np.asarray(f["windows"][()], dtype=np.float64),
                    peaks={
                        k: np.asarray(g[k][()], dtype=np.float64)
                        for k in json.loads(g.attrs["order"])
                    },
                    precision=Precision.from_spec(json.loads(f.attrs["precision"])),
                    title=str(f.attrs["title"]),
                    metadata=json.loads(f.attrs["metadata"]),
                )
            except (KeyError, TypeError, ValueError) as exc:  # ValueError: JSONDecodeError too
                raise ValueError(f"{path}: a damaged {DRIFT_FORMAT} file ({exc})") from None


def drift_envelope(result: Result, windows: int | np.ndarray = 8) -> DriftEnvelope:
    """The drift envelope of a run's conserved monitors.

    Parameters
    ----------
    result
        A run with at least one conserved monitor (:attr:`Result.conserved`) and two output
        times.
    windows
        The number of windows (≥ 1; windows holding no output time are left out), or an array
        of shape ``(k, 2)`` of ``(start, end]`` pairs, e.g. a golden envelope's
        :attr:`DriftEnvelope.windows`.
    """
    if not isinstance(result, Result):
        raise TypeError(f"result must be a Result, got {type(result).__name__}")
    if not result.conserved:
        raise ValueError("result: the scene has no conserved monitor, so no drift to envelope")
    if len(result.t) < 2:
        raise ValueError(f"result: needs at least 2 output times, has {len(result.t)}")
    t = np.array([float(v) for v in result.t])
    spans = _windows(t, windows)
    members = [_window_members(t, lo, hi, j == 0) for j, (lo, hi) in enumerate(spans)]
    if not isinstance(windows, int | np.integer):
        empty = [j for j, m in enumerate(members) if not m.any()]
        if empty:
            lo, hi = spans[empty[0]]
            raise ValueError(
                f"windows: the result has no output time in ({lo:.10g}, {hi:.10g}] "
                f"(its times run from {t[0]:.10g} to {t[-1]:.10g})"
            )
    else:
        keep = [j for j, m in enumerate(members) if m.any()]
        spans, members = spans[keep], [members[j] for j in keep]
    peaks = {}
    for name in result.conserved:
        size = _drift_in_eps(result.drift(name), result.precision)
        peaks[name] = np.array([np.max(size[m]) for m in members])
    meta = {
        k: result.metadata[k]
        for k in ("cayley_heyoka", "heyoka", "numpy", "tolerance", "order")
        if k in result.metadata
    }
    return DriftEnvelope(
        windows=spans,
        peaks=peaks,
        precision=result.precision,
        title=str(result.scene.get("title", "")),
        metadata=meta,
    )


#: The most windows :func:`drift_envelope` makes from a count.
MAX_WINDOWS = 1000


def _windows(t: np.ndarray, windows: int | np.ndarray) -> np.ndarray:
    if isinstance(windows, bool):
        raise TypeError(
            f"windows must be an int or an array of (start, end] pairs, got {windows!r}"
        )
    if isinstance(windows, int | np.integer):
        # Each window halves the span before it: past ~1000 they are below any precision.
        if not 1 <= windows <= MAX_WINDOWS:
            raise ValueError(f"windows must be in 1 … {MAX_WINDOWS}, got {windows}")
        t0, span = t[0], t[-1] - t[0]
        ends = t0 + span * 2.0 ** np.arange(1 - int(windows), 1)
        ends[-1] = t[-1]
        return np.column_stack([np.concatenate(([t0], ends[:-1])), ends])
    spans = np.asarray(windows, dtype=np.float64)
    if spans.ndim != 2 or spans.shape[1] != 2 or not len(spans):
        raise ValueError(f"windows must have shape (k, 2) with k >= 1, got {spans.shape}")
    return spans


def _window_members(t: np.ndarray, lo: float, hi: float, first: bool) -> np.ndarray:
    return ((t > lo) | (first & (t == lo))) & (t <= hi)


def _drift_in_eps(drift: np.ndarray, precision: Precision) -> np.ndarray:
    """``|drift|`` (largest component per time) in units of ε, as float64.

    Scaling by 1/ε = 2^(bits-1) in the run's own type is exact, and the scaled values are
    within double's range whatever the precision.
    """
    if precision.kind == "double":
        size = np.abs(drift) / precision.epsilon
    else:
        scale = precision.number(2 ** (precision.bits - 1))
        size = np.array([float(abs(v) * scale) for v in np.ravel(drift)]).reshape(drift.shape)
    return size.max(axis=1) if size.ndim > 1 else size


def assert_drift_within(
    measured: Result | DriftEnvelope,
    golden: DriftEnvelope | str | Path,
    *,
    factor: float = DRIFT_FACTOR,
    floor: float = DRIFT_FLOOR,
) -> None:
    """Fail if a run's drift exceeds ``factor × golden + floor`` in any window.

    Parameters
    ----------
    measured
        A run (its envelope is taken over the golden windows) or its envelope over the same
        windows.
    golden
        The envelope of the accepted run, or the path of its file.
    factor
        How many times the golden drift a window may reach (≥ 1). The default absorbs the
        spread of the round-off between machines (see :data:`DRIFT_FACTOR`).
    floor
        Added allowance in units of the precision's ε (≥ 0), for early windows whose drift is
        a few ε.

    Raises
    ------
    AssertionError
        A window exceeds its allowance (the message gives the monitor, window, measured and
        golden drift, their ratio and the allowance; a window NaN in both agrees, NaN in one
        only exceeds), or the two cannot be compared (other precision, other conserved
        monitors, a window without output times).
    """
    __tracebackhide__ = True
    factor = _nonneg_number(factor, "factor")
    if factor < 1:
        raise ValueError(f"factor must be >= 1 (below 1 the golden run itself fails), got {factor}")
    floor = _nonneg_number(floor, "floor")
    source = ""
    if isinstance(golden, str | Path):
        source = f" ({golden})"
        golden = DriftEnvelope.load(golden)
    elif not isinstance(golden, DriftEnvelope):
        raise TypeError(f"golden must be a DriftEnvelope or a path, got {type(golden).__name__}")
    if not isinstance(measured, Result | DriftEnvelope):
        raise TypeError(
            f"measured must be a Result or a DriftEnvelope, got {type(measured).__name__}"
        )
    if measured.precision != golden.precision:
        raise AssertionError(
            f"the result is in {measured.precision.name}, the golden envelope{source} in "
            f"{golden.precision.name}: regenerate the golden file"
        )
    if isinstance(measured, Result):
        _check_coverage(measured, golden.windows, source)
        measured = drift_envelope(measured, golden.windows)
    elif not np.array_equal(measured.windows, golden.windows):
        raise ValueError(
            "measured: its windows differ from the golden envelope's; pass the Result, or "
            "drift_envelope(result, golden.windows)"
        )
    if set(measured.peaks) != set(golden.peaks):
        raise AssertionError(
            f"conserved monitors differ: result {sorted(measured.peaks)}, golden envelope"
            f"{source} {sorted(golden.peaks)}: regenerate the golden file"
        )
    eps = golden.epsilon
    lines = []
    for name, gold in golden.peaks.items():
        got = measured.peaks[name]
        allowed = factor * gold + floor
        # A window undefined (NaN) in both agrees; NaN in one only fails.
        failing = np.flatnonzero(~(got <= allowed) & ~(np.isnan(got) & np.isnan(gold)))
        if not len(failing):
            continue
        excess = np.where(np.isfinite(got[failing]), got[failing] / allowed[failing], np.inf)
        j = failing[np.argmax(excess)]
        ratio = got[j] / gold[j] if gold[j] > 0 else math.inf
        lines.append(
            f"  {name}: {len(failing)} of {len(gold)} windows exceed; worst t in "
            f"{_window_text(golden.windows, j)}: max |drift| {got[j] * eps:.3e} ({got[j]:.4g} ε) "
            f"vs golden {gold[j] * eps:.3e} ({gold[j]:.4g} ε), ratio {ratio:.3g}, allowed "
            f"{allowed[j] * eps:.3e}; first t in {_window_text(golden.windows, failing[0])}"
        )
    if lines:
        raise AssertionError(
            f"drift exceeds the golden envelope{source} for {len(lines)} of {len(golden.peaks)} "
            f"conserved monitors ({golden.precision.name}, ε = {eps:.3e}; allowed {factor:g} × "
            f"golden + {floor:g} ε):\n" + "\n".join(lines)
        )


def _window_text(windows: np.ndarray, j: int) -> str:
    lo, hi = windows[j]
    opening = "[" if j == 0 else "("  # the first window holds its start time
    return f"{opening}{lo:.6g}, {hi:.6g}]"


def _check_coverage(result: Result, windows: np.ndarray, source: str) -> None:
    """Fail clearly when a run (one stopped early, say) misses some golden window."""
    __tracebackhide__ = True
    t = np.array([float(v) for v in result.t])
    for j, (lo, hi) in enumerate(windows):
        if not _window_members(t, lo, hi, j == 0).any():
            ends = f"{t[0]:.10g} to {t[-1]:.10g}" if len(t) else "nowhere (no output times)"
            raise AssertionError(
                f"the result has no output time in the golden window ({lo:.10g}, {hi:.10g}]"
                f"{source}: its times run from {ends}"
            )
