"""The registry of result names (cayley_heyoka/core/names.py): the rule that flattens vectors
into columns, shared by the views, and the rule a name must follow."""

from __future__ import annotations

import pytest

from cayley_heyoka.core import names
from cayley_heyoka.core.families import FAMILIES


def test_columns_of_numbers_vectors_and_matrices():
    assert names.columns("E") == ["E"]
    assert names.columns("L", (3,)) == ["L_x", "L_y", "L_z"]
    assert names.columns("q", (4,)) == ["q_0", "q_1", "q_2", "q_3"]
    assert names.columns("M", (3, 2)) == ["M_x_0", "M_x_1", "M_y_0", "M_y_1", "M_z_0", "M_z_1"]
    assert [names.component_dim(n) for n in (3, 4)] == ["component", "component_4"]


@pytest.mark.parametrize(
    ("name", "problem"),
    [("K", None), ("Ψ", None), ("a/b", "identifier"), ("_K", "start with _"), ("ﬁ", "NFKC")],
)
def test_name_rule(name, problem):
    found = names.name_problem(name)
    assert found is None if problem is None else problem in found


def test_no_family_takes_a_generic_table_or_a_layout_name():
    """Our families' records keep the rules the registry holds other packages to."""
    for family in (FAMILIES[n] for n in FAMILIES):
        assert not set(family.tables) & set(names.SCENE_TABLES)
        assert family.key_table in family.tables
        for event in family.events:
            assert names.name_problem(event) is None
