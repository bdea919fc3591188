"""The orbit integrators (Cayley 1860) against references (validation/orbit_*.py).

Fast by default: reference case R1 in double judged by the phase law of
``validation/orbit_report.py``, a few orbits of the long case L1 (Cayley vs Cartesian), and a
check that the comparison flags a wrong run (μ perturbed by 1e-9). ``-m slow``: the brief's
headline requirements — real128 within 1e-19 of every reference value, 1000 orbits of L1 in
double within the law, the inclination sweep down to 1e-8 rad.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path

import numpy as np
import orbit_report as orr
import pytest
from orbit_cases import EPSILON, LONG_BY_NAME, REFERENCE

VALIDATION = Path(__file__).resolve().parents[2] / "validation"


def reference_failures(job: dict) -> list[str]:
    out = []
    for q, err in job["errors"].items():
        tol = orr.reference_tolerance(job["case"], job["precision"], q, job["steps"])
        value = err["scaled"] if job["precision"] == "double" else err["relative"]
        if value > tol:
            out.append(f"{q}: {value:.2e} > {tol:.2e}")
    return out


# ---------------------------------------------------------------------------- fast
@pytest.mark.parametrize("formulation", ["cayley", "quaternion", "cartesian"])
def test_r1_double_within_the_phase_law(formulation):
    job = orr.reference_job("R1", formulation, "double")
    assert reference_failures(job) == []
    # Independently of the law's constants: ~150 steps keep every quantity near 1e-13.
    assert max(e["scaled"] for e in job["errors"].values()) < 1e-12


def test_long_case_few_orbits_within_the_law():
    jobs = {
        (f, "double"): orr.long_job("L1", f, "double", "quick") for f in ("cayley", "cartesian")
    }
    rows = orr.long_comparisons("L1", jobs)
    assert rows and all(r["pass"] for r in rows), rows
    drifts = [r for r in orr.drift_rows("L1", jobs) if r["judged"]]
    assert drifts and all(r["pass"] for r in drifts)


def test_the_comparison_flags_a_wrong_run():
    # μ off by 1e-9 relative: the mean motion differs by 1.5e-9, so after a few orbits the
    # position differs by ~1e-8 — far outside the law, which must say so.
    case = LONG_BY_NAME["L1"]
    times = orr.output_times(case.period, 3 * case.period, 20)
    good = orr.scene(case.base, "cartesian", "double", times)
    wrong = copy.deepcopy(good)
    wrong["orbit"]["mu"] = "1.000000001"
    ref_result, ref_steps, _ = orr.integrate(good)
    run_result, run_steps, _ = orr.integrate(wrong)
    t = np.array([float(x) for x in ref_result.t])

    def job(result, steps):
        return {
            "t": t,
            "n": orr.steps_at(steps, t),
            "precision": "double",
            "columns": orr.columns(result, ("x", "y", "z")),
        }

    a, b = job(run_result, run_steps), job(ref_result, ref_steps)
    err = orr.position_error(a, b, case.a)
    tol = orr.law(EPSILON["double"], t, np.maximum(a["n"], 1), case.period, orr.K_x(case.e))
    assert np.max(err / (2 * tol)) > 10
    # …and the reference-value comparison flags the same wrong μ.
    r1 = REFERENCE[0]
    orbit = {**r1.scene["orbit"], "mu": "1.000000001"}
    bad = orr.reference_job(
        "R1", "cayley", "double", replace(r1, scene={**r1.scene, "orbit": orbit})
    )
    assert reference_failures(bad)


# ---------------------------------------------------------------------------- slow
@pytest.mark.slow
@pytest.mark.parametrize("name", [c.name for c in REFERENCE])
def test_reference_values_real128_within_1e_19(name):
    for formulation in ("cayley", "quaternion", "cartesian"):
        job = orr.reference_job(name, formulation, "quad")
        worst = max(e["relative"] for e in job["errors"].values())
        assert worst <= 1e-19, (formulation, worst)


@pytest.mark.slow
def test_l1_1000_orbits_double_within_the_law():
    jobs = {
        (f, p): orr.long_job("L1", f, p, "full")
        for f in ("cayley", "quaternion", "cartesian")
        for p in ("double",)
    }
    jobs[("cartesian", "quad")] = orr.long_job("L1", "cartesian", "quad", "full")
    assert jobs[("cayley", "double")]["orbits"] >= 1000
    rows = orr.long_comparisons("L1", jobs)
    assert len(rows) == 5 and all(r["pass"] for r in rows), [
        (r["run"], r["against"], r["ratio"]) for r in rows
    ]
    assert all(r["pass"] for r in orr.drift_rows("L1", jobs))


@pytest.mark.slow
def test_inclination_1e_8_within_the_law():
    job = orr.inclination_job("1e-8", "full")
    assert job["sin_phi_min"] < 2e-8
    for f, run in job["runs"].items():
        assert max(run["ratio"].values()) <= 1, (f, run["ratio"])
        assert run["max"]["position"] < 1e-11


def test_passage_of_the_reference_plane_within_the_laws():
    """validation/orbit_passage.py at δ = 1e-6: position and angles within their laws against
    the closed form; the hand-over keeps Θ, Σ where they are accurate, and the equatorial
    event at sin Φ = 1e-3 exactly: its function |L|²(sin²Φ − ε²) carries a round-off of a few
    ε|L|² and changes at 2 sin Φ Φ̇ |L|² (Φ̇ ≈ φ̇′ = 0.02), so its zeros are found to
    3ε/(1e-3 · 0.02) ≈ 3e-11 in t (measured 1.6e-12)."""
    import orbit_passage

    rows = orbit_passage.measure("1e-6")
    assert [r["formulation"] for r in rows] == ["cayley", "cayley, ε = 1e-3", "quaternion"]
    assert all(r["ratio"] <= 1 for r in rows), rows
    through, handed, _ = rows
    # Integrated through, the angles lose accuracy like ε/δ (here ~1e-10); handed over, they
    # are reported only where sin Φ ≥ 1e-3, and keep ~ε/1e-3.
    assert through["dTheta"] > 1e-12 and handed["dTheta"] < 1e-12
    assert handed["handovers"] == 2 and handed["unreported"] > 0
    assert handed["dx"] < 1e-13
    found = [float(t) for t in handed["events"].time]
    assert list(handed["events"].label) == ["approach", "recede"]
    exact = handed["exact_events"]
    bound = 3 * 2.0**-52 / (1e-3 * float(orbit_passage.PHI_RATE))
    assert max(abs(a - b) for a, b in zip(found, exact, strict=True)) < bound
