"""Plots: what is drawn is the data in the file, on the axes it claims; refused clearly."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import h5py
import matplotlib
import numpy as np
import pytest
from helpers import free_body
from matplotlib.figure import Figure

import cayley_heyoka as ch
from cayley_heyoka.cli import main
from cayley_heyoka.workflows.plots import (
    PlotError,
    _read_sweep,
    crossings,
    drift,
    drift_of,
    orbit,
    plot_file,
    polhode,
)

matplotlib.use("Agg")  # no screen: set before anything imports pyplot

PNG = b"\x89PNG\r\n\x1a\n"
HEAVY_TOP = {
    "body": {"inertia": ["1", "1.6", "2.3"]},
    "initial": {"rates": ["0.3", "1", "0.5"]},
    "forces": {
        "heavy_top": {
            "weight": "1",
            "center_of_mass": ["0.1", "-0.05", "0.3"],
            "up": ["0", "0", "1"],
        }
    },
    "output": {"times": {"start": "0", "stop": "20", "count": 201}, "events": ["invariable_plane"]},
}
J2_ORBIT = {
    "orbit": {"mu": "1", "position": ["0.9", "0.2", "0.1"], "velocity": ["-0.25", "0.85", "0.45"]},
    "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.8"}},
    "output": {"times": {"start": "0", "stop": "30", "count": 121}, "events": ["apsis"]},
}


@pytest.fixture(scope="module")
def free():
    times = {"start": "0", "stop": "30", "count": 301}
    return ch.run(
        ch.Scene.from_dict(free_body(output={"times": times, "events": ["invariable_plane"]}))
    )


@pytest.fixture(scope="module")
def top():
    return ch.run(ch.Scene.from_dict(HEAVY_TOP))


@pytest.fixture(scope="module")
def kepler_j2():
    return ch.run(ch.Scene.from_dict(J2_ORBIT))


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    import matplotlib.pyplot as plt

    plt.close("all")


def _line(ax, label):
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == label]
    return line


# ------------------------------------------------------------------ drift
def test_drift_of_a_result_is_each_conserved_monitor_on_log_axes(free):
    ax = drift(free)
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    assert ax.get_title().startswith(free.scene.get("title", "(untitled"))
    t = np.asarray(free.t, dtype=float)
    series = drift_of(free)
    assert list(series) == list(free.conserved) == ["energy", "momentum_squared", "momentum_space"]
    worst_component = np.abs(free.drift("momentum_space")).max(axis=1)
    np.testing.assert_array_equal(series["momentum_space"], worst_component)
    for name, d in series.items():
        x, y = _line(ax, name).get_data()
        keep = (t > 0) & (d > 0)
        assert 0 < keep.sum() < len(t)  # t = 0 (drift 0 by definition) is left out
        np.testing.assert_array_equal(x, t[keep])
        np.testing.assert_array_equal(y, d[keep])


def test_reference_slopes_are_half_and_one_in_log_log(free):
    ax = drift(free)
    slopes = {}
    for line in ax.get_lines():
        label = line.get_label()
        if "propto" in label:
            x, y = line.get_data()
            slopes[label] = np.log(y[-1] / y[0]) / np.log(x[-1] / x[0])
    assert sorted(slopes.values()) == pytest.approx([0.5, 1.0], rel=1e-12)
    assert any("random walk" in k for k in slopes) and any("systematic" in k for k in slopes)


def test_sweep_series_draw_median_band_and_worst_member():
    rng = np.random.default_rng(7)
    t = np.linspace(0.0, 100.0, 201)
    steps = rng.choice([-1.0, 0.0, 1.0], size=(40, 200)) * 2.0**-52  # exact multiples of ε
    d = np.concatenate([np.zeros((40, 1)), np.cumsum(steps, axis=1)], axis=1)
    magnitude = np.abs(d)
    leader = int(np.argmax(magnitude[:, -1]))
    magnitude[leader, 150:] = np.nan  # stopped early: the worst is among those that got there
    ax = drift(t, {"energy": magnitude}, title="sweep")
    worst = int(np.nanargmax(magnitude[:, -1]))
    assert worst != leader
    x, y = _line(ax, f"energy: worst member (#{worst})").get_data()
    keep = (t > 0) & (magnitude[worst] > 0)
    np.testing.assert_array_equal(y, magnitude[worst][keep])
    x, y = _line(ax, "energy: median of 40").get_data()
    median = np.nanmedian(magnitude, axis=0)
    np.testing.assert_array_equal(y, median[(t > 0) & (median > 0)])
    (band,) = ax.collections
    edges = np.concatenate([p.vertices[:, 1] for p in band.get_paths()])
    members = set(magnitude[~np.isnan(magnitude)])
    assert edges.min() > 0 and set(edges) <= members  # band edges are members' own values


def test_drift_refuses_mismatched_shapes_and_results_without_conserved_monitors(kepler_j2):
    with pytest.raises(PlotError, match=r"series\['energy'\]: shape \(3,\); expected \(5,\)"):
        drift(np.arange(5.0), {"energy": np.ones(3)})
    with pytest.raises(PlotError, match=r"series\['energy'\]: no member has a drift value"):
        drift(np.arange(5.0), {"energy": np.full((2, 5), np.nan)})
    unconserved = dataclasses.replace(kepler_j2, conserved=())
    with pytest.raises(PlotError, match="needs conserved monitors.*supports: orbit$"):
        drift(unconserved)


def test_sweep_file_from_the_command_line(tmp_path, capsys):
    path = tmp_path / "sweep.h5"
    t = np.linspace(0.0, 10.0, 11)
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "cayley_heyoka.sweep"
        f.attrs["format_version"] = 1  # before checksums: read unchecked
        f.attrs["study"] = '{"title": "Energy drift of four members"}'
        f["t"] = t
        f.create_group("drift")["energy"] = np.outer(np.arange(1.0, 5.0), t) * 1e-16
    assert main(["plot", str(path), "--kind", "drift"]) == 0
    out = tmp_path / "sweep_drift.png"
    assert capsys.readouterr().out.strip() == f"plot written to {out}"
    assert out.read_bytes().startswith(PNG)
    t_read, series, title = _read_sweep(path)
    assert title == "Energy drift of four members" and list(series) == ["energy"]
    np.testing.assert_array_equal(t_read, t)
    assert main(["plot", str(path), "--kind", "orbit"]) == 2
    assert "sweep file, which supports only: drift" in capsys.readouterr().err


# ------------------------------------------------------------------ polhode
def test_free_polhode_lies_on_the_energy_and_momentum_ellipsoids(free):
    ax = polhode(free)
    assert ax.name == "3d" and len(ax.figure.axes) == 4  # the curve and three projections
    p, q, r = _line(ax, "ω(t) = (p, q, r)").get_data_3d()
    inertia = np.array([1.0, 1.5, 2.5])
    w = np.array([p, q, r])
    energy = inertia @ w**2
    momentum = inertia**2 @ w**2
    assert len(p) == len(free.t)
    assert np.max(np.abs(energy / energy[0] - 1)) < 1e-13
    assert np.max(np.abs(momentum / momentum[0] - 1)) < 1e-13
    assert "energy ellipsoid" in ax.get_title() and ax.collections  # the faint ellipsoid


def test_forced_polhode_is_the_curve_only(top):
    ax = polhode(top)
    assert "curve only" in ax.get_title() and not ax.collections
    p, q, r = _line(ax, "ω(t) = (p, q, r)").get_data_3d()
    np.testing.assert_array_equal(r, top["r"])


def test_polhode_refuses_an_orbit_and_flat_axes(kepler_j2, free):
    with pytest.raises(
        PlotError, match=r"'polhode' is drawn for rotation results.*supports: drift, orbit$"
    ):
        polhode(kepler_j2)
    with pytest.raises(PlotError, match="3-D axes"):
        polhode(free, ax=Figure().add_subplot())


# ------------------------------------------------------------------ orbit
def test_orbit_path_at_equal_scale_with_r_and_the_apsides(kepler_j2):
    ax = orbit(kepler_j2)
    assert ax.name == "3d" and ax.get_aspect() == "equal"
    x, y, z = _line(ax, "path").get_data_3d()
    np.testing.assert_array_equal(z, kepler_j2["z"])
    start = _line(ax, "start, t = 0").get_data_3d()
    assert [float(c[0]) for c in start] == [float(kepler_j2[k][0]) for k in "xyz"]
    assert [float(c[0]) for c in start] == pytest.approx([0.9, 0.2, 0.1], abs=1e-15)
    r_panel, *others = ax.figure.axes[1:]
    assert [a.get_ylabel() for a in others] == [
        "h = |x × v|",
        "Θ, node (rad)",
        "Φ, inclination (rad)",
    ]
    curve, *markers = r_panel.get_lines()
    np.testing.assert_array_equal(curve.get_ydata(), kepler_j2["r"])
    apsis = kepler_j2.events["apsis"]
    assert sum(len(m.get_xdata()) for m in markers) == len(apsis) > 0


# ------------------------------------------------------------------ crossings
def test_crossing_markers_are_the_recorded_events_on_the_curves_zeros(free):
    ax = crossings(free)
    log = free.events["invariable_plane"]
    markers = [c for c in ax.collections if "crossing" in c.get_label()]
    assert sum(len(c.get_offsets()) for c in markers) == len(log) > 0
    t = np.asarray(free.t, dtype=float)
    for c in markers:
        axis, _, word, _ = c.get_label().split()
        offsets = np.asarray(c.get_offsets())
        direction = 1 if word == "up" else -1
        expected = log.time[(log.label == axis) & (log.direction == direction)]
        np.testing.assert_array_equal(offsets[:, 0], expected)
        assert not offsets[:, 1].any()
        curve = [ln for ln in ax.get_lines() if ln.get_label().startswith(f"{axis}:")][0]
        # The elevation passes zero where the event fired (to the output grid's resolution),
        # rising over that step for an upward crossing.
        elevation = curve.get_ydata()
        assert np.max(np.abs(np.interp(expected, t, elevation))) < 5e-3
        after = np.searchsorted(t, expected)
        assert np.all(np.sign(elevation[after] - elevation[after - 1]) == direction)
    assert "perpendicular to L" in ax.get_title() and "not conserved" not in ax.get_title()


def test_crossings_under_torque_use_the_instantaneous_momentum(top):
    ax = crossings(top)
    title = " ".join(ax.get_title().split())  # the title is wrapped
    assert "at each instant (L is not conserved under a torque)" in title
    inertia = np.array([1.0, 1.6, 2.3])
    momentum = inertia[:, None] * np.array([top["p"], top["q"], top["r"]])
    elevation = _line(ax, "z1: Cr/|L|").get_ydata()
    np.testing.assert_allclose(elevation, momentum[2] / np.linalg.norm(momentum, axis=0))


def test_crossings_need_the_event_recorded(free):
    unrecorded = dataclasses.replace(free, events={})
    with pytest.raises(PlotError, match=r'output.events = \["invariable_plane"\].*drift, polhode$'):
        crossings(unrecorded)


# ------------------------------------------------------------------ files, command, imports
def test_plot_file_writes_each_kind_a_result_supports(free, tmp_path, capsys):
    path = tmp_path / "free.h5"
    free.save(path)
    for kind in ("drift", "polhode", "crossings"):
        assert plot_file(path, kind).read_bytes().startswith(PNG)
    out = tmp_path / "mine.png"
    assert main(["plot", str(path), "--kind", "polhode", "--out", str(out)]) == 0
    assert capsys.readouterr().out.strip() == f"plot written to {out}" and out.is_file()
    assert main(["plot", str(path), "--kind", "orbit"]) == 2
    err = capsys.readouterr().err
    assert "is drawn for orbit results" in err and "supports: drift, polhode, crossings" in err


def test_command_refuses_missing_and_foreign_files(tmp_path, capsys):
    assert main(["plot", str(tmp_path / "absent.h5"), "--kind", "drift"]) == 2
    assert "no such file" in capsys.readouterr().err
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as f:
        f.attrs["format"] = "someone.else"
    assert main(["plot", str(foreign), "--kind", "drift"]) == 2
    assert "an HDF5 file of format 'someone.else'" in capsys.readouterr().err


def test_missing_matplotlib_names_the_extra(free, tmp_path, monkeypatch, capsys):
    path = tmp_path / "free.h5"
    free.save(path)
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)  # import now fails
    assert main(["plot", str(path), "--kind", "drift"]) == 2
    assert 'pip install "cayley_heyoka[plots]"' in capsys.readouterr().err


def test_the_command_line_does_not_import_matplotlib():
    code = (
        "import sys, cayley_heyoka.cli, cayley_heyoka.workflows.plots; "
        "print('matplotlib' in sys.modules)"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "False"


def test_quad_results_are_drawn(tmp_path):
    scene = free_body(
        integrator={"precision": "quad"},
        output={
            "times": {"start": "0", "stop": "10", "count": 101},
            "events": ["invariable_plane"],
        },
    )
    result = ch.run(ch.Scene.from_dict(scene))
    ax = drift(result)
    y = _line(ax, "energy").get_ydata()
    assert 0 < y.max() < 1e-30  # quad round-off, not double's
    ax = crossings(result)
    assert sum(len(c.get_offsets()) for c in ax.collections) == len(
        result.events["invariable_plane"]
    )
