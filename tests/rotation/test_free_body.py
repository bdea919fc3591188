"""Torque-free integrations against the 25-digit closed-form values and the exact invariants.

Reference values: 25 digits of the closed form computed independently at 50 digits and
confirmed by a quad-precision integration, kept below. The attitude is compared in the invariable
frame: the run starts from λ₀(0) = Bq₁/(k + Cr₁), μ₀(0) = −Ap₁/(k + Cr₁), ν₀(0) = 0.
"""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
from helpers import PRECISIONS

from cayley_heyoka import Scene, run

CASES = {
    "major_axis": dict(
        inertia=("1", "1.5", "2.5"),
        rates=("0.125", "0.25", "1"),
        t="10",
        p="0.03701005140819792930314192",
        q="-0.2770473896191092908781587",
        r="0.9985734568778841172878553",
        lam="-0.1002544949724092960912453",
        mu="0.1902029234444625537810625",
        nu="-2.390092871587000921892715",
    ),
    "minor_axis": dict(
        inertia=("1", "1.5", "2.5"),
        rates=("1", "0.1875", "0.25"),
        t="12.5",
        p="0.9081804870265588525008913",
        q="-0.4586550479218585552298852",
        r="0.1657056408308405367168351",
        lam="0.2634213254742426020622825",
        mu="-1.078296648331565776955060",
        nu="1.229337411019955974857845",
    ),
    "c_intermediate": dict(
        inertia=("2.5", "1", "1.75"),
        rates=("0.5", "-0.75", "0.625"),
        t="8",
        p="0.1762150868396231963175924",
        q="0.1230015937894296575196216",
        r="-1.008063196956143300424109",
        lam="3.379203639073671863888878",
        mu="-7.197802712981020955886950",
        nu="0.1682188402831881917506973",
    ),
}
# The references carry 25 significant digits; a run cannot be checked beyond that.
REF_DIGITS = 1e-24


def invariable_frame_start(case):
    mpmath.mp.dps = 50
    A, B, C = (mpmath.mpf(x) for x in case["inertia"])
    p, q, r = (mpmath.mpf(x) for x in case["rates"])
    k = mpmath.sqrt((A * p) ** 2 + (B * q) ** 2 + (C * r) ** 2)
    return [mpmath.nstr(B * q / (k + C * r), 45), mpmath.nstr(-A * p / (k + C * r), 45), "0"]


def scene(case, precision, formulation):
    return Scene.from_dict(
        {
            "body": {"inertia": list(case["inertia"])},
            "initial": {"rates": list(case["rates"]), "rodrigues": invariable_frame_start(case)},
            "attitude": {"formulation": formulation},
            "integrator": {"precision": precision.to_spec()},
            "output": {"times": ["0", case["t"]]},
        }
    )


def rel_err(value, ref):
    ref = mpmath.mpf(ref)
    return float(abs(mpmath.mpf(str(value)) - ref) / max(1, abs(ref)))


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize(
    "prec_name, formulation",
    [
        ("double", "rodrigues"),
        ("double", "quaternion"),
        ("quad", "rodrigues"),
        ("quad", "quaternion"),
    ],
)
def test_against_closed_form(name, prec_name, formulation):
    case, prec = CASES[name], PRECISIONS[prec_name]
    result = run(scene(case, prec, formulation))
    # Observed: a few ε in double over these O(1) periods; the rest is the references' digits.
    tol = max(100 * prec.epsilon, REF_DIGITS)
    for var, key in (
        ("p", "p"),
        ("q", "q"),
        ("r", "r"),
        ("lambda", "lam"),
        ("mu", "mu"),
        ("nu", "nu"),
    ):
        assert rel_err(result[var][-1], case[key]) < tol, (var, rel_err(result[var][-1], case[key]))


def test_multiprecision_against_closed_form():
    case, prec = CASES["major_axis"], PRECISIONS["real256"]
    result = run(scene(case, prec, "rodrigues"))
    for var, key in (("p", "p"), ("r", "r"), ("nu", "nu")):
        assert rel_err(result[var][-1], case[key]) < REF_DIGITS


@pytest.mark.parametrize("formulation", ["quaternion", "rodrigues"])
@pytest.mark.parametrize("prec_name", ["double", "quad", "real256"])
def test_conservation_at_each_precision(prec_name, formulation):
    prec = PRECISIONS[prec_name]
    stop = "200" if prec_name == "double" else "20"
    data = {
        "body": {"inertia": ["1", "1.6", "2.3"]},
        "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
        "attitude": {"formulation": formulation},
        "integrator": {"precision": prec.to_spec()},
        "output": {"times": {"start": "0", "stop": stop, "count": 201}},
    }
    result = run(Scene.from_dict(data))
    steps = result.counters["steps"]
    # Brouwer's law: unbiased round-off grows like ε √steps; allow a modest constant.
    bound = 30 * prec.epsilon * np.sqrt(steps)
    for name in ("energy", "momentum_squared", "momentum_space"):
        worst = float(np.max(np.abs(result.drift(name))))
        assert worst < bound, (name, worst, bound)
    defect = float(np.max(result["orthogonality"]))
    if formulation == "rodrigues":
        # The chart's matrix is orthogonal by construction: only its evaluation rounds.
        assert defect < 30 * prec.epsilon, defect
    else:
        # The quaternion's norm walks by Brouwer's law like the invariants.
        assert defect < bound, (defect, bound)
