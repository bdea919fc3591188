"""Hostile sweeps through shared model structures (cayley_heyoka.core.structures): members
whose numbers a structure cannot take, members whose numbers are compiled into their
equations, and members that reach a terminal handler shared by their structure. Each member
ends as its own scene run alone would, or fails by its field; nothing escapes the command."""

from __future__ import annotations

import numpy as np
import pytest

import cayley_heyoka as ch

BODY = {
    "body": {"inertia": [1.0, 1.5, 2.5]},
    "initial": {"rates": [0.3, 1.0, 0.5], "quaternion": [1, 0, 0, 0]},
    "output": {"times": {"start": 0.0, "stop": 2.0, "count": 3}, "events": ["invariable_plane"]},
}


def _study(hostile, scene: dict, parameters: dict) -> str:
    data = {"title": "s", "scene": scene, "sweep": {"kind": "grid", "parameters": parameters}}
    return str(hostile.scene(data, name="study.toml"))


@pytest.mark.covers("verb:sweep", "class:12")
def test_a_member_whose_numbers_its_structure_refuses_fails_by_field(hostile, tmp_path):
    """A body at rest has no invariable plane: refused by the numbers that fill the structure
    the other members share, for that member only."""
    parameters = {f"initial.rates[{i}]": [0.0, 0.5] for i in range(3)}
    out = tmp_path / "s.h5"
    o = hostile.run(["sweep", _study(hostile, BODY, parameters), "--out", str(out)],
                    expect="stopped", out=out)  # fmt: skip
    assert "7 completed, 1 failed" in o.stdout
    assert "member 0 (" in o.stdout and "output.events: invariable_plane is undefined" in o.stdout
    swept = ch.load_sweep(out)
    assert swept.completed.sum() == 7 and not swept.completed[0]
    # None of them has a model: refused before any work, naming the first member.
    at_rest = {f"initial.rates[{i}]": [0.0] for i in range(3)}
    hostile.run(["sweep", _study(hostile, BODY, at_rest), "--out", str(tmp_path / "t.h5")],
                expect="refused", field="member 0 (initial.rates[0] = 0")  # fmt: skip
    assert not (tmp_path / "t.h5").exists()


@pytest.mark.covers("verb:sweep")
def test_members_whose_numbers_are_compiled_in_each_take_their_own_equations(hostile, tmp_path):
    """A reduced body's vertical is compiled into its equations (a zero component drops a
    term): members with other verticals are other structures, each the run of its scene."""
    scene = {
        "body": {"inertia": [1.0, 1.0, 0.5]},
        "initial": {"rates": [0.1, 0.2, 4.0], "quaternion": [1, 0, 0, 0]},
        "attitude": {"formulation": "poisson"},
        "forces": {"heavy_top": {"weight": 1.0, "center_of_mass": [0, 0, 0.4]}},
        "output": {"times": {"start": 0.0, "stop": 3.0, "count": 4}},
    }
    ups = [[0, 0, 1], [0, 0.6, 0.8], [1, 0, 0]]
    study = hostile.scene(
        {"title": "s", "scene": scene,
         "sweep": {"kind": "grid", "parameters": {
             f"forces.heavy_top.up[{i}]": sorted({u[i] for u in ups}) for i in range(3)}}}
    )  # fmt: skip
    out = tmp_path / "s.h5"
    # Most of the grid's verticals are not unit vectors: refused by field before any work.
    hostile.run(["sweep", str(study), "--out", str(out)], expect="refused",
                field="forces.heavy_top.up")  # fmt: skip
    assert not out.exists()
    for k, up in enumerate(ups):  # one vertical a sweep: its own structure, its scene's run
        data = {**scene, "forces": {"heavy_top": {**scene["forces"]["heavy_top"], "up": up}}}
        parameters = {"initial.rates[2]": [4.0, 3.0]}
        swept_out = tmp_path / f"s{k}.h5"
        hostile.run(["sweep", _study(hostile, data, parameters), "--out", str(swept_out)],
                    expect="done", out=swept_out)  # fmt: skip
        swept = ch.load_sweep(swept_out)
        for row, r in enumerate((4.0, 3.0)):
            alone = ch.run(
                ch.Scene.from_dict({**data, "initial": {**data["initial"], "rates": [0.1, 0.2, r]}})
            )
            expected = [float(alone.variables[n][-1]) for n in swept.final_names]
            np.testing.assert_allclose(swept.final_state[row], expected, rtol=1e-12, atol=1e-13)


@pytest.mark.covers("verb:sweep", "class:8")
def test_members_through_a_shared_chart_handler_cross_the_plane_as_alone(hostile, tmp_path):
    """The Rodrigues chart's re-basing is one handler for every member of the structure: each
    member's invariable-plane crossings are its own run's."""
    scene = {
        **BODY,
        "initial": {"rates": [0.3, 1.0, 0.5], "rodrigues": [0.1, 0.2, -0.3]},
        "attitude": {"formulation": "rodrigues", "max_chart_angle": 90},
        "output": {"times": {"start": 0.0, "stop": 20.0, "count": 5},
                   "events": ["invariable_plane"]},
    }  # fmt: skip
    rates = [0.3, -0.8, 1.5]
    out = tmp_path / "s.h5"
    hostile.run(["sweep", _study(hostile, scene, {"initial.rates[0]": rates}), "--out", str(out)],
                expect="done", out=out)  # fmt: skip
    swept = ch.load_sweep(out)
    for row, p in enumerate(rates):
        alone = ch.run(
            ch.Scene.from_dict({**scene, "initial": {**scene["initial"], "rates": [p, 1.0, 0.5]}})
        )
        assert alone.counters["rebasings"] > 0
        assert swept.events["invariable_plane"][row] == len(alone.events["invariable_plane"].time)
        assert swept.steps[row] == alone.counters["steps"]


