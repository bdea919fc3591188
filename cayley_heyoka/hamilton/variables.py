"""What each output and monitor of a Hamiltonian scene is (``Family.variables``), in Hamilton's
symbols; importing nothing heavier than the standard library. Names carry an index: a
coordinate's (η₁ … η_N) or, for the system with one predominant mass, a body's."""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any

_INDEXED = re.compile(r"([a-z]+)([1-9][0-9]*)")
_COORDINATES = {
    "eta": "coordinate η{i}",
    "varpi": "momentum ϖ{i}, conjugate to η{i}",
    "chi": "varying element χ{i}: η{i} of the H₁ motion at t = 0 (elements formulation)",
    "lambda": "varying element λ{i}: ϖ{i} of the H₁ motion at t = 0 (elements formulation)",
}
# The system with one predominant mass (Second Essay §8): body i's state and elements.
_BODIES = {
    "x": "body {i}'s position x relative to the predominant mass",
    "y": "body {i}'s position y relative to the predominant mass",
    "z": "body {i}'s position z relative to the predominant mass",
    "vx": "body {i}'s velocity ẋ relative to the predominant mass",
    "vy": "body {i}'s velocity ẏ relative to the predominant mass",
    "vz": "body {i}'s velocity ż relative to the predominant mass",
    "mu": "body {i}'s element μ: the energy of its binary per unit mass (§8.3)",
    "tau": "body {i}'s element τ: the time of pericentre passage",
    "varpi": "body {i}'s element ϖ: the longitude of the pericentre",
    "lambda": "body {i}'s element λ: |ξ × x′|, twice its reduced areal velocity",
    "chi": "body {i}'s element χ: λ times the versed sine of the inclination",
    "nu": "body {i}'s element ν: the longitude of the node",
}
_NAMES = {
    "S": "Hamilton's principal function S, the action along the run",
    "energy": "the Hamiltonian H",
    "angular_momentum": "the total angular momentum (a vector)",
}


def describe(scene: Mapping[str, Any], name: str) -> str | None:
    """What ``name`` is in a Hamiltonian scene's results, or None if it is not one of its."""
    if name in _NAMES:
        return _NAMES[name]
    match = _INDEXED.fullmatch(name)
    if match is None:
        return None
    table = scene.get("hamiltonian", {})
    bodies = isinstance(table, Mapping) and table.get("model") == "predominant_mass"
    text = (_BODIES if bodies else _COORDINATES).get(match.group(1))
    return None if text is None else text.format(i=match.group(2))
