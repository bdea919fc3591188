"""The Python an orbit sweep spends on each member, against the same at another revision.

Run:  python validation/orbit_member_cost.py [--members N] [--against REV] [--repeats K]
      [--elements]

The study of users_engine.py's terminal row "Cayley's orbit (ρ's revolutions), J2" (its
members differ in one velocity component), or with ``--elements`` the same orbit given by
its elements (members differing in the semi-major axis). Two phases of ``run_sweep``'s local
path, per member: the members' scenes (``Study.member_scene``: the base scene with the
member's value, validated by ``Scene.from_dict``) and ``prepare_members`` (the scenes again,
and the study's structure filled with each member's numbers, as the sweep calls it), beside
the whole ``run_sweep`` on one worker (those phases and the members' integration); each
timed interleaved (users_common.py's ``interleaved``: wall time) with the same phase of the
package at ``REV`` (``git archive`` of its ``cayley_heyoka``, imported beside this one under
another name), so that the ratio holds on a shared machine. Before timing, every member's
initial state and parameters are compared, bit for bit, between the two.
"""

from __future__ import annotations

import argparse
import copy
import importlib
import io
import statistics
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from users_common import interleaved
from users_engine import TERMINAL_CASES

ROOT = Path(__file__).resolve().parent.parent
LABEL = "Cayley's orbit (ρ's revolutions), J2"
BASE = "cayley_heyoka_base"


def _base_package(rev: str, where: Path) -> None:
    """``cayley_heyoka`` at ``rev`` as the package ``cayley_heyoka_base`` in ``where``."""
    archive = subprocess.run(
        ["git", "archive", rev, "cayley_heyoka"], cwd=ROOT, check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=io.BytesIO(archive)) as tar:
        tar.extractall(where, filter="data")
    (where / "cayley_heyoka").rename(where / BASE)
    for path in (where / BASE).rglob("*.py"):
        text = path.read_text()
        path.write_text(text.replace("cayley_heyoka", BASE))


#: The terminal row's orbit by its elements (those of its position and velocity, rounded).
ELEMENTS = {
    "a": "1.2",
    "e": "0.25",
    "inclination": "0.5",
    "node": "0.3",
    "argument_of_pericentre": "0.4",
    "mean_anomaly": "0.2",
}


def study_of(members: int, elements: bool) -> dict[str, Any]:
    """The study: the terminal row's, or its orbit by elements, swept in one number."""
    scene = copy.deepcopy(TERMINAL_CASES[LABEL])
    if elements:
        orbit = scene["orbit"]
        del orbit["position"], orbit["velocity"]
        orbit["elements"] = dict(ELEMENTS)
        path, base = "orbit.elements.a", 1.2
    else:
        path, base = "orbit.velocity[1]", 0.85
    values = [f"{base * (1 + 0.05 * k / members):.6f}" for k in range(members)]
    return {"scene": scene, "sweep": {"kind": "grid", "parameters": {path: values}}}


class _Side:
    """One package's study and phases."""

    def __init__(self, package: str, study: dict[str, Any]) -> None:
        study_module = importlib.import_module(f"{package}.workflows.study")
        self.members_module: ModuleType = importlib.import_module(f"{package}.workflows.members")
        sweep = importlib.import_module(f"{package}.workflows.sweep")
        self.study = study_module.Study.from_dict(copy.deepcopy(study))
        self.listed = list(enumerate(self.study.members()))
        self.layout = sweep.layout_of(self.study)
        self.run_sweep = sweep.run_sweep

    def scenes(self) -> list[Any]:
        return [self.study.member_scene(*m) for m in self.listed]

    def prepare(self) -> Any:
        return self.members_module.prepare_members(self.study, self.listed, self.layout)

    def sweep(self) -> Any:
        return self.run_sweep(self.study, workers=1)


def _numbers(side: _Side) -> list[tuple[np.ndarray, np.ndarray]]:
    _, groups = side.prepare()
    rows = sorted(e for g in groups.values() for e in ((e.row, e) for e in g.entries))
    return [
        (np.asarray(e.initial, dtype=np.float64), np.asarray(e.pars, dtype=np.float64))
        for _, e in rows
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=128)
    parser.add_argument("--against", default="HEAD", help="the revision to compare with")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--elements", action="store_true", help="the orbit by its elements")
    args = parser.parse_args(argv)
    study = study_of(args.members, args.elements)
    with tempfile.TemporaryDirectory() as where:
        _base_package(args.against, Path(where))
        sys.path.insert(0, where)
        ours, theirs = _Side("cayley_heyoka", study), _Side(BASE, study)
        a, b = _numbers(ours), _numbers(theirs)
        same = len(a) == len(b) and all(
            np.array_equal(x.view(np.int64), y.view(np.int64))
            for (xi, xp), (yi, yp) in zip(a, b, strict=True)
            for x, y in ((xi, yi), (xp, yp))
        )
        if not same:
            raise SystemExit("the members' numbers differ from the base revision's")
        label = f"{LABEL}, by elements" if args.elements else LABEL
        print(
            f"{label}: {args.members} members; this tree against {args.against} (numbers of "
            f"every member the same, bit for bit); per member, least of {args.repeats} "
            "interleaved repeats (wall time)"
        )
        print(f"  {'phase':18s} {'this tree':>10s} {args.against:>10s}  ratio: median (min–max)")
        for name in ("scenes", "prepare", "sweep"):
            ratios, mine, base = interleaved(
                getattr(ours, name), getattr(theirs, name), repeats=args.repeats
            )
            n = args.members
            print(
                f"  {name:18s} {mine * 1e3 / n:7.3f} ms {base * 1e3 / n:7.3f} ms  "
                f"{statistics.median(ratios):.2f} ({min(ratios):.2f}–{max(ratios):.2f})"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
