"""Recorded events whose zeros fall beside a terminal event's: every crossing, once.

heyoka orders a step's zeros by separate root searches, and a terminal event ends the step; a
recorded event within round-off of it was lost or found twice until the engine accounted for
crossings by parity (:mod:`cayley_heyoka.core.event_parity`). Cayley's orbit puts its node on
the revolution count's event whenever Σ starts at 0 or π, so the cases here start it there and
just beside, and compare with the Cartesian orbit, which has no terminal event at all.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import ORBIT_ELEMENTS

import cayley_heyoka as ch
from cayley_heyoka.workflows.checkpoint import CheckpointedRun
from cayley_heyoka.workflows.members import PATH_LANES
from cayley_heyoka.workflows.study import Study
from cayley_heyoka.workflows.sweep import run_sweep

#: Σ₀ at, and within a few ulps of, the revolution count's zeros 0 and π.
SIGMAS = [
    "0",
    "-4e-16",
    "4e-16",
    "1e-300",
    "3.1415926535897922",
    "3.141592653589793",
    "3.1415926535897936",
    "-3.141592653589793",
]


def orbit(
    formulation: str = "cayley",
    sigma0: str | None = None,
    precision: str | None = None,
    stop: str = "40",
    events=("node", "apsis"),
) -> dict:
    body = {
        "mu": "1",
        "formulation": formulation,
        "elements": dict(ORBIT_ELEMENTS),
    }
    if sigma0 is not None:
        body["sigma0"] = sigma0
    scene = {
        "orbit": body,
        "output": {"times": {"start": "0", "stop": stop, "count": 11}, "events": list(events)},
    }
    if precision:
        scene["integrator"] = {"precision": precision}
    return scene


@pytest.fixture(scope="module")
def cartesian() -> ch.Result:
    return ch.run(ch.Scene.from_dict(orbit("cartesian")))


def assert_same_crossings(result: ch.Result, expected: ch.Result, tol: float = 1e-9) -> None:
    for name, log in expected.events.items():
        got = result.events[name]
        assert len(got) == len(log), (name, len(got), len(log))
        np.testing.assert_allclose(
            np.asarray(got.time, float), np.asarray(log.time, float), atol=tol
        )
        assert list(got.label) == list(log.label), name


@pytest.mark.parametrize("formulation", ["cayley", "quaternion"])
@pytest.mark.parametrize("sigma0", SIGMAS)
def test_every_node_once_where_the_revolution_count_falls_on_it(cartesian, formulation, sigma0):
    result = ch.run(ch.Scene.from_dict(orbit(formulation, sigma0)))
    assert result.counters["revolutions"] >= 5  # the terminal event did fire beside the nodes
    assert len(cartesian.events["node"]) == 12
    assert_same_crossings(result, cartesian)
    labels = list(result.events["node"].label)
    assert all(a != b for a, b in zip(labels, labels[1:], strict=False))  # they alternate


def test_an_event_of_one_direction_keeps_only_its_own_crossings(cartesian):
    """The integrator records every crossing for the accounting; a log keeps its direction's."""
    scene = orbit("cayley", "3.1415926535897922", events=("node", "rise"))
    scene["events"] = {"rise": {"expression": "z", "direction": "up"}}
    result = ch.run(ch.Scene.from_dict(scene))
    nodes = cartesian.events["node"]
    ascending = np.asarray(nodes.time, float)[np.asarray(nodes.label) == "ascending"]
    assert len(result.events["rise"]) == len(ascending) == 6
    np.testing.assert_allclose(np.asarray(result.events["rise"].time, float), ascending, atol=1e-9)


def test_quad_finds_every_node_beside_the_revolution_count():
    # π to quad's 34 digits and a Cartesian reference in quad: the same nodes, to quad's eps.
    pi = "3.141592653589793238462643383279503"
    result = ch.run(ch.Scene.from_dict(orbit("cayley", pi, precision="quad", stop="20")))
    reference = ch.run(ch.Scene.from_dict(orbit("cartesian", precision="quad", stop="20")))
    assert len(reference.events["node"]) == 6
    assert result.counters["revolutions"] >= 3
    assert_same_crossings(result, reference, tol=1e-20)


def test_sweep_lanes_count_every_node(cartesian):
    """The batch lanes hold one accounting per member: the counts of the lone runs."""
    members = ["0", "-4e-16", "3.1415926535897922", "3.1415926535897936"]
    study = Study.from_dict(
        {
            "scene": orbit("cayley", "0"),
            "sweep": {"kind": "grid", "parameters": {"orbit.sigma0": members}},
        }
    )
    result = run_sweep(study, workers=1)
    assert result.metadata["paths"] == {PATH_LANES: len(members)}
    assert list(result.events["node"]) == [12] * len(members)
    assert list(result.events["apsis"]) == [len(cartesian.events["apsis"])] * len(members)


class Stop(Exception):
    pass


