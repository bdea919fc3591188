"""What each output and monitor of an orbit scene is (``Family.variables``), in Cayley's 1860
symbols; importing nothing heavier than the standard library."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

_NAMES = {
    "x": "position x in frame 0 (the fixed reference plane)",
    "y": "position y in frame 0",
    "z": "position z in frame 0",
    "vx": "velocity ẋ in frame 0",
    "vy": "velocity ẏ in frame 0",
    "vz": "velocity ż in frame 0",
    "r": "radius r = |x|",
    "rdot": "radial velocity ṙ",
    "rho": "departure ρ: the angle from the orbit plane's departure point (continuous)",
    "h": "h = |x × v|, twice the areal velocity",
    "Theta": (
        "Θ, longitude of the orbit plane's node on the reference plane (cayley: NaN where "
        "sin Φ < orbit.equatorial_limit, the angles carried on a tilted frame)"
    ),
    "Sigma": "Σ, departure of the node from the departure point (NaN where Θ is)",
    "Phi": "Φ, inclination of the orbit plane to the reference plane",
    "qw": "orbit-frame quaternion, scalar part (quaternion formulation)",
    "qx": "orbit-frame quaternion, x component",
    "qy": "orbit-frame quaternion, y component",
    "qz": "orbit-frame quaternion, z component",
    "energy": "½|v|² − μ/r − Ω: the energy, the disturbing function Ω included",
    "angular_momentum": "x × v (a vector)",
    "jacobi": "the Jacobi constant of a perturber on a circular orbit",
    "polar_momentum": "the angular momentum's component along the zonal field's axis",
}


def describe(scene: Mapping[str, Any], name: str) -> str | None:
    """What ``name`` is in an orbit scene's results, or None if it is not one of its names."""
    return _NAMES.get(name)
