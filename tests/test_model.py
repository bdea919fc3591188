"""What a model hands the engine: the keys that decide whether compiled code is shared."""

from __future__ import annotations

import heyoka as hy

from cayley_heyoka.model import Model, ParTable


def _model(k: float) -> Model:
    x = hy.make_vars("x")
    rhs = hy.sum([hy.sin(x * i) for i in range(1, 200)] + [k * x] + [hy.cos(x)] * 100)
    return Model("test", [(x, rhs)], [0.0], ParTable(), {"x": x})


def test_systems_differing_deep_inside_long_expressions_do_not_share_code():
    """heyoka prints long expressions with their middle elided: the cache key must not."""
    a, b = _model(1.0), _model(2.0)
    assert str(a.system[0][1]) == str(b.system[0][1])  # elided alike by heyoka's printer
    assert a.structure_key() != b.structure_key()
    assert a.output_key() == b.output_key()
    assert _model(1.0).structure_key() == a.structure_key()  # and stable across builds