def test_a_resumed_run_keeps_the_accounting(tmp_path, cartesian):
    """The accounting's baseline is part of a snapshot: interrupted between the nodes that the
    revolution count hides and resumed, the run finds each of them once."""
    scene = ch.Scene.from_dict(orbit("cayley", "3.1415926535897922"))
    whole = CheckpointedRun(scene, tmp_path / "a", 8).run()

    def stop(k, t):
        if k == 3:
            raise Stop

    with pytest.raises(Stop):
        CheckpointedRun(scene, tmp_path / "b", 8).run(stop)
    resumed = CheckpointedRun(scene, tmp_path / "b", 8).run()
    assert_same_crossings(whole, cartesian)
    assert_same_crossings(resumed, whole, tol=0)


@pytest.mark.parametrize("rates", [["0.3", "1", "0.5"], ["1.2", "0.2", "1.1"], ["2", "0.01", "1"]])
def test_rodrigues_chart_changes_lose_no_invariable_plane_crossing(rates):
    """The Rodrigues chart re-bases (a terminal event) near every half turn; the quaternion
    body has no terminal event: the same crossings of the invariable plane."""

    def body(formulation: str, start: list[str]) -> ch.Result:
        return ch.run(
            ch.Scene.from_dict(
                {
                    "body": {"inertia": ["1", "1.5", "2.5"]},
                    "initial": {"rates": rates, formulation: start},
                    "attitude": {"formulation": formulation},
                    "output": {
                        "times": {"start": "0", "stop": "200", "count": 5},
                        "events": ["invariable_plane"],
                    },
                }
            )
        )

    rodrigues = body("rodrigues", ["0", "0", "0"])
    quaternion = body("quaternion", ["1", "0", "0", "0"])
    assert rodrigues.counters["rebasings"] > 10
    assert len(quaternion.events["invariable_plane"]) > 10
    assert_same_crossings(rodrigues, quaternion, tol=1e-8)


@pytest.mark.parametrize("formulation", ["cartesian", "cayley"])
def test_sweep_members_in_steps_of_size_zero_say_so(formulation):
    """An event whose coefficients are not finite at its zero (``sqrt(z)``): heyoka's steps of
    size zero in the batch lanes, to the budget, are named as such."""
    scene = orbit("cartesian", events=("node", "root"))
    scene["events"] = {"root": {"expression": "sqrt(z)"}}
    scene["orbit"]["elements"]["mean_anomaly"] = "1"
    scene["integrator"] = {"max_steps": 20_000}
    if formulation == "cayley":
        scene["orbit"]["formulation"] = "cayley"
    study = Study.from_dict(
        {"scene": scene, "sweep": {"kind": "grid", "parameters": {"orbit.mu": ["1", "1.01"]}}}
    )
    result = run_sweep(study, workers=1)
    # Cayley's steps shrink towards zero without reaching it: steps, to the budget.
    expected = "step size fell to zero" if formulation == "cartesian" else "max_steps = 20000"
    assert all(expected in m for m in result.message), list(result.message)


def _orbits(count: int, seed: int = 2) -> list[dict]:
    """Orbits off their events' zeros at the start: eccentric, near-equatorial, retrograde,
    Σ₀ at and beside 0 and π, with and without J2."""
    import random

    rng = random.Random(seed)
    cases = []
    for _ in range(count):
        case = {
            "e": rng.choice(["0.01", "0.1", "0.5", "0.9"]),
            "inclination": rng.choice(["0.001", "0.05", "0.3", "1.5", "3.1"]),
            "argument_of_pericentre": rng.choice(["0", "0.3", "1.5707963267948966"]),
            "mean_anomaly": rng.choice(["1", "2.5", "0.4"]),
            "sigma0": rng.choice([None, "0", "3.1415926535897922", "-4e-16", "1e-17"]),
            "J2": rng.choice([None, "1e-3"]),
        }
        cases.append(case)
    return cases


@pytest.mark.parametrize("case", _orbits(12), ids=lambda c: "-".join(map(str, c.values())))
def test_every_formulation_finds_the_same_nodes_and_apsides(case):
    """The Cartesian orbit has no terminal event; Cayley's and the quaternion's count
    revolutions, Encke's rectifies at each apocentre: the same crossings in all four."""
    found = {}
    for form in ["cartesian", "cayley", "quaternion", "encke"]:
        scene = orbit(form, case["sigma0"] if form in ("cayley", "quaternion") else None)
        elements = {k: case[k] for k in ("e", "inclination", "argument_of_pericentre")}
        scene["orbit"]["elements"] |= {
            **elements,
            "node": "0.2",
            "mean_anomaly": case["mean_anomaly"],
        }
        scene["output"]["times"] = {"start": "0", "stop": "60", "count": 5}
        if case["J2"]:
            scene["perturbations"] = {"zonal": {"J2": case["J2"], "radius": "0.5"}}
        result = ch.run(ch.Scene.from_dict(scene))
        found[form] = (len(result.events["node"]), len(result.events["apsis"]))
    assert len(set(found.values())) == 1, found
