"""What to cite (``cayley_heyoka.cite``, CITATION.cff) and the files a distribution carries."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

import cayley_heyoka as ch
from cayley_heyoka.core.citation import MEMOIRS
from cayley_heyoka.core.families import FAMILIES

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


def _keys(text: str) -> list[str]:
    return re.findall(r"^@\w+\{([^,]+),", text, flags=re.MULTILINE)


def test_cite_lists_the_package_every_memoir_heyoka_and_mpmath():
    assert _keys(ch.cite()) == ["cayley_heyoka", *MEMOIRS, "heyoka", "mpmath"]
    assert "10.1093/mnras/stab1032" in ch.cite()
    assert f"version = {{{ch.__version__}}}" in ch.cite()


@pytest.mark.parametrize(
    ("scene", "memoirs"),
    [
        ("free_body.toml", ["cayley1843", "cayley1846", "euler1758"]),
        ("orbit_j2_third_body.toml", ["cayley1860"]),
        ("projectile.toml", ["hamilton1835"]),
    ],
)
def test_cite_a_scene_names_its_familys_memoirs(scene, memoirs):
    keys = _keys(ch.cite(ch.load_scene(EXAMPLES / scene)))
    assert keys == ["cayley_heyoka", *memoirs, "heyoka", "mpmath"]


def test_every_family_names_memoirs_that_exist():
    for name in FAMILIES:
        assert FAMILIES[name].memoirs and set(FAMILIES[name].memoirs) <= set(MEMOIRS)


def test_citation_cff_is_valid_yaml_and_agrees_with_the_package():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text(encoding="utf-8"))
    assert cff["cff-version"] == "1.2.0" and cff["license"] == "MIT"
    assert cff["version"] == ch.__version__
    years = sorted(r["year"] for r in cff["references"] if r["type"] == "article")
    assert years == [1765, 1835, 1843, 1846, 1860, 2021]


def test_the_license_and_type_marker_are_there():
    assert (ROOT / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    assert (ROOT / "cayley_heyoka" / "py.typed").exists()
