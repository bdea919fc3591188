"""Hostile names: a user monitor or event, a family's output, a plugin's table or a number
that takes a name (or a range) that something else holds. Each is refused by name before any
work (:mod:`cayley_heyoka.core.names`, the registry of :mod:`cayley_heyoka.core.families`), or
runs with every name kept; never a run that ends and then cannot be saved, a column silently
replaced, a traceback from another package's family, or a number turned into inf.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import heyoka as hy
import numpy as np
import plugin_family
import pytest
from conftest import Raw, toml
from test_scenes import small

import cayley_heyoka as ch
from cayley_heyoka.core.errors import SceneError
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.core.result import EventLog, Result
from cayley_heyoka.workflows.sweep_result import SweepResult


def _with(data: dict, *, monitors: dict | None = None, events: dict | None = None) -> dict:
    """``data`` with user monitors (by default ``p*p``, not conserved) and user events (each
    listed in ``output.events``)."""
    if monitors:
        data["monitors"] = {
            name: {"expression": "p*p", "conserved": False, **spec}
            for name, spec in monitors.items()
        }
    if events:
        data["events"] = events
        listed = [*data["output"].get("events", []), *events]
        data["output"]["events"] = list(dict.fromkeys(listed))
    return data


def _scene(hostile, data: dict) -> Path:
    """The scene file of ``data``, its monitor and event names quoted (TOML's bare keys are
    ASCII: ``Ｋ`` must be written ``"Ｋ"``)."""
    named = {k: data.pop(k) for k in ("monitors", "events") if k in data}
    text = toml(data)
    for table, entries in named.items():
        inner = ", ".join(f"{json.dumps(n)} = {_inline(spec)}" for n, spec in entries.items())
        text += f"{table} = {{ {inner} }}\n"
    return hostile.scene(text)


def _inline(spec: dict) -> str:
    return "{ " + ", ".join(f"{k} = {json.dumps(v)}" for k, v in spec.items()) + " }"


def _free_body(**names: dict) -> dict:
    """The bundled free body (its Rodrigues attitude gives the vector monitor
    ``momentum_space``), over three output times."""
    return _with(small("free_body"), **names)


# ---------------------------------------------------------------------- user monitors
#: Monitor names that the layouts hold, each with the words of its refusal.
LAYOUT = [
    ("time", "time axis"),
    ("events", "group of events"),
    ("component", "components of 3-vectors"),
    ("component_4", "components of 4-vectors"),
    ("certificate", "certificate group"),
]
#: Names that no layout can hold, each with the words of its refusal (``a/b``, ``a.b`` and
#: the like were refused as non-identifiers already: tests/test_user_monitors.py).
MALFORMED = [
    ("Ｋ", "NFKC"),
    ("K" * 257, "at most 256 bytes"),
    ("é" * 129, "at most 256 bytes"),
]


@pytest.mark.covers("class:2", "key:monitors", "verb:run")
@pytest.mark.parametrize(("name", "words"), LAYOUT + MALFORMED)
def test_monitor_named_like_the_layout_is_refused_before_the_run(hostile, tmp_path, name, words):
    """``[monitors.time]`` ran to the end and then failed to save (a traceback, no file)."""
    out = tmp_path / "r.h5"
    scene = _scene(hostile, _free_body(monitors={name: {}}))
    o = hostile.run(
        ["run", str(scene), "--out", str(out)], expect="refused", field=f"monitors.{name}"
    )
    assert words in o.error_line
    assert not out.exists()
    assert "steps" not in o.stdout  # refused: no summary of a run


@pytest.mark.covers("class:2", "key:monitors", "verb:check", "verb:plan", "verb:reference")
@pytest.mark.parametrize("verb", ["check", "plan", "reference", "sweep"])
def test_monitor_named_time_is_refused_by_every_verb(hostile, tmp_path, verb):
    """Every verb validates the scene through one path: none integrates it first."""
    scene = _scene(hostile, _free_body(monitors={"time": {}}))
    argv = {
        "check": ["check", str(scene)],
        "plan": ["plan", str(scene), "--error", "1e-6"],
        "reference": ["reference", str(scene), "--digits", "5", "--out", str(tmp_path / "r.h5")],
        "sweep": [
            "sweep",
            str(
                hostile.scene(
                    {
                        "title": "s",
                        "scene": str(scene),
                        "sweep": {
                            "kind": "grid",
                            "parameters": {"initial.rates[0]": [Raw("0.1"), Raw("0.2")]},
                        },
                    }
                )
            ),
            "--out",
            str(tmp_path / "s.h5"),
        ],
    }[verb]
    hostile.run(argv, expect="refused", field="monitors.time", seconds=30)
    assert not (tmp_path / "r.h5").exists() and not (tmp_path / "s.h5").exists()


def _orbit(**names: dict) -> dict:
    """The bundled J2 orbit (its vector monitor ``angular_momentum``), over three times."""
    return _with(small("orbit_j2_third_body"), **names)


#: Columns of the family's vector monitors, which a user monitor silently replaced in
#: ``to_pandas()``.
TAKEN = [
    (_free_body, "momentum_space_x", "a column of the built-in monitor momentum_space"),
    (_free_body, "momentum_space_z", "a column of the built-in monitor momentum_space"),
    (_orbit, "angular_momentum_y", "a column of the built-in monitor angular_momentum"),
]


@pytest.mark.covers("class:2", "key:monitors")
@pytest.mark.parametrize(("make", "name", "words"), TAKEN)
def test_monitor_that_takes_a_column_of_a_vector_is_refused(hostile, make, name, words):
    """``[monitors.momentum_space_x] expression = "1000 + p"`` silently replaced L's x
    component in ``to_pandas()``."""
    data = make(monitors={name: {"expression": "1000 + p" if make is _free_body else "x"}})
    o = hostile.run(["run", str(_scene(hostile, data))], expect="refused", field=f"monitors.{name}")
    assert words in o.error_line


@pytest.mark.covers("class:2", "key:monitors", "api:run", "api:to_pandas")
def test_monitor_taking_a_vector_column_is_refused_through_the_api():
    scene = ch.Scene.from_dict(_free_body(monitors={"momentum_space_x": {}}))
    with pytest.raises(SceneError, match="a column of the built-in monitor") as info:
        ch.run(scene)
    assert info.value.field == "monitors.momentum_space_x"


@pytest.mark.covers("class:2", "key:monitors", "verb:sweep")
def test_sweep_of_a_scene_whose_monitor_takes_a_column_is_refused(hostile, tmp_path):
    scene = _scene(hostile, _free_body(monitors={"momentum_space_x": {}}))
    study = hostile.scene(
        {
            "title": "s",
            "scene": str(scene),
            "sweep": {
                "kind": "grid",
                "parameters": {"initial.rates[0]": [Raw("0.1"), Raw("0.2")]},
            },
        }
    )
    out = tmp_path / "s.h5"
    hostile.run(
        ["sweep", str(study), "--out", str(out)],
        expect="refused",
        field="monitors.momentum_space_x",
    )
    assert not out.exists()


# ---------------------------------------------------------------------- user events
EVENTS = [
    (_free_body, "invariable_plane", "rotation family's own events"),
    (_orbit, "apsis", "orbit family's own events"),
    (_free_body, "a/b", "identifier"),
    (_free_body, "x" * 300, "at most 256 bytes"),
]


@pytest.mark.covers("class:2", "key:events", "key:output.events")
@pytest.mark.parametrize(("make", "name", "words"), EVENTS)
def test_user_event_named_like_a_family_event_or_unwritable_is_refused(hostile, make, name, words):
    """``[events.invariable_plane]`` was silently replaced by the family's event of that name;
    ``[events."a/b"]`` became a nested group of the file."""
    data = make(events={name: {"expression": "p" if make is _free_body else "x"}})
    o = hostile.run(["run", str(_scene(hostile, data))], expect="refused", field=f"events.{name}")
    assert words in o.error_line


# ---------------------------------------------------------------------- results built in Python
def _quad(**arrays: list[str]) -> Result:
    prec = Precision("quad")
    return Result(
        t=prec.array(["0", "1"]),
        variables={k: prec.array(v) for k, v in arrays.items()},
        precision=prec,
    )


@pytest.mark.covers("class:2", "api:Result.save")
@pytest.mark.parametrize("name", ["a/b", "component_7", ""])
def test_result_built_in_python_with_an_unwritable_name_is_refused_before_writing(tmp_path, name):
    result = _quad(x=["1", "2"])
    result.monitors[name] = result.variables["x"]
    with pytest.raises(ValueError, match=f"{name!r} cannot be saved"):
        result.save(tmp_path / "r.h5")
    assert not (tmp_path / "r.h5").exists()


@pytest.mark.covers("class:2", "api:Result.save")
def test_result_built_in_python_with_an_unwritable_event_name_is_refused(tmp_path):
    result = _quad(x=["1", "2"])
    result.events["up/down"] = EventLog(np.array([]), np.array([]), np.array([]))
    with pytest.raises(ValueError, match="'up/down' cannot be saved"):
        result.save(tmp_path / "r.h5")


@pytest.mark.covers("class:2", "api:to_pandas")
def test_two_columns_of_one_name_are_refused_in_the_table():
    result = _quad(L_x=["1", "2"])
    result.monitors["L"] = np.stack([result.variables["L_x"]] * 3, axis=1)
    with pytest.raises(ValueError, match="two columns .* 'L_x'"):
        result.to_pandas()


# ---------------------------------------------------------------------- narrowing to double
@pytest.mark.covers("class:12", "api:to_xarray", "api:to_pandas")
@pytest.mark.parametrize("view", ["xarray", "pandas", "events"])
def test_quad_number_beyond_double_is_refused_as_double_not_made_inf(view):
    """A quad 5.8e702 became −inf with only numpy's warning."""
    result = _quad(x=["1", "-5.8e702"])
    prec = result.precision
    result.events["e"] = EventLog(prec.array(["5.8e702"]), np.array([1]), np.array(["e"]))
    name = {"xarray": "x", "pandas": "x", "events": "events.e.time"}[view]
    build = {
        "xarray": lambda: result.to_xarray(as_double=True),
        "pandas": lambda: result.to_pandas(as_double=True),
        "events": lambda: result.to_pandas("events", as_double=True),
    }[view]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=rf"{name} in quad: \[.*\] is .*e\+702, beyond"):
            build()
    exact = result.to_xarray()
    assert exact["x"].values[1] == prec.number("-5.8e702")


