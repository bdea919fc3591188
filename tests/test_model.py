"""What a model hands the engine: the keys that decide whether compiled code is shared."""

from __future__ import annotations

import heyoka as hy

from cayley_heyoka import Scene
from cayley_heyoka.core.model import Model, ParTable


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


def test_compact_mode_rule():
    """'auto' compiles compact in extended precision, for models that ask, and for large
    systems (validation/BENCHMARKS.md, 'setup'); the scene's explicit choice wins."""
    from cayley_heyoka.core.compiler import COMPACT_THRESHOLD, use_compact_mode
    from cayley_heyoka.core.families import FAMILIES

    def decide(precision, compact="auto"):
        d = {
            "body": {"inertia": [1, 2, 3]},
            "initial": {"rates": [0.1, 0.2, 1]},
            "integrator": {"precision": precision, "compact_mode": compact},
            "output": {"times": [0, 1]},
        }
        scene = Scene.from_dict(d)
        model = FAMILIES["rotation"].build(scene)
        assert model.size() < COMPACT_THRESHOLD
        return use_compact_mode(model, scene.integrator), model, scene

    assert decide("double")[0] is False
    assert decide("quad")[0] is True
    assert decide({"bits": 128})[0] is True
    assert decide("quad", False)[0] is False
    _, model, scene = decide("double")
    model.compact = True
    assert use_compact_mode(model, scene.integrator) is True
