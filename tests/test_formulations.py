"""Each family's formulation objects (``<family>/formulations.py``): every name the scene takes
has one, and what each declares is what the scene's validation and the built model do."""

from __future__ import annotations

import copy
import pickle

import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.errors import SceneError
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.structures import model_for
from cayley_heyoka.hamilton import formulations as ham
from cayley_heyoka.orbit import formulations as orb
from cayley_heyoka.orbit.cartesian_check import TWINS
from cayley_heyoka.rotation import formulations as rot

MODULES = {"rotation": rot, "orbit": orb, "hamiltonian": ham}
KEYS = {
    "rotation": "attitude.formulation",
    "orbit": "orbit.formulation",
    "hamiltonian": "hamiltonian.formulation",
}


def _scene(data: dict) -> ch.Scene:
    return ch.Scene.from_dict(data)


def _refusal(data: dict) -> str | None:
    """The scene's refusal (building its model too), or None where it is accepted."""
    try:
        model_for(_scene(data))
    except SceneError as exc:
        return str(exc)
    return None


@pytest.mark.parametrize("family", list(MODULES))
def test_every_name_has_one_object_found_by_it(family):
    module = MODULES[family]
    scene_module = {"rotation": "rotation", "orbit": "orbit", "hamiltonian": "hamilton"}[family]
    names = __import__(f"cayley_heyoka.{scene_module}.scene", fromlist=["x"]).FORMULATIONS
    assert names == module.FORMULATIONS == tuple(module.BY_NAME)
    for name in names:
        form = module.formulation(name)
        assert form.name == name and module.BY_NAME[name] is form
        assert pickle.loads(pickle.dumps(form)) is form
    offered = FAMILIES[family].formulations
    if offered is not None:
        assert offered[0] == KEYS[family] and set(offered[1]) <= set(names)


@pytest.mark.parametrize("family", list(MODULES))
@pytest.mark.parametrize("value", ["bogus", ["quaternion"], {"a": 1}, 3])
def test_an_unknown_name_is_refused_with_the_scene_error(family, value):
    module = MODULES[family]
    with pytest.raises(SceneError) as caught:
        module.formulation(value)
    assert str(caught.value) == (
        f"{KEYS[family]}: must be one of {module.FORMULATIONS}, got {value!r}"
    )


# ---------------------------------------------------------------------- rotation
FREE = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.3", "1", "0.5"], "quaternion": ["0.9", "0.3", "-0.3", "0.1"]},
    "output": {"times": [0, 1]},
}
TOP = {
    **FREE,
    "forces": {
        "heavy_top": {"weight": "0.2", "center_of_mass": ["0", "0.1", "0.3"], "up": [0, 0, 1]}
    },
}


def _rotation(base: dict, name: str, **output) -> dict:
    data = copy.deepcopy(base)
    data["attitude"] = {"formulation": name}
    data["output"] = {**data["output"], **output}
    return data


@pytest.mark.parametrize("name", rot.FORMULATIONS)
def test_rotation_declarations_are_what_the_scene_and_the_model_do(name):
    form = rot.formulation(name)
    for base, why in ((FREE, form.unforced), (TOP, form.forced)):
        refused = _refusal(_rotation(base, name))
        assert refused == (None if why is None else f"attitude.formulation: {why}")
    base = FREE if form.unforced is None else TOP
    model = model_for(_scene(_rotation(base, name)))
    assert tuple(model.state_names) == ("p", "q", "r", *form.state)
    assert ("rebasings" in [t.counter for t in model.terminal]) == form.chart
    assert (form.attitude is None) == (not form.state) == (form.numbers is None)
    azimuth = _refusal(_rotation(base, name, azimuth=True))
    assert (azimuth is None) == form.reduced
    plane = _rotation(base, name, events=["invariable_plane"])
    if form.unforced is None:
        held = set(model_for(_scene(plane)).pars.names) - set(model.pars.names)
        assert bool(held) == (form.plane_numbers is not None)
    # The twin is a formulation the scene's motion can be written in.
    if form.twin is None:
        assert not form.state
    else:
        assert form.twin in rot.FORMULATIONS and form.twin != name
        data = ch.Scene.from_dict(_rotation(base, name))
        twin = FAMILIES["rotation"].with_formulation(data, form.twin, True)
        assert _refusal(twin) is None
    assert form.element_check == (bool(form.state) and not form.reduced)


def test_a_rotation_twin_keeps_the_chart_angle_only_for_a_chart():
    data = _rotation(TOP, "quaternion")
    data["attitude"]["max_chart_angle"] = 90
    scene = _scene(data)
    for name in rot.FORMULATIONS:
        form = rot.formulation(name)
        if not form.state or name == "quaternion":
            continue
        twin = FAMILIES["rotation"].in_formulation(scene, name)
        assert ("max_chart_angle" in twin["attitude"]) == form.chart
        assert (twin.get("output", {}).get("azimuth") is True) == form.reduced


