"""Conservation sweeps: study files, members equal to run(), the file, failures, Dask = local."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import h5py
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.cli import main
from cayley_heyoka.workflows.members import PATH_LANES
from cayley_heyoka.workflows.sweep import (
    FAILED,
    NOT_RUN,
    OK,
    Study,
    SweepResult,
    load_study,
    run_sweep,
)

STUDIES = Path(__file__).resolve().parent.parent / "examples" / "studies"

# A quaternion body (no terminal events: heyoka's ensemble) recording its invariable-plane
# crossings, so that event counts are checked too.
BODY = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.3", "1", "0.5"], "quaternion": ["1", "0", "0", "0"]},
    "attitude": {"formulation": "quaternion"},
    "output": {
        "times": {"start": "0", "stop": "20", "count": "21"},
        "events": ["invariable_plane"],
    },
}
# The same body in Cayley's Rodrigues parameters: a terminal event (the chart's re-basing).
RODRIGUES = {
    **BODY,
    "initial": {"rates": ["0.3", "1", "0.5"], "rodrigues": ["0.1", "0.2", "-0.3"]},
    "attitude": {"formulation": "rodrigues"},
}


# Orbits whose handlers act between steps: ρ's revolutions (Cayley), rectifications (Encke).
ORBIT_CAYLEY = {
    "orbit": {
        "mu": "1",
        "position": ["0.9", "0.2", "0.1"],
        "velocity": ["-0.25", "0.85", "0.45"],
        "formulation": "cayley",
    },
    "perturbations": {"zonal": {"J2": "1.0826e-3", "radius": "0.8", "axis": ["0", "0", "1"]}},
    "output": {"times": {"start": "0", "stop": "30", "count": "31"}, "events": ["node"]},
}
ORBIT_ENCKE = {**ORBIT_CAYLEY, "orbit": {**ORBIT_CAYLEY["orbit"], "formulation": "encke"}}


def study(scene=BODY, parameters=None, **sweep) -> Study:
    sweep = {"kind": "grid", **sweep}
    sweep["parameters"] = parameters or {
        "initial.rates[0]": {"start": "0.1", "stop": "0.4", "count": 3},
        "body.inertia[1]": ["1.5", "2"],
    }
    return Study.from_dict({"scene": scene, "sweep": sweep})


def drift_row(result: ch.Result, name: str) -> np.ndarray:
    d = np.abs(result.drift(name))
    return (d.max(axis=1) if d.ndim > 1 else d).astype(np.float64)


# ---------------------------------------------------------------------- members
def test_grid_is_the_product_in_exact_decimal_text():
    s = study(
        parameters={
            "initial.rates[0]": {"start": "0.1", "stop": "0.2", "count": 3},
            "body.inertia[1]": ["1.5", 2],
            "integrator.tolerance": {
                "start": "1e-12",
                "stop": "1e-8",
                "count": 3,
                "spacing": "log",
            },
        }
    )
    members = s.members()
    assert s.size == len(members) == 18
    assert {m[0] for m in members} == {"0.1", "0.15", "0.2"}  # not 0.15000000000000002
    assert members[0][:2] == ("0.1", "1.5") and members[1][:2] == ("0.1", "1.5")
    assert members[-1][:2] == ("0.2", 2)
    tolerances = sorted({m[2] for m in members}, key=lambda v: Fraction(v))
    assert tolerances[0] == "1e-12" and tolerances[-1] == "1e-8"
    assert abs(Fraction(tolerances[1]) / Fraction("1e-10") - 1) < Fraction(1, 10**25)
    scene = s.member_scene(17, members[17])
    assert scene.source["initial"]["rates"] == ["0.2", "1", "0.5"]
    assert scene.source["body"]["inertia"] == ["1", 2, "2.5"]
    assert BODY["initial"]["rates"][0] == "0.3"  # the base scene is not changed


def test_random_members_are_reproducible_and_follow_their_distributions():
    params = {
        "initial.rates[0]": {"uniform": ["0.2", "0.4"]},
        "initial.rates[1]": {"normal": ["1", "0.01"]},
    }
    a = study(parameters=params, kind="random", count=500, seed=7).members()
    b = study(parameters=params, kind="random", count=500, seed=7).members()
    c = study(parameters=params, kind="random", count=500, seed=8).members()
    assert a == b and a != c and len(a) == 500
    p, q = np.array(a).T
    assert p.min() >= 0.2 and p.max() < 0.4
    assert abs(q.mean() - 1) < 5 * 0.01 / np.sqrt(500) and 0.008 < q.std() < 0.012


@pytest.mark.parametrize(
    "change, field, says",
    [
        (
            {"sweep": {"kind": "grid", "paramters": {}}},
            "sweep.paramters",
            "did you mean 'parameters'",
        ),
        ({"sweep": {"kind": "mesh"}}, "sweep.kind", "must be one of"),
        ({"params": {"output.times": [1, 2]}}, '"output.times"', "shared grid"),
        ({"params": {"initial.rates[3]": [1, 2]}}, '"initial.rates[3]"', "out of range"),
        ({"params": {"initial.rates": [1, 2]}}, '"initial.rates"', 'like "initial.rates[0]"'),
        ({"params": {"body.inertia[0].x": [1]}}, '"body.inertia[0].x"', "a number, not a table"),
        ({"params": {"initial rates": [1]}}, '"initial rates"', "dotted scene path"),
        ({"params": {"initial.rates[0]": []}}, '"initial.rates[0]"', "must not be empty"),
        ({"params": {"initial.rates[0]": ["x"]}}, '"initial.rates[0]"[0]', "finite number"),
        ({"params": {"initial.rates[0]": {"uniform": [0, 1]}}}, '"initial.rates[0]"', "random"),
        (
            {"params": {"initial.rates[0]": {"start": 0, "stop": 1}}},
            '"initial.rates[0]"',
            "missing ['count']",
        ),
        (
            {"params": {"initial.rates[0]": {"start": 0, "stop": 1, "count": 2, "spacing": "log"}}},
            '"initial.rates[0]"',
            "needs start and stop > 0",
        ),
        ({"kind": "random", "count": 5}, "sweep.seed", "is required"),
        ({"kind": "random", "count": 0, "seed": 1}, "sweep.count", "integer >= 1"),
        # None (a study given as Python dictionaries) is no count: it was a TypeError later.
        ({"kind": "random", "count": None, "seed": 1}, "sweep.count", "integer >= 1"),
        (
            {"params": {"initial.rates[0]": {"start": 0, "stop": 1, "count": None}}},
            '"initial.rates[0]".count',
            "integer >= 1",
        ),
        (
            {"kind": "random", "count": 5, "seed": 1, "params": {"initial.rates[0]": [1, 2]}},
            '"initial.rates[0]"',
            "needs a distribution",
        ),
        (
            {
                "kind": "random",
                "count": 5,
                "seed": 1,
                "params": {"initial.rates[0]": {"uniform": [1, 1]}},
            },
            '"initial.rates[0]".uniform',
            "lo < hi",
        ),
        (
            {
                "kind": "random",
                "count": 5,
                "seed": 1,
                "params": {"initial.rates[0]": {"normal": [1, 0]}},
            },
            '"initial.rates[0]".normal',
            "standard deviation > 0",
        ),
        ({"seed": 3}, "sweep.seed", "kind = 'random' only"),
        ({"run": {"backend": "local", "scheduler": "tcp://h:8786"}}, "run.scheduler", "dask"),
        ({"run": {"scheduler": "tcp://h:8786", "workers": 2}}, "run.workers", "cluster's own"),
        ({"run": {"backend": "slurm"}}, "run.backend", "must be one of"),
        ({"run": {"chunk": 0}}, "run.chunk", "integer >= 1"),
        ({"scene": {**BODY, "body": {"inertia": [1, 1, 3]}}}, "scene: body.inertia", "triangle"),
        ({"scene": "missing.toml"}, "scene", "no such file"),
    ],
)
def test_bad_study_fields_are_named(tmp_path, change, field, says):
    data = {
        "scene": BODY,
        "sweep": {"kind": change.pop("kind", "grid")},
        "run": change.pop("run", {}),
    }
    for key in ("count", "seed"):
        if key in change:
            data["sweep"][key] = change.pop(key)
    data["sweep"]["parameters"] = change.pop("params", {"initial.rates[0]": [0.1]})
    data.update(change)
    with pytest.raises(ch.SceneError) as err:
        Study.from_dict(data, tmp_path)
    assert err.value.field.endswith(field) and says in err.value.constraint, str(err.value)


def test_an_invalid_member_is_named_with_its_values_before_anything_runs():
    s = study(parameters={"initial.rates[0]": ["0.1", "0.2"], "body.inertia[1]": ["1.5", "1.25"]})
    with pytest.raises(ch.SceneError) as err:
        run_sweep(s)
    assert (
        err.value.field == "member 1 (initial.rates[0] = 0.1, body.inertia[1] = 1.25): body.inertia"
    )
    assert "violates the triangle inequality A + B >= C" in err.value.constraint


def test_bundled_studies_are_valid():
    files = sorted(STUDIES.glob("*.toml"))
    assert files
    for path in files:
        s = load_study(path)
        members = s.members()
        assert len(members) == s.size > 1
        for i, values in enumerate(members):
            s.member_scene(i, values)


# ---------------------------------------------------------------------- integration
@pytest.fixture(scope="module")
def body_sweep(tmp_path_factory):
    """A grid with one member whose state overflows (q = 1e160): recorded, not fatal."""
    s = study(
        parameters={"initial.rates[1]": ["1", "1e160", "0.8"], "body.inertia[1]": ["1.5", "2"]}
    )
    out = tmp_path_factory.mktemp("sweep") / "body.h5"
    return s, run_sweep(s, out=out, workers=2, chunk=4), out


def test_lane_members_take_the_steps_and_events_of_run(body_sweep):
    """Members without terminal events go through batch lanes: run()'s steps and events, its
    states to a few ulps (SIMD arithmetic rounds differently)."""
    s, result, _ = body_sweep
    assert result.metadata["paths"] == {PATH_LANES: 6}
    for i, values in enumerate(s.members()):
        scene = s.member_scene(i, values)
        if values[0] == "1e160":
            assert result.status[i] == FAILED and "non-finite" in result.message[i]
            assert "nan" not in result.message[i]  # the last output time kept is named
            assert np.isnan(result.final_state[i]).all()
            # Alone, the run is refused before integrating: its energy overflows at t0.
            with pytest.raises(ch.SceneError, match="body.inertia, initial.rates: the monitor"):
                ch.run(scene)
            continue
        alone = ch.run(scene)
        assert result.status[i] == OK and result.steps[i] == alone.counters["steps"]
        for name in alone.conserved:
            np.testing.assert_allclose(result.drift[name][i], drift_row(alone, name), atol=1e-14)
        expected = [alone.variables[k][-1] for k in result.final_names]
        np.testing.assert_allclose(result.final_state[i], expected, rtol=0, atol=1e-13)
        assert result.events["invariable_plane"][i] == len(alone.events["invariable_plane"]) > 0


def test_lane_members_do_not_depend_on_their_lane_mates(body_sweep):
    """A member's bits are its own: the same members in another order, chunking and thread
    count (other lanes, other lane-mates, lanes left idle) give the same rows."""
    s, result, _ = body_sweep
    order = [4, 1, 5, 0, 3, 2]
    members = s.members()
    from cayley_heyoka.workflows.sweep import layout_of, propagate_members

    layout = layout_of(s)
    part = propagate_members(s, [(i, members[i]) for i in order], layout, threads=1)
    for row, i in enumerate(order):
        assert part.steps[row] == result.steps[i]
        for name in layout.drift:
            np.testing.assert_array_equal(part.drift[name][row], result.drift[name][i])
        np.testing.assert_array_equal(part.final[row], result.final_state[i])


def test_a_lane_member_out_of_steps_stops_as_its_run_does():
    """A member whose step budget runs out midway stops where run() stops it, with its rows;
    its lane-mates go on (a batch re-run lane by lane)."""
    s = study(parameters={"integrator.max_steps": [7, 100000], "body.inertia[1]": ["1.5"]})
    result = run_sweep(s, workers=1)
    assert result.metadata["paths"] == {PATH_LANES: 2}
    for i, values in enumerate(s.members()):
        scene = s.member_scene(i, values)
        try:
            alone = ch.run(scene)
        except ch.IntegrationError as exc:
            alone = exc.result
        assert result.steps[i] == alone.counters["steps"]
        assert result.message[i] == alone.message
        assert (result.status[i] == OK) == alone.success
        reached = len(alone.t)
        for name in alone.conserved:
            np.testing.assert_allclose(
                result.drift[name][i][:reached], drift_row(alone, name), atol=1e-14
            )
    assert result.status[0] == FAILED and "max_steps = 7" in result.message[0]


@pytest.mark.parametrize(
    "scene, members",
    [
        (RODRIGUES, ["0.2", "0.3", "0.25"]),  # chart re-basings every few steps
        (ORBIT_CAYLEY, ["0.85", "0.8", "0.9"]),  # ρ's revolutions (a handler with state)
        (ORBIT_ENCKE, ["0.85", "0.8", "0.9"]),  # Encke's rectifications
    ],
    ids=["rodrigues", "cayley", "encke"],
)
def test_members_with_terminal_events_take_the_steps_of_run_in_lanes(scene, members):
    """Terminal events run in the lanes too, each member's handler on its own lane: run()'s
    steps, counts and events, states to a few ulps; reordered, the same bits."""
    name = "initial.rates[0]" if scene is RODRIGUES else "orbit.velocity[1]"
    s = study(scene=scene, parameters={name: members})
    result = run_sweep(s, workers=2)
    assert result.metadata["paths"] == {PATH_LANES: 3}
    for i, values in enumerate(s.members()):
        alone = ch.run(s.member_scene(i, values))
        assert result.status[i] == OK and result.steps[i] == alone.counters["steps"]
        for name_ in alone.conserved:
            np.testing.assert_allclose(result.drift[name_][i], drift_row(alone, name_), atol=1e-14)
        assert result.final_names == tuple(alone.variables)
        expected = np.array([v[-1] for v in alone.variables.values()], dtype=float)
        np.testing.assert_allclose(result.final_state[i], expected, rtol=1e-12, atol=1e-13)
        for event, log in alone.events.items():
            assert result.events[event][i] == len(log)
    from cayley_heyoka.workflows.sweep import layout_of, propagate_members

    layout = layout_of(s)
    order = [2, 0, 1]
    part = propagate_members(s, [(i, s.members()[i]) for i in order], layout, threads=1)
    for row, i in enumerate(order):
        assert part.steps[row] == result.steps[i]
        np.testing.assert_array_equal(part.final[row], result.final_state[i])


def test_the_file_has_the_documented_layout(body_sweep):
    s, result, out = body_sweep
    with h5py.File(out) as f:
        assert f.attrs["format"] == "cayley_heyoka.sweep"
        assert json.loads(f.attrs["study"])["sweep"]["parameters"]["initial.rates[1]"][1] == "1e160"
        meta = json.loads(f.attrs["metadata"])
        assert meta["backend"] == "local" and meta["complete"] and meta["heyoka"]
        assert f.attrs["format_version"] == 3 and f.attrs["Conventions"] == "CF-1.10"
        assert f["time"].shape == (21,) and f["time"].dtype == np.float64
        order = json.loads(f.attrs["order"])
        assert order["parameters"] == ["initial.rates[1]", "body.inertia[1]"]
        np.testing.assert_array_equal(f["body.inertia[1]"][()], [1.5, 2] * 3)
        assert [m.decode() for m in f["monitor"][()]] == order["drift"]
        assert set(order["drift"]) == {"energy", "momentum_squared", "momentum_space"}
        assert f["drift"].shape == (3, 6, 21) and f["drift"].dtype == np.float64
        assert f["final_state"].shape == (6, len(order["final"]))
        np.testing.assert_array_equal(f["status"][()], [OK, OK, FAILED, FAILED, OK, OK])
        # netCDF-4: each array names its dimensions; the parameters are member coordinates.
        assert [d[0].name for d in f["drift"].dims] == ["/monitor", "/member", "/time"]
        assert f["steps"].attrs["coordinates"] == "initial.rates[1] body.inertia[1]"
        assert f["message"].shape == f["steps"].shape == (6,)
    loaded = SweepResult.load(out)
    for name in result.drift:
        np.testing.assert_array_equal(loaded.drift[name], result.drift[name])
    np.testing.assert_array_equal(loaded.final_state, result.final_state)
    assert list(loaded.message) == list(result.message) and loaded.final_names == result.final_names


def test_summary_names_the_worst_member(body_sweep):
    _, result, _ = body_sweep
    text = result.summary()
    final = np.where(result.completed, result.drift["energy"][:, -1], np.nan)
    worst = int(np.nanargmax(final))
    values = result.values(worst)
    assert f"{np.nanmax(final):9.2e}" in text and f"{np.nanmedian(final):9.2e}" in text
    assert f"  {worst} (initial.rates[1] = {values['initial.rates[1]']:.6g}" in text
    assert (
        "4 completed, 2 failed, 0 not run" in text and "member 2 (initial.rates[1] = 1e+160" in text
    )


def test_quad_study_keeps_exact_numbers(tmp_path):
    scene = {**BODY, "integrator": {"precision": "quad"}}
    scene["output"] = {"times": {"start": "0", "stop": "2", "count": "3"}}
    s = study(
        scene=scene, parameters={"initial.rates[0]": {"start": "0.1", "stop": "0.3", "count": 2}}
    )
    result = run_sweep(s, out=tmp_path / "quad.h5", workers=1)
    loaded = SweepResult.load(tmp_path / "quad.h5")
    prec = ch.Precision("quad")
    assert loaded.parameters["initial.rates[0]"][0] == prec.number("0.1")  # not double's 0.1
    for i, values in enumerate(s.members()):
        alone = ch.run(s.member_scene(i, values))
        assert alone.t[-1] == loaded.t[-1]
        expected = [alone.variables[k][-1] for k in result.final_names]
        assert all(a == b for a, b in zip(loaded.final_state[i], expected, strict=True))
        np.testing.assert_array_equal(loaded.drift["energy"][i], drift_row(alone, "energy"))
    assert np.nanmax(loaded.drift["energy"]) < 1e-30


def test_an_interrupted_sweep_keeps_what_it_computed(tmp_path):
    s = study()  # 6 members

    def stop_after_first_chunk(done, total):
        raise KeyboardInterrupt

    out = tmp_path / "stopped.h5"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(s, out=out, chunk=2, progress=stop_after_first_chunk)
    kept = SweepResult.load(out)
    np.testing.assert_array_equal(kept.status, [OK, OK] + [NOT_RUN] * 4)
    assert np.isfinite(kept.drift["energy"][:2]).all() and np.isnan(kept.drift["energy"][2:]).all()
    assert kept.metadata["complete"] is False and "KeyboardInterrupt" in kept.metadata["stopped"]
    assert "2 completed, 0 failed, 4 not run (STOPPED" in kept.summary()


# ---------------------------------------------------------------------- command line and Dask
def test_command_line_exit_codes(tmp_path, capsys):
    good = STUDIES / "free_body_grid.toml"
    out = tmp_path / "grid.h5"
    assert main(["sweep", str(good), "--out", str(out), "--no-progress", "--workers", "2"]) == 0
    text = capsys.readouterr().out
    assert "28 completed, 0 failed" in text and f"sweep written to {out}" in text
    assert SweepResult.load(out).completed.all()

    failing = tmp_path / "failing.toml"
    failing.write_text(
        'scene = "' + str(STUDIES.parent / "free_body.toml") + '"\n'
        '[sweep]\nkind = "grid"\n[sweep.parameters]\n"initial.rates[1]" = [0.25, 1e160]\n'
    )
    assert main(["sweep", str(failing), "--no-progress"]) == 1
    assert "1 completed, 1 failed" in capsys.readouterr().out

    bad = tmp_path / "bad.toml"
    bad.write_text(failing.read_text().replace("[1]", "[5]"))
    assert main(["sweep", str(bad), "--no-progress"]) == 2
    assert (
        'sweep.parameters."initial.rates[5]": index [5] is out of range' in capsys.readouterr().err
    )

    assert main(["sweep", str(good), "--backend", "local", "--scheduler", "tcp://x:1"]) == 2
    assert "needs backend = 'dask'" in capsys.readouterr().err


def test_dask_local_cluster_gives_the_local_arrays(body_sweep, tmp_path):
    pytest.importorskip("distributed")
    s, local, _ = body_sweep
    result = run_sweep(s, out=tmp_path / "dask.h5", backend="dask", workers=2, chunk=2)
    meta = SweepResult.load(tmp_path / "dask.h5").metadata
    assert meta["backend"] == "dask" and meta["cluster"] == "LocalCluster" and meta["workers"] == 2
    assert meta["paths"] == {PATH_LANES: 6}
    np.testing.assert_array_equal(result.status, local.status)
    np.testing.assert_array_equal(result.steps, local.steps)
    np.testing.assert_array_equal(result.final_state, local.final_state)
    for name in local.drift:
        np.testing.assert_array_equal(result.drift[name], local.drift[name])
    np.testing.assert_array_equal(
        result.events["invariable_plane"], local.events["invariable_plane"]
    )
    assert list(result.message) == list(local.message)


def test_an_unreachable_scheduler_is_refused_before_the_file_is_written(
    tmp_path, capsys, monkeypatch
):
    pytest.importorskip("distributed")
    from cayley_heyoka.workflows import sweep_dask

    monkeypatch.setattr(sweep_dask, "CONNECT_TIMEOUT", 1)
    out = tmp_path / "lost.h5"
    args = ["sweep", str(STUDIES / "free_body_random.toml"), "--out", str(out), "--no-progress"]
    assert main([*args, "--scheduler", "tcp://127.0.0.1:9"]) == 2
    assert "--scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:9" in (
        capsys.readouterr().err
    )
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_scheduler_address_reaches_a_cluster_of_separate_processes(body_sweep, tmp_path):
    """Scaling out: a scheduler and a worker started as their own processes, as on a cluster;
    the sweep connects by address and gathers the same arrays as the local run."""
    pytest.importorskip("distributed")
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    scheduler = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "distributed.cli.dask_scheduler",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--dashboard-address",
            ":0",
        ],
        **quiet,
    )
    worker = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "distributed.cli.dask_worker",
            address,
            "--nworkers",
            "1",
            "--nthreads",
            "1",
            "--no-dashboard",
        ],
        **quiet,
    )
    try:
        s, local, _ = body_sweep
        result = run_sweep(s, out=tmp_path / "remote.h5", backend="dask", scheduler=address)
    finally:
        for proc in (worker, scheduler):
            proc.terminate()
            proc.wait(timeout=30)
    meta = SweepResult.load(tmp_path / "remote.h5").metadata
    assert meta["cluster"] == f"scheduler {address}" and meta["workers"] == 1
    np.testing.assert_array_equal(result.final_state, local.final_state)
    for name in local.drift:
        np.testing.assert_array_equal(result.drift[name], local.drift[name])


def test_lane_columns_are_padded_in_their_widest_gap_or_refused():
    """A lane's column is padded (rectangular batch calls) with times strictly inside its widest
    gap, the last point kept last; a grid with no room is refused by name, not mangled."""
    from cayley_heyoka.core.lanes import _padded

    points = np.array([0.0, 1e-300, 1.0, 2.0])
    padded = _padded(points, 8)
    assert len(padded) == 8 and np.all(np.diff(padded) > 0) and padded[-1] == 2.0
    assert set(points) <= set(padded)
    with pytest.raises(ValueError, match="output.times"):
        _padded(np.array([1.0, np.nextafter(1.0, 2.0)]), 5)


@pytest.mark.parametrize("scene", [BODY, RODRIGUES], ids=["quaternion", "rodrigues"])
def test_a_cancel_stops_the_batch_calls_in_flight(scene):
    """A batch call covers its members' whole span; a cancel (Ctrl-C in a sweep) makes the
    integrators' parameters NaN, so heyoka returns after its current step and the members in
    flight stay unfinished, instead of stepping on to t = 1e7 (hours: a hang)."""
    import threading

    from cayley_heyoka.core import lanes, signals
    from cayley_heyoka.core.engine import model_of

    data = {**scene, "output": {"times": {"start": "0", "stop": "1e7", "count": 3}}}
    member = ch.Scene.from_dict(data)
    model = model_of(member)
    grid = member.output.time_grid(member.integrator.precision)
    initial = np.repeat(np.array(model.initial_state, dtype=float)[None, :], 12, axis=0)
    pars = np.repeat(np.array(model.pars.values, dtype=float)[None, :], 12, axis=0)
    cancel = signals.Cancel()
    out: list = []
    worker = threading.Thread(
        target=lambda: out.append(
            lanes.integrate_lanes(model, member.integrator, grid, initial, pars, 1, cancel)
        )
    )
    worker.start()
    threading.Timer(0.5, cancel.set).start()
    worker.join(timeout=120)  # a hang check, not a timing: uncancelled, this runs for hours
    assert not worker.is_alive() and len(out) == 1
    assert all(r is None for r in out[0])