@pytest.mark.covers("class:12", "api:to_xarray")
def test_multiprecision_number_beyond_double_is_refused_and_tiny_ones_round():
    """Beyond the range: refused. Below double's smallest: the nearest double (0, or a
    subnormal), as any rounding; NaN and inf stay."""
    prec = Precision.from_spec({"bits": 128})
    big = Result(t=prec.array(["0"]), variables={"y": prec.array(["1e400"])}, precision=prec)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ValueError, match=r"y in mpfr128: \[0\] is 1\.0*e\+400"):
            big.to_xarray(as_double=True)
    y = prec.array(["1e-400", "-3e-320", "0", "0"])
    y[2], y[3] = hy.real("nan", 128), hy.real("-inf", 128)
    small_ = Result(t=prec.array(["0", "1", "2", "3"]), variables={"y": y}, precision=prec)
    y = small_.to_xarray(as_double=True)["y"].values
    assert y[0] == 0.0 and y[1] == -3e-320 and np.isnan(y[2]) and y[3] == -np.inf


@pytest.mark.covers("class:12", "api:SweepResult.to_xarray", "api:SweepResult.to_pandas")
def test_sweep_parameter_beyond_double_is_refused_as_double():
    prec = Precision("quad")
    sweep = SweepResult(
        t=prec.array(["0", "1"]),
        parameters={"initial.rates[0]": prec.array(["1", "-5.8e702"])},
        drift={},
        final_names=("p",),
        final_state=prec.array(["1", "2"]).reshape(2, 1),
        status=np.zeros(2, dtype=int),
        message=np.array(["ok", "ok"], dtype=object),
        steps=np.zeros(2, dtype=np.int64),
        precision=prec,
    )
    for view in (sweep.to_xarray, sweep.to_pandas):
        with pytest.raises(ValueError, match=r"initial\.rates\[0\] in quad: \[1\] is -5\.79"):
            view(as_double=True)


