"""A run's drift as users read it: the largest over the run (not the final one) and when, in
``largest_drift``, ``repr`` and the command line's summary; an unknown monitor named by name."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.cli.show import summary

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture(scope="module")
def top() -> ch.Result:
    return ch.run(ch.load_scene(EXAMPLES / "heavy_top.toml"))


def test_largest_drift_is_the_largest_over_the_run_and_when(top):
    d = np.abs(np.asarray(top.drift("energy"), dtype=float))
    value, at = top.largest_drift("energy")
    assert value == d.max() and at == top.t[int(np.argmax(d))]
    # The bundled top's energy drift peaks before the end: the case the final value hides.
    assert value > d[-1]


def test_the_summary_prints_the_largest_drift_with_its_time_and_the_final(top):
    text = summary(top)
    value, at = top.largest_drift("energy")
    line = next(x for x in text.splitlines() if x.strip().startswith("energy"))
    assert f"{value:.3e} at t = {float(at):.6g}" in line
    assert f"final {abs(float(top.drift('energy')[-1])):.3e}" in line


def test_repr_gives_the_largest_conserved_drift(top):
    worst = max(top.largest_drift(n)[0] for n in top.conserved)
    assert f"{worst:.1e}" in repr(top)


def test_a_drift_of_exactly_zero_is_said_in_words(top):
    still = ch.Result(
        t=top.t,
        variables={},
        monitors={"energy": np.full(len(top.t), 2.5)},
        conserved=["energy"],
        events={},
        precision=top.precision,
        status=0,
        message="",
        counters={},
        scene=top.scene,
        metadata={},
    )
    assert still.largest_drift("energy") == (0.0, top.t[0])
    assert "0 (the same value, to the last bit, at every output time)" in summary(still)


@pytest.mark.parametrize("name", ["Energy", "p"])
def test_drift_of_an_unknown_name_lists_the_monitors(top, name):
    with pytest.raises(KeyError, match="the monitors are: .*energy") as err:
        top.drift(name)
    assert repr(name) in str(err.value)
