"""Consistency checks of a scene against an independent computation (``cayley-heyoka check``).

A family's check integrates the scene and measures it against something the run itself does
not use: the partial derivatives of Hamilton's principal function, a second formulation of the
same motion, an element theory. Each compared quantity is one :class:`CheckRow` with the error
measured and the bound it must stay within, fixed by a round-off law before the run; the
report passes when every row does.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import SceneError
from .scene import Scene


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


def check_scene(scene: Scene) -> CheckReport:
    """Run the consistency check that fits ``scene``.

    * ``hamiltonian`` family: the partial derivatives of the principal function S
      (:func:`cayley_heyoka.hamilton.principal.check_principal_function`); for the system with
      one predominant mass, Hamilton's varying elements against the canonical equations
      (:func:`cayley_heyoka.hamilton.planets_check.check_formulations`).
    * ``rotation`` family with forces: Cayley's 1846 element equations (62)–(63) against the
      elements' actual rates (:func:`cayley_heyoka.rotation.element_check.check_element_equations`).

    Raises
    ------
    SceneError
        When no check applies to the scene.
    ValueError
        When the check cannot be carried through (e.g. a forced body whose free motion stops
        passing Cayley's υ₀), naming the reason.
    """
    if scene.family == "hamiltonian" and scene.model.model == "predominant_mass":
        from .hamilton.planets_check import check_formulations

        return check_formulations(scene)
    if scene.family == "hamiltonian":
        from .hamilton.principal import check_principal_function

        return check_principal_function(scene).report()
    if scene.family == "rotation" and scene.model.forces:
        from .rotation.element_check import check_element_equations

        return check_element_equations(scene)
    raise SceneError(
        "scene",
        f"no consistency check for this {scene.family} scene; `check` covers hamiltonian scenes "
        "and rotation scenes with forces",
    )
