"""Results in the scientific Python stack: ``to_xarray``, ``to_pandas`` and files that any
netCDF reader opens with named dimensions — for every family and every precision."""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core.errors import SceneError
from cayley_heyoka.workflows.study import Study

xr = pytest.importorskip("xarray")
pd = pytest.importorskip("pandas")
pytest.importorskip("h5netcdf")

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
SHORT = {"times": {"start": "0.0", "stop": "2.0", "count": 5}}
# One scene per family, short, with each family's events; the parameter a sweep varies.
FAMILIES = {
    "rotation": ("free_body.toml", {"events": ["invariable_plane"]}, "initial.rates[0]"),
    "orbit": ("orbit_j2_third_body.toml", {"events": ["node", "apsis"]}, "orbit.velocity[1]"),
    "hamiltonian": ("projectile.toml", {"principal_function": True}, "hamiltonian.g"),
}
PRECISIONS = {"double": "double", "quad": "quad", "real": {"bits": 128}}


def _scene(family: str, precision: str, **output) -> dict:
    name, extra, _ = FAMILIES[family]
    data = ch.load_scene(EXAMPLES / name).to_dict()
    data["output"] = {**SHORT, **extra, **output}
    data["integrator"] = {**data.get("integrator", {}), "precision": PRECISIONS[precision]}
    return data


@pytest.fixture(scope="module", params=[(f, p) for f in FAMILIES for p in PRECISIONS])
def case(request, tmp_path_factory):
    family, precision = request.param
    result = ch.run(ch.Scene.from_dict(_scene(family, precision)))
    path = tmp_path_factory.mktemp("labelled") / f"{family}_{precision}.h5"
    result.save(path)
    return family, precision, result, path


def _text(values, prec) -> list[str]:
    return [str(x) for x in prec.to_text(np.asarray(values, dtype=object).ravel())]


def test_to_xarray_holds_every_output_exactly_with_its_description(case):
    family, precision, result, _ = case
    ds = result.to_xarray()
    prec = result.precision
    assert ds.sizes["time"] == len(result.t) and ds.attrs["precision"] == prec.name
    assert "rounded_from" not in ds.attrs and ds.attrs["success"] == 1
    assert list(ds.data_vars) == [*result.variables, *result.monitors]
    for name in (*result.variables, *result.monitors):
        assert ds[name].dims[0] == "time"
        assert ds[name].attrs["long_name"], f"{family}: {name} has no description"
        assert _text(ds[name].values, prec) == _text(result[name], prec)
    assert _text(ds["time"].values, prec) == _text(result.t, prec)
    for name, arr in result.monitors.items():
        if arr.ndim > 1:
            assert ds[name].dims == ("time", "component")
            assert list(ds["component"].values) == ["x", "y", "z"]
    expected = np.float64 if precision == "double" else object
    assert ds[result.names[0]].dtype == expected


def test_the_double_view_is_asked_for_and_says_so(case):
    _, precision, result, _ = case
    ds = result.to_xarray(as_double=True)
    name = result.names[0]
    assert ds[name].dtype == np.float64
    assert np.array_equal(ds[name].values, np.asarray(result[name], dtype=float))
    if precision == "double":
        assert ds.attrs["precision"] == "double" and "rounded_from" not in ds.attrs
    else:
        assert ds.attrs["precision"] == "double"
        assert ds.attrs["rounded_from"] == result.precision.name


def test_the_file_opens_in_xarray_with_named_dimensions(case):
    _, precision, result, path = case
    with xr.open_dataset(path, engine="h5netcdf") as f:
        view = result.to_xarray()
        assert set(f.data_vars) == set(view.data_vars)
        assert dict(f.sizes) == dict(view.sizes)
        assert not any(d.startswith("phony_dim") for d in f.dims)
        assert f.attrs["Conventions"] == "CF-1.10" and f.attrs["format_version"] == 3
        assert json.loads(f.attrs["scene"]) == result.scene
        for name in view.data_vars:
            assert f[name].dims == view[name].dims
            assert f[name].attrs["long_name"] == view[name].attrs["long_name"]
            if precision == "double":
                assert np.array_equal(f[name].values, view[name].values)
            else:  # the exact decimal text of the run's numbers
                assert list(f[name].values.ravel()) == _text(result[name], result.precision)
        for event in result.events:
            with xr.open_dataset(path, engine="h5netcdf", group=f"events/{event}") as g:
                assert set(g.data_vars) == {"direction", "label"}
                assert g.sizes["time"] == len(result.events[event])


def test_the_file_opens_in_the_netcdf_c_library(case):
    netCDF4 = pytest.importorskip("netCDF4")
    _, _, result, path = case
    with netCDF4.Dataset(path) as f:
        assert f.dimensions["time"].size == len(result.t)
        assert set(result.variables) <= set(f.variables)


def test_the_outputs_table_and_the_events_table(case):
    _, _, result, _ = case
    frame = result.to_pandas(as_double=True)
    assert frame.index.name == "time" and len(frame) == len(result.t)
    for name, arr in result.monitors.items():
        if arr.ndim > 1:
            assert {f"{name}_x", f"{name}_y", f"{name}_z"} <= set(frame.columns)
    assert np.array_equal(
        frame[result.names[0]].to_numpy(), np.asarray(result[result.names[0]], dtype=float)
    )
    events = result.to_pandas("events")
    assert list(events.columns) == ["event", "time", "direction", "label"]
    assert len(events) == sum(len(log) for log in result.events.values())
    assert np.all(np.diff(np.asarray(events["time"], dtype=float)) >= 0)
    assert set(events["direction"]) <= {-1, 1}
    with pytest.raises(ValueError, match="table must be one of 'outputs', 'events'"):
        result.to_pandas("members")


