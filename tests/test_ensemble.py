"""Ensemble propagation: every mode reproduces run() member by member; bad input is refused."""

from __future__ import annotations

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.workflows.ensemble import (
    MODES,
    EnsembleError,
    ensemble_state,
    propagate_ensemble,
)

T_END = 10.0
# Members: 11, not a multiple of the SIMD width (8 on AVX-512, 4 on AVX2), so that the last
# batch is padded.
MEMBERS = 11

BODY = {
    "body": {"inertia": [1.0, 1.5, 2.5]},
    "initial": {"rates": [0.3, 1.0, 0.5]},
    "attitude": {"formulation": "quaternion"},
    "output": {"times": [0.0, T_END]},
}
ORBIT = {
    "orbit": {
        "mu": 1.0,
        "position": [0.9, 0.2, 0.1],
        "velocity": [-0.25, 0.85, 0.45],
        "formulation": "cartesian",
    },
    "perturbations": {"zonal": {"J2": 0.0010826, "radius": 0.8}},
    "output": {"times": [0.0, T_END]},
}


def _body_members(rng: np.random.Generator) -> list[ch.Scene]:
    scenes = []
    for _ in range(MEMBERS):
        q = rng.standard_normal(4)
        q /= np.linalg.norm(q)
        rates = np.array([0.3, 1.0, 0.5]) + 0.1 * rng.standard_normal(3)
        initial = {"rates": [float(v) for v in rates], "quaternion": [float(v) for v in q]}
        scenes.append(ch.Scene.from_dict({**BODY, "initial": initial}))
    return scenes


def _orbit_members(rng: np.random.Generator) -> list[ch.Scene]:
    scenes = []
    for _ in range(MEMBERS):
        x = np.array([0.9, 0.2, 0.1]) * (1 + 0.05 * rng.standard_normal(3))
        v = np.array([-0.25, 0.85, 0.45]) * (1 + 0.05 * rng.standard_normal(3))
        orbit = {**ORBIT["orbit"], "position": x.tolist(), "velocity": v.tolist()}
        scenes.append(ch.Scene.from_dict({**ORBIT, "orbit": orbit}))
    return scenes


@pytest.fixture(scope="module", params=["body", "orbit"])
def case(request):
    """The base scene, its members as scenes, their initial states and run()'s final states."""
    rng = np.random.default_rng(7)
    base, members = {
        "body": (BODY, _body_members),
        "orbit": (ORBIT, _orbit_members),
    }[request.param]
    scenes = members(rng)
    names, _ = ensemble_state(scenes[0])
    initial = np.array([ensemble_state(s)[1] for s in scenes])
    final = np.array([[ch.run(s)[n][-1] for n in names] for s in scenes])
    return ch.Scene.from_dict(base), names, initial, final


@pytest.mark.parametrize("mode", MODES)
def test_each_mode_equals_run_member_by_member(case, mode):
    scene, names, initial, final = case
    out = propagate_ensemble(scene, initial, T_END, mode=mode, workers=2)
    assert out.names == names
    assert out.states.shape == (MEMBERS, len(names))
    assert out.t_end == T_END and out.t_start == 0.0
    assert (out.steps > 0).all()
    # The scalar modes step exactly as run() does; batch lanes round their SIMD arithmetic
    # differently, a few ulps of the state.
    scale = np.abs(final).max(axis=1, keepdims=True)
    assert np.abs(out.states - final).max() <= 1e-13 * scale.max()


def test_threads_with_many_tasks_keep_member_order():
    scene = ch.Scene.from_dict(BODY)
    _, x0 = ensemble_state(scene)
    rng = np.random.default_rng(3)
    members = np.repeat(x0[None, :], 300, axis=0)
    members[:, :3] += 0.1 * rng.standard_normal((300, 3))
    serial = propagate_ensemble(scene, members, 2.0, mode="serial")
    for mode in ("threads", "batch"):
        out = propagate_ensemble(scene, members, 2.0, mode=mode, workers=3)
        assert np.abs(out.states - serial.states).max() <= 1e-14
        assert out.workers == 3


def test_quad_threads_match_serial():
    data = {**BODY, "attitude": {"formulation": "none"}, "integrator": {"precision": "quad"}}
    scene = ch.Scene.from_dict(data)
    _, x0 = ensemble_state(scene)
    members = [[str(x0[0]), "0.9", "0.45"], ["0.31", "1.01", "0.49"]]
    serial = propagate_ensemble(scene, members, "1.5", mode="serial")
    threads = propagate_ensemble(scene, members, "1.5", mode="threads")
    assert serial.states.dtype == x0.dtype
    assert (serial.states == threads.states).all()
    with pytest.raises(ValueError, match="double precision only"):
        propagate_ensemble(scene, members, "1.5", mode="batch")


@pytest.mark.parametrize(
    ("states", "match"),
    [
        (np.zeros(7), r"shape \(members, 7\)"),
        (np.zeros((3, 6)), r"shape \(members, 7\)"),
        (np.zeros((0, 7)), r"shape \(members, 7\)"),
        ([["a"] * 7], r"initial_states\[0, 0\] must be a finite number: 'a' is not a decimal"),
    ],
)
def test_wrong_shapes_are_refused(states, match):
    with pytest.raises(ValueError, match=match):
        propagate_ensemble(ch.Scene.from_dict(BODY), states, T_END)


def test_non_finite_input_names_member_and_variable():
    scene = ch.Scene.from_dict(BODY)
    _, x0 = ensemble_state(scene)
    states = np.repeat(x0[None, :], 4, axis=0)
    states[2, 4] = np.nan
    with pytest.raises(ValueError, match=r"initial_states\[2\] is not finite: qx = nan"):
        propagate_ensemble(scene, states, T_END)
    with pytest.raises(ValueError, match="t_end must be a finite number: inf is not finite"):
        propagate_ensemble(scene, states[:2], float("inf"))


@pytest.mark.parametrize("mode", MODES)
def test_a_member_going_non_finite_is_named(mode):
    scene = ch.Scene.from_dict(ORBIT)
    _, x0 = ensemble_state(scene)
    states = np.repeat(x0[None, :], 12, axis=0)
    states[9, :3] = 0.0  # at the central mass: the acceleration is infinite
    with pytest.raises(EnsembleError, match="member 9: its state became non-finite") as info:
        propagate_ensemble(scene, states, T_END, mode=mode)
    assert info.value.member == 9


def test_scenes_and_options_it_cannot_run_are_refused():
    states = np.zeros((2, 7))
    rodrigues = {**BODY, "attitude": {"formulation": "rodrigues"}}
    with pytest.raises(ValueError, match="formulation = 'quaternion'"):
        propagate_ensemble(ch.Scene.from_dict(rodrigues), np.zeros((2, 6)), T_END)
    cayley = {**ORBIT, "orbit": {**ORBIT["orbit"], "formulation": "cayley"}}
    with pytest.raises(ValueError, match="formulation = 'cartesian'"):
        propagate_ensemble(ch.Scene.from_dict(cayley), np.zeros((2, 7)), T_END)
    events = {**BODY, "output": {"times": [0.0, T_END], "events": ["invariable_plane"]}}
    with pytest.raises(ValueError, match="records no events"):
        propagate_ensemble(ch.Scene.from_dict(events), states, T_END)
    scene = ch.Scene.from_dict(BODY)
    with pytest.raises(ValueError, match="mode must be one of"):
        propagate_ensemble(scene, states, T_END, mode="gpu")
    with pytest.raises(ValueError, match="workers must be a positive integer"):
        propagate_ensemble(scene, states, T_END, workers=0)