# ---------------------------------------------------------------------- orbit
ORBIT = {
    "orbit": {"mu": "1", "position": ["1", "0", "0.1"], "velocity": ["0", "1.1", "0.2"]},
    "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.5", "axis": [0, 0, 1]}},
    "output": {"times": [0, 1]},
}


def _orbit(name: str, **orbit) -> dict:
    data = copy.deepcopy(ORBIT)
    data["orbit"] |= {"formulation": name, **orbit}
    return data


@pytest.mark.parametrize("name", orb.FORMULATIONS)
def test_orbit_declarations_are_what_the_scene_and_the_model_do(name):
    form = orb.formulation(name)
    model = model_for(_scene(_orbit(name, equatorial_limit=0)))
    assert tuple(model.state_names) == form.state
    assert form.cartesian == (form.state == ("x", "y", "z", "vx", "vy", "vz"))
    counters = [t.counter for t in model.terminal]
    assert ("revolutions" in counters) == form.revolutions
    assert ("rectifications" in counters) == form.deviation
    sigma0 = _refusal(_orbit(name, sigma0="0.1"))
    assert sigma0 == (
        None if form.gauge else f"orbit.sigma0: has no meaning for formulation = {name!r}"
    )
    hyperbolic = _refusal(_orbit(name, velocity=["0", "1.6", "0"]))
    assert (hyperbolic is None) == form.hyperbolic
    # Cayley's angles: a hand-over near the plane, and no start on it without a limit.
    near = model_for(_scene(_orbit(name)))
    assert bool(near.variant) == form.angles
    flat = _orbit(name, position=["1", "0", "0"], velocity=["0", "1", "0"], equatorial_limit=0)
    assert (_refusal(flat) is None) == (not form.angles)
    assert form.twin in TWINS and form.twin != name


# ---------------------------------------------------------------------- Hamiltonian
SPLIT = {
    "hamiltonian": {
        "H1": "varpi1**2/2",
        "H2": "eta1**4/10",
        "flow": {"eta1": "chi1 + lambda1*t", "varpi1": "lambda1"},
    },
    "initial": {"eta": ["0.5"], "varpi": ["0.2"]},
    "output": {"times": [0, 1]},
}
PROJECTILE = {
    "hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3", "nu": "0.45"},
    "initial": {"eta": ["0.2", "-0.4", "1.5"], "varpi": ["0.7", "0.3", "2.1"]},
    "output": {"times": [0, 1]},
}
ELEMENTS = {
    "a": "1",
    "e": "0.05",
    "inclination": "0.05",
    "node": "0.3",
    "argument_of_pericentre": "1.1",
    "mean_anomaly": "0.4",
}


def _hamiltonian(base: dict, name: str, **table) -> dict:
    data = copy.deepcopy(base)
    data["hamiltonian"] |= {"formulation": name, **table}
    return data


def _planets(name: str, **elements) -> dict:
    body = {"mass": "0.001", "elements": {**ELEMENTS, **elements}}
    table = {"model": "predominant_mass", "G": "1", "central_mass": "1", "bodies": [body]}
    return {"hamiltonian": {**table, "formulation": name}, "output": {"times": [0, 1]}}


@pytest.mark.parametrize("name", ham.FORMULATIONS)
def test_hamiltonian_declarations_are_what_the_scene_and_the_model_do(name):
    form = ham.formulation(name)
    model = model_for(_scene(_hamiltonian(SPLIT, name)))
    assert tuple(model.state_names) == (f"{form.coordinates}1", f"{form.momenta}1")
    assert model.initial_field(model.state_names[0]) == "initial.eta[0]"
    assert model.initial_field(model.state_names[1]) == "initial.varpi[0]"
    single = copy.deepcopy(SPLIT)
    single["hamiltonian"] = {"H": "varpi1**2/2 + eta1**4/10", "formulation": name}
    assert (_refusal(single) is None) == (not form.needs_flow)
    flowless = _hamiltonian(SPLIT, name)
    del flowless["hamiltonian"]["flow"]
    assert (_refusal(flowless) is None) == (not form.needs_flow)
    late = _hamiltonian(SPLIT, name)
    late["output"]["times"] = [1, 2]
    assert (_refusal(late) is None) == (not form.from_zero)
    assert (_refusal(_planets(name, e="0")) is None) == (not form.ellipses)
    assert (_refusal(_planets(name, inclination="0")) is None) == (not form.ellipses)
    planets = model_for(_scene(_planets(name)))
    assert planets.compact == form.compact
    assert ("delta_mu1" in planets.state_names) == form.elements
    projectile = _scene(_hamiltonian(PROJECTILE, name))
    assert (FAMILIES["hamiltonian"].closed_form(projectile) is not None) == form.closed_form