@pytest.mark.covers("class:12", "verb:plot")
def test_plot_of_a_quad_result_beyond_double_is_refused(hostile, tmp_path):
    """A plot draws doubles: a rate of 5.8e702 was drawn as inf (not at all)."""
    path = tmp_path / "r.h5"
    result = _quad(**{k: ["1", "5.8e702"] for k in "pqr"})
    result.scene = small("free_body")
    result.save(path)
    argv = ["plot", str(path), "--kind", "polhode", "--out", str(tmp_path / "p.png")]
    o = hostile.run(argv, expect="refused", field="p: [1] is 5.79")
    assert "beyond double's range" in o.error_line
    assert not (tmp_path / "p.png").exists()


# ---------------------------------------------------------------------- families of other packages
RIGID = small("free_body")
OSCILLATOR = {
    "oscillator": {"omega": "2", "x0": "1", "v0": "0"},
    "output": {"times": {"start": 0, "stop": 1, "count": 3}},
}


@pytest.mark.covers("plugin", "class:12")
@pytest.mark.parametrize(
    "points",
    [
        {"bodies": "plugin_family:CLAIMS_BODY"},
        {"initials": "plugin_family:CLAIMS_INITIAL"},
        {"orbit": "plugin_family:FAMILY"},
    ],
    ids=["key-table-body", "key-table-initial", "name-orbit"],
)
def test_a_plugin_cannot_take_a_table_or_name_of_ours(hostile, monkeypatch, points):
    """A plugin claiming ``[body]`` broke every rigid-body scene ("names several model
    families"); one named ``orbit`` broke every scene."""
    plugin_family.install(monkeypatch, **points)
    hostile.run(["run", str(hostile.scene(RIGID))], expect="done")
    hostile.run(["run", str(hostile.scene(small("projectile")))], expect="done")


