"""The case matrix of the orbit validation (Cayley 1860): scenes, spans and reference values.

Every scene number is a decimal string, so every precision integrates the same exact inputs
(``docs/scenes.md``); output times are binary64 values, exact in every precision, so runs in
different precisions are compared on the same grid.

* ``REFERENCE``: cases R1–R4, inputs and the state at ``t`` to 20 digits, computed independently
  by two quad-precision integrations (Cartesian, and Cayley's system), which agree to ~1e-26.
* ``LONG``: two 1000-orbit problems, (a) J2 only with a fixed plane (R1's inputs) and (b) J2
  about a tilted axis + a third body + a moving reference plane (R3-like; the J2 axis is the
  perturber's orbit normal, so the Jacobi constant is conserved and its drift can be judged).
* ``INCLINATIONS``: J2 about z and a third body in the reference plane, so the orbit plane stays
  near the reference plane; i from 1 to 1e-8 rad, e = 0.1, 100 orbits.
* ``ECCENTRICITIES``: J2 (radius a(1 − e)/2, so the pericentre stays outside the body) and a
  third body, e from 0 to 0.99, 100 orbits.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field

import mpmath

SPECS = {"double": "double", "quad": "quad", "real160": {"bits": 160}}
EPSILON = {"double": 2.0**-52, "quad": 2.0**-112, "real160": 2.0**-159}
FORMULATIONS = ("cayley", "quaternion", "cartesian")

# ---------------------------------------------------------------------------- R1–R4
# Quantities in the order of the cases' tables; "x", …, "vz" are the Cartesian state.
QUANTITIES = ("r", "rdot", "rho", "h", "Theta", "Sigma", "Phi", "x", "y", "z", "vx", "vy", "vz")


@dataclass(frozen=True)
class ReferenceCase:
    """One test case: its scene, time and values at ``t``."""

    name: str
    title: str
    scene: dict
    t: str
    values: dict[str, str]
    a: float  # osculating semi-major axis at t = 0 (for the law's orbit count)
    e: float  # osculating eccentricity at t = 0

    def scene_for(self, formulation: str, precision: str, times: list) -> dict:
        d = copy.deepcopy(self.scene)
        d["orbit"]["formulation"] = formulation
        if formulation == "cartesian":
            d["orbit"].pop("sigma0", None)
        d["integrator"] = {"precision": SPECS[precision]}
        d["output"] = {"times": list(times)}
        return d


REFERENCE = (
    ReferenceCase(
        "R1",
        "J2 only, fixed reference plane (spin axis = z0)",
        {
            "orbit": {
                "mu": "1",
                "position": ["0.9", "0.2", "0.1"],
                "velocity": ["-0.25", "0.85", "0.45"],
                "sigma0": "0",
            },
            "perturbations": {"zonal": {"J2": "0.0010826", "radius": "0.8"}},
        },
        "50",
        {
            "r": "0.91754381238570604346",
            "rdot": "-0.044431014285083049911",
            "rho": "63.506274576114734312",
            "h": "0.92138573223351558618",
            "Theta": "-0.068781647446886413184",
            "Sigma": "-0.071130813592626208822",
            "Phi": "0.48529528100646901776",
            "x": "0.71037710291908746397",
            "y": "0.50293930986728166014",
            "z": "0.29034990939520265054",
            "vx": "-0.66915495340167687317",
            "vy": "0.67352349558539207195",
            "vz": "0.33009658283230273760",
        },
        0.855318,
        0.0849214,
    ),
    ReferenceCase(
        "R2",
        "third body on a fixed circular orbit, fixed reference plane",
        {
            "orbit": {
                "mu": "1",
                "position": ["1.0", "0.0", "0.0"],
                "velocity": ["0.0", "0.9", "0.35"],
                "sigma0": "0.5",
            },
            "perturbations": {
                "third_body": {
                    "gm": "0.01",
                    "a": "4",
                    "n": "0.125",
                    "inclination": "0.2",
                    "node": "0.5",
                    "mean_anomaly0": "0.3",
                }
            },
        },
        "80",
        {
            "r": "0.99803033444417985127",
            "rdot": "-0.015289492490858408243",
            "rho": "88.690120032842073207",
            "h": "0.96562285812520598225",
            "Theta": "-0.0051888935588595229872",
            "Sigma": "0.49516300385363752105",
            "Phi": "0.36992332943352065185",
            "x": "0.97275538031796457047",
            "y": "0.20742124951939164451",
            "z": "0.082388978516715845238",
            "vx": "-0.23125864697784773964",
            "vy": "0.87620734400274891923",
            "vz": "0.33930137453799927162",
        },
        0.936768,
        0.0675,
    ),
    ReferenceCase(
        "R3",
        "J2 (tilted axis) + third body, moving reference plane, x1 a departure point",
        {
            "orbit": {
                "mu": "1",
                "position": ["0.5", "-0.8", "0.3"],
                "velocity": ["0.9", "0.45", "0.2"],
                "sigma0": "0.7",
            },
            "perturbations": {
                "zonal": {"J2": "0.001", "radius": "0.6", "axis": ["0.1", "-0.2", "1"]},
                "third_body": {
                    "gm": "0.001",
                    "a": "3",
                    "n": "0.2",
                    "inclination": "0.3",
                    "node": "0.2",
                    "mean_anomaly0": "1.0",
                },
            },
            "reference_plane": {
                "theta0": "0.3",
                "theta_rate": "0.002",
                "phi0": "0.2",
                "phi_rate": "0.001",
                "sigma0": "0.1",
            },
        },
        "100",
        {
            "r": "1.1301518064558511140",
            "rdot": "0.10898644939439616932",
            "rho": "97.269116015122398418",
            "h": "1.0045791502895634261",
            "Theta": "-2.5807071222033200875",
            "Sigma": "0.67913581658894126537",
            "Phi": "0.62137023908715296683",
            "x": "1.0821190824467400077",
            "y": "-0.032945599128392473248",
            "z": "0.32430847127098040504",
            "vx": "0.17627597749570660164",
            "vy": "0.86978279904390681766",
            "vz": "-0.12002415719870077010",
        },
        1.03327,
        0.153405,
    ),
    ReferenceCase(
        "R4",
        "retrograde eccentric orbit, J2, reference plane turning about z0 (φ′ constant)",
        {
            "orbit": {
                "mu": "1",
                "position": ["0.6", "0.3", "-0.2"],
                "velocity": ["0.2", "-1.35", "-0.6"],
                "sigma0": "-1.0",
            },
            "perturbations": {"zonal": {"J2": "0.002", "radius": "0.5"}},
            "reference_plane": {
                "theta0": "-0.5",
                "theta_rate": "0.01",
                "phi0": "0.4",
                "phi_rate": "0",
                "sigma0": "0.25",
            },
        },
        "60",
        {
            "r": "1.6621013544153836037",
            "rdot": "-0.42811875027560051125",
            "rho": "26.734766236741659692",
            "h": "1.0303586184490513178",
            "Theta": "-0.74245757757382385981",
            "Sigma": "-1.1231934843083595875",
            "Phi": "2.7196181337340400024",
            "x": "-0.77644773585945291321",
            "y": "1.2064168093140621778",
            "z": "0.83920695184957780082",
            "vx": "0.67475048133955693799",
            "vy": "0.072084281574021233977",
            "vz": "-0.32725176972196370304",
        },
        1.57569,
        0.571083,
    ),
)
REFERENCE_BY_NAME = {c.name: c for c in REFERENCE}


# ---------------------------------------------------------------------------- scenes
def scene(
    base: dict, formulation: str, precision: str, times: list, limit: str | None = None
) -> dict:
    """``base`` with the formulation, the precision (tolerance auto) and the output times."""
    d = copy.deepcopy(base)
    d["orbit"]["formulation"] = formulation
    if formulation == "cartesian":
        d["orbit"].pop("sigma0", None)
    elif limit is not None:
        d["orbit"]["equatorial_limit"] = limit
    d["integrator"] = {"precision": SPECS[precision]}
    d["output"] = {"times": list(times)}
    return d


def _axis_of(inclination: str, node: str) -> list[str]:
    """The unit normal (sin Ω sin i, −cos Ω sin i, cos i) of an orbit, as 60-digit text.

    60 digits, not fewer: a 160-bit run resolves ~48 digits, and a J2 axis misaligned with the
    perturber's normal by 1e-40 (40-digit text) made its Jacobi constant drift by ~1e-41 over
    1000 orbits, 5e3 times Brouwer's tolerance (a first full run of the report).
    """
    with mpmath.workdps(80):
        i, n = mpmath.mpf(inclination), mpmath.mpf(node)
        k = [mpmath.sin(n) * mpmath.sin(i), -mpmath.cos(n) * mpmath.sin(i), mpmath.cos(i)]
        return [mpmath.nstr(c, 60) for c in k]


@dataclass(frozen=True)
class LongCase:
    """A problem integrated over many orbits in every formulation and precision."""

    name: str
    title: str
    base: dict
    a: float  # initial osculating semi-major axis
    e: float  # initial osculating eccentricity
    conserved: tuple[str, ...]  # monitors the exact flow conserves
    orbits: dict[str, float] = field(default_factory=dict)  # per mode

    @property
    def period(self) -> float:
        return 2 * math.pi * self.a**1.5


_THIRD_BODY = {"gm": "0.001", "a": "3", "n": "0.2", "inclination": "0.3", "node": "0.2"}
LONG = (
    LongCase(
        "L1",
        "J2 only, fixed reference plane (R1's inputs)",
        {
            "orbit": copy.deepcopy(REFERENCE[0].scene["orbit"]),
            "perturbations": {"zonal": {"J2": "0.0010826", "radius": "0.8"}},
        },
        0.855318,
        0.0849214,
        ("energy", "polar_momentum"),
        {"full": 1000, "quick": 5},
    ),
    LongCase(
        "L2",
        "J2 about a tilted axis + third body (circular, its normal = the J2 axis) + moving "
        "reference plane (R3-like)",
        {
            "orbit": {
                "mu": "1",
                "elements": {
                    "a": "1",
                    "e": "0.15",
                    "inclination": "1",
                    "node": "0.4",
                    "argument_of_pericentre": "0.3",
                    "mean_anomaly": "0.5",
                },
                "sigma0": "0.7",
            },
            "perturbations": {
                "zonal": {"J2": "0.001", "radius": "0.6", "axis": _axis_of("0.3", "0.2")},
                "third_body": {**_THIRD_BODY, "mean_anomaly0": "1"},
            },
            # θ′₀ = 0.2, φ′₀ = 0.3: the plane starts perpendicular to the J2 axis and turns
            # away slowly, so Φ stays within ~[0.8, 1.4] (never near the Cayley singularity).
            "reference_plane": {
                "theta0": "0.2",
                "theta_rate": "0.0002",
                "phi0": "0.3",
                "phi_rate": "0.00002",
                "sigma0": "0.1",
            },
        },
        1.0,
        0.15,
        ("jacobi",),
        {"full": 1000, "quick": 3},
    ),
)
LONG_BY_NAME = {c.name: c for c in LONG}

# The J₂ orbit timed by orbit_passage.py (step cost) and planned by planner.py: e = 0.1,
# i = 0.5, J₂ of the Earth on a body of radius 0.8.
J2_ORBIT = {
    "orbit": {
        "mu": "1",
        "elements": {
            "a": "1",
            "e": "0.1",
            "inclination": "0.5",
            "node": "0.3",
            "argument_of_pericentre": "0.2",
            "mean_anomaly": "0",
        },
    },
    "perturbations": {"zonal": {"J2": "1.0826e-3", "radius": "0.8"}},
}


# ---------------------------------------------------------------------------- sweeps
INCLINATIONS = ("1", "1e-1", "1e-2", "1e-3", "1e-4", "1e-5", "1e-6", "1e-7", "1e-8")
SWEEP_ORBITS = {"full": 100, "quick": 3}
INCLINATION_E = "0.1"


def inclination_base(inclination: str) -> dict:
    """J2 about z and a third body in the reference plane: Φ stays ≈ i (no normal forcing
    beyond what sin Φ carries)."""
    return {
        "orbit": {
            "mu": "1",
            "elements": {
                "a": "1",
                "e": INCLINATION_E,
                "inclination": inclination,
                "node": "0.4",
                "argument_of_pericentre": "0.3",
                "mean_anomaly": "0.5",
            },
            "sigma0": "0.2",
        },
        "perturbations": {
            "zonal": {"J2": "0.001", "radius": "0.5"},
            "third_body": {"gm": "0.001", "a": "3", "n": "0.2", "mean_anomaly0": "1"},
        },
    }


ECCENTRICITIES = ("0", "0.01", "0.1", "0.3", "0.5", "0.7", "0.9", "0.95", "0.99")


def eccentricity_base(e: str) -> dict:
    """J2 with radius a(1 − e)/2 (pericentre twice the radius) + a third body at a₃ = 5 (beyond
    the largest apocentre 1.99)."""
    with mpmath.workdps(30):
        radius = mpmath.nstr((1 - mpmath.mpf(e)) / 2, 20)
    return {
        "orbit": {
            "mu": "1",
            "elements": {
                "a": "1",
                "e": e,
                "inclination": "0.5",
                "node": "0.3",
                "argument_of_pericentre": "0.7",
                "mean_anomaly": "0.2",
            },
            "sigma0": "0.1",
        },
        "perturbations": {
            "zonal": {"J2": "0.001", "radius": radius},
            "third_body": {
                "gm": "0.001",
                "a": "5",
                "n": "0.0895",
                "inclination": "0.3",
                "node": "0.2",
                "mean_anomaly0": "1",
            },
        },
    }
