"""The vocabulary of consistency checks (``cayley-heyoka check``): rows, reports, options and
the round-off laws their bounds come from.

A family's check integrates the scene and measures it against something the run itself does
not use: the partial derivatives of Hamilton's principal function, a second formulation of the
same motion, an element theory. Each compared quantity is one :class:`CheckRow` with the error
measured and the bound it must stay within, fixed by a round-off law before the run; the
report passes when every row does.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError
from .precision import Number, Precision
from .scene import checked_numbers, number


@dataclass(frozen=True)
class CheckRow:
    """One compared quantity.

    Attributes
    ----------
    quantity
        What is compared, e.g. ``"∂S/∂η − ϖ"``.
    error
        Largest error measured (NaN when nothing could be measured).
    bound
        The bound it must stay within.
    note
        How the bound was set, or what the error is relative to.
    """

    quantity: str
    error: float
    bound: float
    note: str = ""

    @property
    def passed(self) -> bool:
        return math.isfinite(self.error) and self.error <= self.bound


@dataclass(frozen=True)
class CheckReport:
    """The outcome of a consistency check.

    Attributes
    ----------
    title
        What was checked against what.
    rows
        The compared quantities.
    series
        Per-sample arrays (e.g. ``"t"`` and one error series per row), saved with the report.
    """

    title: str
    rows: tuple[CheckRow, ...]
    series: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return bool(self.rows) and all(row.passed for row in self.rows)

    def text(self) -> str:
        """A table a person can read."""
        width = max([len(r.quantity) for r in self.rows] + [8])
        lines = [self.title, ""]
        lines.append(f"  {'quantity':<{width}}  {'error':>10}  {'bound':>10}  ok")
        for r in self.rows:
            mark = "yes" if r.passed else "NO"
            line = f"  {r.quantity:<{width}}  {r.error:10.3e}  {r.bound:10.3e}  {mark}"
            lines.append(line + (f"  ({r.note})" if r.note else ""))
        lines.append("")
        lines.append("  passed" if self.passed else "  FAILED")
        return "\n".join(lines)

    def save(self, path: str | Path) -> None:
        """Write the rows and series to an HDF5 file (atomically, with a checksum, as
        :meth:`Result.save <cayley_heyoka.Result.save>`)."""
        from .files import FORMAT_VERSION, FORMATS, write_hdf5

        def fill(f: Any) -> None:
            f.attrs["format"] = FORMATS["check"]
            f.attrs["format_version"] = FORMAT_VERSION
            f.attrs["title"] = self.title
            f.attrs["passed"] = self.passed
            rows = f.create_group("rows")
            for i, r in enumerate(self.rows):
                g = rows.create_group(f"{i:02d}")
                g.attrs["quantity"] = r.quantity
                g.attrs["error"] = r.error
                g.attrs["bound"] = r.bound
                g.attrs["note"] = r.note
            series = f.create_group("series")
            for name, values in self.series.items():
                series.create_dataset(name, data=np.asarray(values, dtype=float))

        write_hdf5(path, fill)

    @classmethod
    def load(cls, path: str | Path) -> CheckReport:
        """Read a check file written by :meth:`save` (``ResultFileError`` if it is damaged)."""
        from .files import open_ours

        with open_ours(path, "check") as f:
            rows = tuple(
                CheckRow(
                    quantity=str(g.attrs["quantity"]),
                    error=float(g.attrs["error"]),
                    bound=float(g.attrs["bound"]),
                    note=str(g.attrs["note"]),
                )
                for g in (f["rows"][k] for k in sorted(f["rows"], key=int))
            )
            series = {k: np.asarray(v[()], dtype=float) for k, v in f["series"].items()}
            return cls(title=str(f.attrs["title"]), rows=rows, series=series)


class CheckOptions:
    """Options of a consistency check, as text (``cayley-heyoka check --set KEY=VALUE``).

    A check reads the options it takes with :meth:`text`, :meth:`number`, :meth:`integer` or
    :meth:`choice`
    after declaring them with :meth:`accept`, which refuses any other key, naming the keys the
    check takes.
    """

    def __init__(self, values: Mapping[str, str] | None = None) -> None:
        self.values = dict(values or {})

    def accept(self, keys: tuple[str, ...], check: str) -> None:
        """Refuse keys that ``check`` does not take."""
        for key in self.values:
            if key not in keys:
                takes = f"takes {', '.join(keys)}" if keys else "takes no options"
                raise SceneError(f"--set {key}", f"unknown option: the {check} {takes}")

    def text(self, key: str) -> str | None:
        return self.values.get(key)

    def number(self, key: str, precision: Precision) -> Number | None:
        """A number option, held by ``precision`` (the scene's): refused as ``--set KEY``
        by the same rules as a scene's numbers (:func:`~.scene.number`,
        :meth:`~.precision.Precision.hold`)."""
        value = self.values.get(key)
        if value is None:
            return None
        with checked_numbers(precision):
            return number(value, f"--set {key}")

    def integer(self, key: str, minimum: int = 1, maximum: int = 10**6) -> int | None:
        value = self.values.get(key)
        if value is None:
            return None
        try:
            number = int(value)
        except ValueError:
            number = minimum - 1
        if not minimum <= number <= maximum:
            raise SceneError(
                f"--set {key}", f"must be an integer in {minimum} … {maximum}, got {value!r}"
            )
        return number

    def choice(self, key: str, choices: tuple[str, ...]) -> str | None:
        value = self.values.get(key)
        if value is not None and value not in choices:
            raise SceneError(f"--set {key}", f"must be one of {', '.join(choices)}, got {value!r}")
        return value


def parse_settings(settings: list[str] | None) -> CheckOptions:
    """``KEY=VALUE`` strings from the command line as :class:`CheckOptions`."""
    values: dict[str, str] = {}
    for item in settings or ():
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise SceneError("--set", f"expected KEY=VALUE, got {item!r}")
        values[key.strip()] = value.strip()
    return CheckOptions(values)


def round_off_scale(steps: int, epsilon: float, tolerance: float | None = None) -> float:
    """Brouwer's law for the error a run's steps add up to: 10 ε √N.

    Each of N steps rounds the state by about ε relative, in directions that are as good as
    random, so the errors add like a random walk; 10 is the safety factor every check uses.
    A tolerance above ε adds truncation errors, which are systematic: they add linearly.
    """
    extra = max(0.0, (tolerance or 0.0) - epsilon) * steps
    return 10 * (epsilon * math.sqrt(max(steps, 1)) + extra)


def flow_sensitivity(
    evaluate: Callable[[int | None, Any], Mapping[str, Any]],
    directions: int,
    times: Sequence[Any],
    delta: Any,
) -> dict[str, float]:
    """How far a closed form's solution moves per unit change of its initial state.

    Parameters
    ----------
    evaluate
        ``evaluate(direction, t)``: the solution at ``t`` from the initial state moved by
        ``delta`` (times the check's scale of that component) along ``direction``, or from
        the initial state itself for ``None``; a mapping of quantity names to numbers or
        vectors (sequences; their change is measured by its length).
    directions
        Number of perturbation directions (together they span the state).
    times
        Times at which to measure.
    delta
        Size of the perturbation: small enough to stay linear, large against the closed
        form's own error.

    Returns
    -------
    dict
        For each quantity, max over directions and times of ``|Δ quantity| / delta``: the
        factor by which the flow carries an error of the initial state (and so, Brouwer's
        argument, any step's round-off) to that quantity.
    """
    out: dict[str, float] = {}
    for t in times:
        base = evaluate(None, t)
        for d in range(directions):
            moved = evaluate(d, t)
            for name, value in base.items():
                if isinstance(value, Sequence):  # a vector: the length of its change
                    diff = [a - b for a, b in zip(moved[name], value, strict=True)]
                    change = float(sum(d * d for d in diff) ** 0.5 / delta)
                else:
                    change = float(abs(moved[name] - value) / delta)
                out[name] = max(out.get(name, 0.0), change)
    return out