@pytest.fixture(scope="module", params=[(f, p) for f in FAMILIES for p in PRECISIONS])
def sweep_case(request, tmp_path_factory):
    family, precision = request.param
    data = _scene(family, precision)
    parameter = FAMILIES[family][2]
    base = _lookup(data, parameter)
    study = Study.from_dict(
        {
            "title": f"{family} in {precision}",
            "scene": data,
            "sweep": {"kind": "grid", "parameters": {parameter: [base, f"{base}1"]}},
        }
    )
    path = tmp_path_factory.mktemp("sweeps") / f"{family}_{precision}.h5"
    return ch.run_sweep(study, out=path, workers=1), path, parameter


def _lookup(data: dict, dotted: str) -> str:
    head, _, index = dotted.partition("[")
    node = data
    for key in head.split("."):
        node = node[key]
    return str(node[int(index.rstrip("]"))] if index else node)


def test_sweep_to_xarray_matches_its_file(sweep_case):
    sweep, path, parameter = sweep_case
    assert sweep.completed.all()
    ds = sweep.to_xarray()
    assert ds.sizes["member"] == 2 and ds.sizes["time"] == len(sweep.t)
    assert ds[parameter].dims == ("member",) and parameter in ds.coords
    assert list(ds["monitor"].values) == list(sweep.drift)
    for i, name in enumerate(sweep.drift):
        assert np.array_equal(ds["drift"].values[i], sweep.drift[name], equal_nan=True)
    assert ds.attrs["precision"] == sweep.precision.name and ds.attrs["completed"] == 2
    with xr.open_dataset(path, engine="h5netcdf") as f:
        assert set(f.data_vars) == set(ds.data_vars)
        assert set(f.coords) == set(ds.coords)
        assert dict(f.sizes) == dict(ds.sizes)
        assert np.array_equal(f["drift"].values, ds["drift"].values, equal_nan=True)
        assert list(f["steps"].values) == list(sweep.steps)
    doubles = sweep.to_xarray(as_double=True)
    assert doubles["final_state"].dtype == np.float64
    if sweep.precision.kind != "double":
        assert doubles.attrs["rounded_from"] == sweep.precision.name
        assert ds["final_state"].dtype == object


def test_sweep_members_table(sweep_case):
    sweep, _, parameter = sweep_case
    table = sweep.to_pandas()
    assert table.index.name == "member" and len(table) == len(sweep)
    assert parameter in table.columns and list(table["steps"]) == list(sweep.steps)
    for name in sweep.drift:
        final = table[f"final_drift_{name}"].to_numpy()
        assert np.array_equal(final, sweep.final_drift(name), equal_nan=True)
    for name, counts in sweep.events.items():
        assert list(table[f"events_{name}"]) == list(counts)


def test_scene_units_reach_the_views_and_the_file(tmp_path):
    data = _scene("rotation", "double")
    data["output"]["units"] = {"time": "s", "p": "rad/s", "energy": "J"}
    result = ch.run(ch.Scene.from_dict(data))
    result.save(tmp_path / "u.h5")
    ds = result.to_xarray()
    assert ds["time"].attrs["units"] == "s" and ds["p"].attrs["units"] == "rad/s"
    assert ds["energy"].attrs["units"] == "J" and "units" not in ds["q"].attrs
    with xr.open_dataset(tmp_path / "u.h5", engine="h5netcdf") as f:
        assert f["time"].attrs["units"] == "s" and f["p"].attrs["units"] == "rad/s"
        assert f["time"].dtype == np.float64  # "s" is no calendar: times stay numbers


@pytest.mark.parametrize(
    ("units", "field", "message"),
    [
        ({"speed": "m/s"}, "output.units.speed", "not an output or monitor"),
        ({"time": ""}, "output.units.time", "non-empty text"),
        ({"time": 3}, "output.units.time", "non-empty text"),
        ({"time": "s\x1b[2J"}, "output.units.time", "printable"),
        ({"time": "s" * 65}, "output.units.time", "at most 64"),
        ("s", "output.units", "must be a table"),
    ],
)
def test_bad_units_are_refused(units, field, message):
    data = _scene("rotation", "double")
    data["output"]["units"] = units
    with pytest.raises(SceneError, match=message) as err:
        ch.run(ch.Scene.from_dict(data))
    assert err.value.field == field


def test_a_file_of_format_version_2_reads_into_the_same_view():
    """Older files load as they were written; their views have the same labels."""
    data = Path(__file__).resolve().parent / "data" / "files"
    old = ch.load_result(data / "result_v2_double.h5").to_xarray()
    assert old.sizes["time"] == 6 and old["p"].attrs["long_name"]
    with h5py.File(data / "result_v2_double.h5") as f:
        assert f.attrs["format_version"] == 2


def test_a_missing_xarray_is_named(monkeypatch, case):
    import sys

    _, _, result, _ = case
    monkeypatch.setitem(sys.modules, "xarray", None)
    with pytest.raises(ImportError, match=r"cayley_heyoka\[xarray\]"):
        result.to_xarray()