@pytest.mark.covers("verb:sweep", "class:12")
def test_a_member_the_table_would_pass_but_its_scene_refuses_refuses_the_study(hostile, tmp_path):
    """Members' numbers computed at once (the family's table) vouch for no member its scene
    would refuse: moments that violate the triangle inequality, or sit on its edge in decimals,
    are validated alone, and the study is refused naming the member."""
    scene = {**BODY, "output": {"times": {"start": 0.0, "stop": 2.0, "count": 3}}}
    C = "body.inertia[2]"
    moments = [2.5, 2.25, "2.5000000000000000001", 0.5, 2.6]  # 2.6 > 1 + 1.5
    out = tmp_path / "s.h5"
    hostile.run(["sweep", _study(hostile, scene, {"body.inertia[2]": moments}), "--out", str(out)],
                expect="refused", field=f"member 2 ({C} = 2.5): body.inertia")  # fmt: skip
    assert not out.exists()
    doubles = [2.5, 2.25, 0.5, 2.6]
    hostile.run(["sweep", _study(hostile, scene, {"body.inertia[2]": doubles}), "--out", str(out)],
                expect="refused", field=f"member 3 ({C} = 2.6): body.inertia")  # fmt: skip
    assert not out.exists()
    edge = [2.5, 2.25, "2.4999999999999999999", 0.5]
    hostile.run(["sweep", _study(hostile, scene, {"body.inertia[2]": edge}), "--out", str(out)],
                expect="done", out=out)  # fmt: skip
    swept = ch.load_sweep(out)
    for row, c in enumerate(edge):
        alone = ch.run(ch.Scene.from_dict({**scene, "body": {"inertia": [1.0, 1.5, c]}}))
        expected = [float(alone.variables[n][-1]) for n in swept.final_names]
        np.testing.assert_allclose(swept.final_state[row], expected, rtol=1e-12, atol=1e-13)
        assert swept.steps[row] == alone.counters["steps"]


ORBIT = {
    "orbit": {"mu": "1", "formulation": "cayley",
              "elements": {"a": "1.2", "e": "0.25", "inclination": "0.5", "node": "0.3",
                           "argument_of_pericentre": "0.4", "mean_anomaly": "0.2"}},
    "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.5"}},
    "output": {"times": {"start": "0", "stop": "20", "count": 3}},
}  # fmt: skip


@pytest.mark.covers("verb:sweep", "class:12")
def test_orbits_at_and_over_their_limits_are_validated_alone(hostile, tmp_path):
    """Orbits' numbers computed at once (double-double) vouch for no member at or over a limit
    of its scene: an eccentricity that rounds to 1 in double (an ellipse, or not), a start in
    the reference plane, a nearly rectilinear motion. Over a limit, the study is refused
    naming the member; at it, the member runs as it would alone."""
    e = "orbit.elements.e"
    over = ["0.25", "0.99999999999999999999", "0.5", "1.00000000000000000001"]
    out = tmp_path / "s.h5"
    hostile.run(["sweep", _study(hostile, ORBIT, {e: over}), "--out", str(out)],
                expect="refused", field=f"member 3 ({e} = 1.0): {e}")  # fmt: skip
    assert not out.exists()
    at = ["0.25", "0.99999999", "0.5"]
    inclinations = ["0.5", "0", "1e-4"]  # in the plane, and below the hand-over limit
    parameters = {e: at, "orbit.elements.inclination": inclinations}
    hostile.run(["sweep", _study(hostile, ORBIT, parameters), "--out", str(out)],
                expect={"done", "stopped"}, out=out)  # fmt: skip
    swept = ch.load_sweep(out)
    k = 0
    for ecc in at:
        for inclination in inclinations:
            elements = {**ORBIT["orbit"]["elements"], "e": ecc, "inclination": inclination}
            scene = {**ORBIT, "orbit": {**ORBIT["orbit"], "elements": elements}}
            try:
                alone = ch.run(ch.Scene.from_dict(scene))
            except ch.IntegrationError as exc:
                alone = exc.result
            assert swept.steps[k] == alone.counters["steps"], (ecc, inclination)
            if alone.success:
                expected = [float(alone.variables[n][-1]) for n in swept.final_names]
                np.testing.assert_allclose(swept.final_state[k], expected, rtol=1e-12, atol=1e-13)
            k += 1
    rectilinear = {"orbit.velocity[0]": ["-0.25", "1.8", "1.80000000000000000001"]}
    scene = {**ORBIT, "orbit": {"mu": "1", "position": ["0.9", "0.2", "0.1"],
                                "velocity": ["-0.25", "0.85", "0.45"]}}  # fmt: skip
    scene["orbit"]["velocity"] = ["-0.25", "0.4", "0.2"]  # 1.8 = 2 × 0.9: v ∥ x
    study, field = _study(hostile, scene, rectilinear), "member 1 (orbit.velocity[0] = 1.8)"
    hostile.run(["sweep", study, "--out", str(tmp_path / "r.h5")],
                expect="refused", field=f"{field}: orbit.velocity")  # fmt: skip