@pytest.mark.covers("plugin")
def test_a_plugin_claiming_a_table_every_scene_has_is_named_when_its_scene_is_run(
    hostile, monkeypatch
):
    plugin_family.install(monkeypatch, outputs="plugin_family:CLAIMS_OUTPUT")
    o = hostile.run(["run", str(hostile.scene(OSCILLATOR))], expect="refused")
    assert "'outputs' (plugin_family:CLAIMS_OUTPUT) claims the table [output]" in o.error_line
    hostile.run(["run", str(hostile.scene(RIGID))], expect="done")


@pytest.mark.covers("plugin")
def test_two_plugins_claiming_one_table_are_both_named(hostile, monkeypatch):
    plugin_family.install(monkeypatch, twin_a="plugin_family:TWIN_A", twin_b="plugin_family:TWIN_B")
    o = hostile.run(["run", str(hostile.scene(OSCILLATOR))], expect="refused", field="scene")
    assert "'twin_a'" in o.error_line and "'twin_b'" in o.error_line
    assert "also has" in o.error_line
    hostile.run(["run", str(hostile.scene(RIGID))], expect="done")


@pytest.mark.covers("plugin")
def test_two_packages_registering_one_family_name_are_both_refused(hostile, monkeypatch):
    """The last entry point found silently won."""
    plugin_family.install(
        monkeypatch,
        ("oscillator", "plugin_family:FAMILY"),
        ("oscillator", "plugin_family:FAMILY_AGAIN"),
    )
    o = hostile.run(["run", str(hostile.scene(OSCILLATOR))], expect="refused", field="scene")
    assert "all register a family named 'oscillator'" in o.error_line


@pytest.mark.covers("plugin", "class:12")
@pytest.mark.parametrize(
    ("attr", "hook"),
    [
        ("FAULTY_PARSE", "parse"),
        ("FAULTY_BUILD", "build"),
        ("FAULTY_VALIDATE", "validate"),
    ],
)
def test_a_plugin_hook_that_raises_is_one_line_naming_the_family_and_hook(
    hostile, monkeypatch, tmp_path, attr, hook
):
    """A plugin whose ``parse`` raised showed a raw traceback."""
    plugin_family.install(monkeypatch, faulty=f"plugin_family:{attr}")
    data = {"oscillator": OSCILLATOR["oscillator"], "output": OSCILLATOR["output"]}
    out = tmp_path / "r.h5"
    o = hostile.run(
        ["run", str(_scene(hostile, data)), "--out", str(out)], expect="refused", field="families"
    )
    assert f"'faulty' (plugin_family:{attr}) failed in its {hook}: ZeroDivisionError" in (
        o.error_line
    )
    assert not out.exists()


@pytest.mark.covers("plugin", "verb:check")
def test_a_plugin_check_that_raises_is_refused_by_name(hostile, monkeypatch):
    plugin_family.install(monkeypatch, faulty="plugin_family:FAULTY_CHECK")
    o = hostile.run(["check", str(hostile.scene(OSCILLATOR))], expect="refused")
    assert "failed in its consistency_check: ZeroDivisionError" in o.error_line


@pytest.mark.covers("plugin", "verb:info")
def test_a_plugin_whose_descriptions_raise_still_saves_its_run(hostile, monkeypatch, tmp_path):
    """Saving labels each variable with its family's description: a description that raises
    must not lose the run."""
    plugin_family.install(monkeypatch, faulty="plugin_family:FAULTY_VARIABLES")
    out = tmp_path / "r.h5"
    data = {**OSCILLATOR, "monitors": {"x2": {"expression": "x*x", "conserved": False}}}
    hostile.run(["run", str(hostile.scene(data)), "--out", str(out)], expect="done", out=out)
    o = hostile.run(["info", str(out), "--variables"], expect="done")
    assert "not described: the family 'faulty'" in o.stdout


@pytest.mark.covers("plugin", "class:2")
def test_a_plugin_output_named_like_the_layout_is_refused_before_the_run(
    hostile, monkeypatch, tmp_path
):
    plugin_family.install(monkeypatch, timed="plugin_family:OUTPUT_TIME")
    out = tmp_path / "r.h5"
    o = hostile.run(
        ["run", str(hostile.scene(OSCILLATOR)), "--out", str(out)],
        expect="refused",
        field="oscillator",
    )
    assert "'time' is already the result file's time axis" in o.error_line
    assert not out.exists()
