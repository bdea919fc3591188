"""Scenes and studies that, together, set every key the parsers allow.

The hostile suite's coverage test (``test_coverage.py``) lists the schema as the parsers enforce
it (:func:`cayley_heyoka.core.scene.recording_keys` while these documents are parsed) and
requires each allowed key to be set by one of them: a key added to a parser then fails the
coverage test until a document here sets it — and the generated cases of ``test_every_key.py``
give it hostile values. The documents are the bundled examples, over a short span, and the
supplements below for what no example uses. Each must be valid and run in well under a second.
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path
from typing import Any

from conftest import Raw

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
SHORT = {"start": Raw("0.0"), "stop": Raw("1.0"), "count": 3}


def _example(path: Path) -> dict[str, Any]:
    data = tomllib.loads(path.read_text(), parse_float=Raw)
    if "output" in data:
        data["output"]["times"] = dict(SHORT)
    return data


_ROTATION_EXTRAS: dict[str, dict[str, Any]] = {
    "rotation-options": {
        "title": "every generic option",
        "body": {"inertia": [1, Raw("1.5"), Raw("2.5")]},
        "initial": {"rates": [Raw("0.1"), Raw("0.2"), 1], "quaternion": [1, 0, 0, 0]},
        "attitude": {"formulation": "rodrigues", "max_chart_angle": 150},
        "integrator": {
            "precision": "double",
            "tolerance": Raw("1e-14"),
            "compact_mode": False,
            "high_accuracy": True,
            "max_step": Raw("0.5"),
            "max_steps": 100000,
        },
        "output": {
            "times": [0, Raw("0.5"), 1],
            "events": ["invariable_plane", "crossing"],
            "monitors": ["energy", "K"],
            "units": {"time": "s", "p": "rad/s"},
            "invariable_angle": True,
        },
        "events": {"crossing": {"expression": "p - 0.05", "direction": "up"}},
        "monitors": {"K": {"expression": "p*p + q*q", "conserved": False}},
    },
    "rotation-matrix-gradient": {
        "body": {"inertia": [1, 2, Raw("2.5")]},
        "initial": {
            "rates": [Raw("0.1"), Raw("0.2"), 1],
            "matrix": [[1, 0, 0], [0, 1, 0], [0, 0, 1]],
        },
        "forces": {"gravity_gradient": {"gm": 1, "distance": 10, "direction": [0, 0, 1]}},
        "output": {"times": dict(SHORT)},
    },
    "rotation-potential-poisson": {
        "body": {"inertia": [1, 2, Raw("2.5")]},
        "initial": {"rates": [Raw("0.1"), Raw("0.2"), 1], "rodrigues": [Raw("0.1"), 0, 0]},
        "attitude": {"formulation": "poisson"},
        "forces": {"potential": {"V": "R33"}},
        "output": {"times": dict(SHORT), "azimuth": True},
    },
}

_ORBIT_EXTRAS: dict[str, dict[str, Any]] = {
    "orbit-elements-potential": {
        "orbit": {
            "mu": 1,
            "formulation": "cayley",
            "sigma0": Raw("0.1"),
            "equatorial_limit": Raw("0.01"),
            "elements": {
                "a": 1,
                "e": Raw("0.1"),
                "inclination": Raw("0.3"),
                "node": Raw("0.2"),
                "argument_of_pericentre": Raw("0.4"),
                "mean_anomaly": Raw("0.5"),
            },
        },
        "perturbations": {
            "potential": {"Omega": "1e-4*z*z"},
            "zonal": {"radius": Raw("0.1"), "axis": [0, 0, 1], "J2": Raw("1e-3"),
                      "J3": Raw("1e-6"), "J4": Raw("1e-6")},
            "third_body": {"gm": Raw("1e-3"), "a": 5, "n": Raw("0.1"), "eccentricity": Raw("0.1"),
                           "inclination": Raw("0.1"), "node": 0, "argument_of_pericentre": 0,
                           "mean_anomaly0": 0, "degree": 3},
        },
        "reference_plane": {"theta0": 0, "theta_rate": Raw("1e-3"), "phi0": Raw("0.1"),
                            "phi_rate": 0, "sigma0": 0, "sigma_rate": 0},
        "output": {"times": dict(SHORT)},
    },
    "orbit-cartesian": {
        "orbit": {"mu": 1, "formulation": "cartesian", "position": [1, 0, 0],
                  "velocity": [0, 1, Raw("0.1")]},
        "perturbations": {"third_body": {"gm": Raw("1e-3"), "a": 5, "n": Raw("0.1"),
                                         "mean_longitude0": Raw("0.3")}},
        "output": {"times": dict(SHORT)},
    },
}  # fmt: skip

_HAMILTON_EXTRAS: dict[str, dict[str, Any]] = {
    "hamilton-H": {
        "hamiltonian": {"H": "varpi1**2/2 + eta1**2/2"},
        "initial": {"eta": [1], "varpi": [0]},
        "output": {"times": dict(SHORT)},
    },
    "hamilton-split": {
        "hamiltonian": {
            "H1": "varpi1**2/2 + eta1**2/2",
            "H2": "eta1**4/100",
            "formulation": "elements",
            "flow": {
                "eta1": "chi1*cos(t) + lambda1*sin(t)",
                "varpi1": "lambda1*cos(t) - chi1*sin(t)",
            },
        },
        "initial": {"eta": [1], "varpi": [0]},
        "output": {"times": dict(SHORT)},
    },
    "hamilton-bodies-cartesian": {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": 1,
            "central_mass": 1,
            "bodies": [
                {"mass": Raw("1e-3"), "position": [1, 0, 0], "velocity": [0, 1, 0]},
                {"mass": Raw("1e-4"), "position": [0, 2, 0], "velocity": [Raw("-0.7"), 0, 0]},
            ],
        },
        "output": {"times": dict(SHORT)},
    },
}

_STUDY_EXTRAS: dict[str, dict[str, Any]] = {
    "study-grid": {
        "title": "a grid",
        "scene": "free_body",
        "sweep": {
            "kind": "grid",
            "parameters": {
                "initial.rates[0]": {"start": Raw("0.1"), "stop": Raw("0.2"), "count": 2,
                                     "spacing": "linear"},
            },
        },
        "run": {"backend": "local", "workers": 1, "chunk": 2},
    },
    "study-random": {
        "title": "random members",
        "scene": "free_body",
        "sweep": {
            "kind": "random",
            "count": 2,
            "seed": 1,
            "parameters": {
                "initial.rates[0]": {"uniform": [Raw("0.1"), Raw("0.2")]},
                "initial.rates[1]": {"normal": [Raw("0.2"), Raw("0.01")]},
            },
        },
    },
    "study-scheduler": {
        "scene": "free_body",
        "sweep": {"kind": "grid", "parameters": {"initial.rates[0]": [Raw("0.1")]}},
        "run": {"backend": "dask", "scheduler": "tcp://127.0.0.1:1"},
    },
}  # fmt: skip


def scenes() -> dict[str, dict[str, Any]]:
    """Name → scene document (fresh copies)."""
    out = {p.stem: _example(p) for p in sorted(EXAMPLES.glob("*.toml"))}
    for extras in (_ROTATION_EXTRAS, _ORBIT_EXTRAS, _HAMILTON_EXTRAS):
        out.update(copy.deepcopy(extras))
    return out


def studies() -> dict[str, dict[str, Any]]:
    """Name → study document, its ``scene`` the name of a document of :func:`scenes` (the
    bundled studies' scene files are the bundled examples, here over the short span):
    ``schema.study_scene`` puts that scene in its place."""
    out = {}
    for path in sorted((EXAMPLES / "studies").glob("*.toml")):
        data = tomllib.loads(path.read_text(), parse_float=Raw)
        if isinstance(data["scene"], str):
            data["scene"] = (path.parent / data["scene"]).resolve().stem
        else:
            data["scene"].setdefault("output", {})["times"] = dict(SHORT)
        if data["sweep"].get("count", 0) > 8:
            data["sweep"]["count"] = 8  # members enough to be a sweep, few to run
        out[f"studies/{path.stem}"] = data
    out.update(copy.deepcopy(_STUDY_EXTRAS))
    return out
