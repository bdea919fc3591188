"""Each family documents its results' variables (``Family.variables``, ``cayley-heyoka info
--variables``): every output and monitor of every bundled scene, in every formulation the
scene allows, has a description."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

import cayley_heyoka as ch
from cayley_heyoka.cli import main
from cayley_heyoka.core.families import FAMILIES

EXAMPLES = sorted((Path(__file__).resolve().parent.parent / "examples").glob("*.toml"))
FORMULATIONS = {
    "rotation": ("attitude", ("none", "rodrigues", "quaternion")),
    "orbit": ("orbit", ("cartesian", "cayley", "quaternion", "encke")),
    "hamiltonian": ("hamiltonian", ("canonical", "elements")),
}


def _variants(path: Path):
    data = ch.load_scene(path).to_dict()
    family = ch.Scene.from_dict(data).family
    yield data
    table, forms = FORMULATIONS[family]
    for form in forms:
        other = copy.deepcopy(data)
        other.setdefault(table, {})["formulation"] = form
        other[table].pop("max_chart_angle", None)
        if form in ("cartesian", "encke"):
            other[table].pop("sigma0", None)
        try:
            yield ch.Scene.from_dict(other).to_dict()
        except ch.SceneError:
            continue  # a formulation this scene cannot take (a force needs an attitude)


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.stem)
def test_every_output_and_monitor_is_described(path):
    undescribed = set()
    for data in _variants(path):
        scene = ch.Scene.from_dict(data)
        family = FAMILIES[scene.family]
        model = family.build(scene)
        for name in (*model.outputs, *model.monitors):
            if not family.variables(data, name):
                undescribed.add((scene.family, name))
    assert undescribed == set()


def test_a_name_that_is_not_the_familys_is_not_described():
    assert FAMILIES["rotation"].variables({}, "x") is None
    assert FAMILIES["orbit"].variables({}, "p") is None
    assert FAMILIES["hamiltonian"].variables({"hamiltonian": {}}, "zeta1") is None


def test_the_same_name_means_what_its_scene_says():
    """ϖ₂ is a momentum in a projectile, a body's element next to a predominant mass."""
    describe = FAMILIES["hamiltonian"].variables
    assert "momentum" in describe({"hamiltonian": {"model": "projectile"}}, "varpi2")
    assert "body 2" in describe({"hamiltonian": {"model": "predominant_mass"}}, "varpi2")


def test_info_lists_them(tmp_path, capsys):
    out = tmp_path / "p.h5"
    assert main(["run", str(EXAMPLES[0].parent / "projectile.toml"), "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["info", "--variables", str(out)]) == 0
    text = capsys.readouterr().out
    assert "eta1" in text and "coordinate η1" in text and "the Hamiltonian H" in text


def test_info_lists_a_sweeps_and_says_a_check_file_has_none(capsys):
    data = Path(__file__).resolve().parent / "data" / "files"
    assert main(["info", "--variables", str(data / "sweep_v2.h5")]) == 0
    text = capsys.readouterr().out
    assert "momentum_squared" in text and "angular momentum" in text and "Euler's p" in text
    assert main(["info", "--variables", str(data / "check_v1.h5")]) == 0
    assert "a check file has rows of quantities, not variables" in capsys.readouterr().out
