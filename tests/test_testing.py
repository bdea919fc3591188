"""cayley_heyoka.testing and its pytest plugin: what passes, what fails, what the message says."""

from __future__ import annotations

import dataclasses
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import h5py
import heyoka as hy
import numpy as np
import pytest
from helpers import free_body

import cayley_heyoka as ch
from cayley_heyoka import Result, pytest_plugin
from cayley_heyoka.core.files import seal
from cayley_heyoka.testing import (
    DriftEnvelope,
    assert_drift_within,
    assert_trajectory_close,
    drift_envelope,
)

pytest_plugins = ["pytester"]

ROOT = Path(__file__).resolve().parent.parent
EPS = 2.0**-52


@pytest.fixture(scope="module")
def double_run() -> Result:
    return ch.run(ch.Scene.from_dict(free_body()))


@pytest.fixture(scope="module")
def quad_run() -> Result:
    return ch.run(ch.Scene.from_dict(free_body(integrator={"precision": "quad"})))


def with_variable(result: Result, name: str, values: np.ndarray) -> Result:
    return dataclasses.replace(result, variables={**result.variables, name: values})


def synthetic(scale: float = 1.0, *, stop: float = 100.0, count: int = 101) -> Result:
    """A double run whose energy drifts by round(scale·√t) ε exactly (E(0) = 1)."""
    t = np.linspace(0.0, stop, count)
    k = np.round(scale * np.sqrt(t))
    momentum = np.column_stack([np.ones(count), -3 * k * EPS, np.zeros(count)])
    return Result(
        t=t,
        variables={"x": np.cos(t)},
        monitors={"energy": 1.0 + k * EPS, "momentum": momentum, "free": t},
        conserved=("energy", "momentum"),
        scene={"title": "synthetic"},
    )


# ---------------------------------------------------------------------- trajectories
def test_double_run_follows_a_quad_reference_and_the_message_locates_a_failure(
    double_run, quad_run
):
    assert_trajectory_close(double_run, quad_run)
    with pytest.raises(AssertionError) as failure:
        assert_trajectory_close(double_run, quad_run, rtol=0, atol=1e-16, variables=["p", "q"])
    message = str(failure.value)
    assert "in 2 of 2 variables" in message and "precisions double vs quad" in message
    assert "p: " in message and "output times fail; worst at t = " in message
    assert "(index " in message and "|Δ| = " in message and "first failure at t = " in message


def test_quad_against_quad_resolves_1e_30(quad_run):
    p = quad_run["p"].copy()
    p[7] = p[7] + hy.real128("1e-30")
    nudged = with_variable(quad_run, "p", p)
    assert_trajectory_close(nudged, quad_run, rtol=0, atol=2e-30)
    with pytest.raises(AssertionError) as failure:
        assert_trajectory_close(nudged, quad_run, rtol=0, atol=5e-31)
    message = str(failure.value)
    assert "in 1 of 10 variables" in message
    assert "p: 1 of 11 output times fail; worst at t = 7 (index 7): |Δ| = 1.000e-30" in message


def test_mixed_quad_and_multiprecision_compare_in_the_higher_precision(quad_run):
    real = ch.run(ch.Scene.from_dict(free_body(integrator={"precision": {"bits": 256}})))
    assert_trajectory_close(quad_run, real, rtol=1e-30, atol=1e-30)
    with pytest.raises(AssertionError, match=r"quad vs mpfr256"):
        assert_trajectory_close(quad_run, real, rtol=0, atol=1e-45)


def test_files_and_a_certificate_widen_the_allowance(double_run, tmp_path):
    ref_path = tmp_path / "ref.h5"
    double_run.save(ref_path)
    q = double_run["q"].copy()
    q[3] += 1e-9
    nudged = with_variable(double_run, "q", q)
    with pytest.raises(AssertionError, match=r"(?s)reference without certificate.*\n  q: 1 of 11 "):
        assert_trajectory_close(nudged, ref_path, rtol=0, atol=1e-12)
    bound = np.zeros(11)
    bound[3] = 2e-9
    with h5py.File(ref_path, "a") as f:  # the layout `cayley-heyoka reference` writes
        g = f.create_group("certificate")
        g.create_dataset("q", data=bound)
        g.create_group("events").create_dataset("invariable_plane", data=np.zeros(0))
        seal(f)  # a file edited in place needs its checksum renewed to load
    assert_trajectory_close(nudged, ref_path, rtol=0, atol=1e-12)
    q[5] += 1e-9
    with pytest.raises(AssertionError, match=r"(?s)reference with certificate.*worst at t = 5 "):
        assert_trajectory_close(with_variable(double_run, "q", q), ref_path, rtol=0, atol=1e-12)
    with h5py.File(ref_path, "a") as f:
        del f["certificate/q"]
        f["certificate"].create_dataset("q", data=np.zeros(4))
        seal(f)
    with pytest.raises(ValueError, match=r"certificate 'q' has shape \(4,\), its variable \(11,\)"):
        assert_trajectory_close(nudged, ref_path)


def test_non_finite_values_fail(double_run):
    r = double_run["r"].copy()
    r[4] = np.nan
    with pytest.raises(AssertionError, match=r"r: 1 of 11 output times fail; worst at t = 4 "):
        assert_trajectory_close(with_variable(double_run, "r", r), double_run)


def test_vector_monitors_name_the_component(double_run):
    m = double_run.monitors["momentum_space"].copy()
    m[6, 1] += 1e-6
    nudged = dataclasses.replace(double_run, monitors={**double_run.monitors, "momentum_space": m})
    assert_trajectory_close(nudged, double_run)  # default: variables only
    with pytest.raises(AssertionError, match=r"worst at t = 6 \(index 6, component 1\)"):
        assert_trajectory_close(nudged, double_run, variables="momentum_space")


def test_output_times_must_match(double_run):
    short = dataclasses.replace(double_run, t=double_run.t[:6])
    with pytest.raises(AssertionError, match=r"result has 6, reference 11 \(result ends at t = 5,"):
        assert_trajectory_close(short, double_run)
    t = double_run.t.copy()
    t[8] += 1e-9
    with pytest.raises(AssertionError, match=r"output times differ from index 8 on"):
        assert_trajectory_close(dataclasses.replace(double_run, t=t), double_run)


def test_bad_arguments_name_the_parameter(double_run):
    with pytest.raises(ValueError, match=r"rtol must be finite and >= 0, got -1\.0"):
        assert_trajectory_close(double_run, double_run, rtol=-1)
    with pytest.raises(TypeError, match=r"atol must be a number, got '1e-9'"):
        assert_trajectory_close(double_run, double_run, atol="1e-9")
    with pytest.raises(ValueError, match=r"variables: result has no variable 'nope'"):
        assert_trajectory_close(double_run, double_run, variables=["nope"])
    with pytest.raises(TypeError, match=r"variables must be a non-empty sequence of names"):
        assert_trajectory_close(double_run, double_run, variables=5)
    with pytest.raises(TypeError, match=r"reference must be a Result or a path, got dict"):
        assert_trajectory_close(double_run, {})


# ---------------------------------------------------------------------- drift envelopes
def test_envelope_windows_double_and_peaks_are_in_epsilon():
    env = drift_envelope(synthetic(), windows=4)
    # Windows (0, 12.5], (12.5, 25], (25, 50], (50, 100]; the energy drifts round(√t) ε.
    assert env.windows.tolist() == [[0, 12.5], [12.5, 25], [25, 50], [50, 100]]
    assert env.peaks["energy"].tolist() == [3, 5, 7, 10]
    assert env.peaks["momentum"].tolist() == [9, 15, 21, 30]  # largest component, 3k ε
    assert set(env.peaks) == {"energy", "momentum"}  # "free" is not conserved


def test_quad_envelope_is_scaled_exactly(quad_run):
    env = drift_envelope(quad_run)
    assert env.precision.name == "quad" and env.epsilon == 2.0**-112
    drift = np.max(np.abs(quad_run.drift("energy")[1:]))
    assert np.max(env.peaks["energy"]) == float(drift * hy.real128(2) ** 112)
    assert 0 < np.max(env.peaks["energy"]) < 100


def test_envelope_round_trips_through_its_file(tmp_path, double_run):
    env = drift_envelope(double_run)
    env.save(tmp_path / "g.h5")
    back = DriftEnvelope.load(tmp_path / "g.h5")
    assert np.array_equal(back.windows, env.windows) and back.precision == env.precision
    assert all(np.array_equal(back.peaks[k], v) for k, v in env.peaks.items())
    assert back.title == env.title and back.metadata == env.metadata
    assert back.metadata["heyoka"] == hy.__version__
    with h5py.File(tmp_path / "g.h5") as f:
        assert f.attrs["format"] == "cayley_heyoka.drift"
    double_run.save(tmp_path / "r.h5")
    with pytest.raises(ValueError, match=r"not a cayley_heyoka\.drift file"):
        DriftEnvelope.load(tmp_path / "r.h5")
    os.mkfifo(tmp_path / "fifo")  # opening it would wait for a writer
    (tmp_path / "text.h5").write_text("not HDF5")
    for name, words in [("missing.h5", "no such file"), ("fifo", "not a file"),
                        ("text.h5", "not an HDF5 file")]:  # fmt: skip
        with pytest.raises(ValueError, match=words):
            DriftEnvelope.load(tmp_path / name)


def test_drift_within_golden_and_the_message_of_a_worse_one():
    golden = drift_envelope(synthetic(), windows=4)
    assert_drift_within(synthetic(), golden)
    assert_drift_within(synthetic(6.0), golden)  # 6× the drift: within 8× + 8 ε
    with pytest.raises(AssertionError) as failure:
        assert_drift_within(synthetic(9.0), golden)
    message = str(failure.value)
    assert message.startswith(
        "drift exceeds the golden envelope for 2 of 2 conserved monitors "
        "(double, ε = 2.220e-16; allowed 8 × golden + 8 ε):\n"
    )
    assert (
        "  energy: 1 of 4 windows exceed; worst t in (50, 100]: max |drift| 1.998e-14 (90 ε) "
        "vs golden 2.220e-15 (10 ε), ratio 9, allowed 1.954e-14; first t in (50, 100]"
    ) in message
    assert "  momentum: 4 of 4 windows exceed; worst t in [0, 12.5]: " in message
    assert "first t in [0, 12.5]" in message
    assert_drift_within(synthetic(5.0), golden, factor=5)


def test_drift_comparison_refuses_what_cannot_be_compared(quad_run):
    golden = drift_envelope(synthetic(), windows=4)
    with pytest.raises(AssertionError, match=r"result is in quad, the golden envelope in double"):
        assert_drift_within(quad_run, golden)
    with pytest.raises(AssertionError, match=r"no output time in the golden window \(50, 100\]"):
        assert_drift_within(synthetic(stop=40.0, count=41), golden)
    fewer = dataclasses.replace(synthetic(), conserved=("energy",))
    with pytest.raises(AssertionError, match=r"conserved monitors differ"):
        assert_drift_within(fewer, golden)
    with pytest.raises(ValueError, match=r"factor must be >= 1"):
        assert_drift_within(synthetic(), golden, factor=0.5)
    with pytest.raises(ValueError, match=r"floor must be finite and >= 0"):
        assert_drift_within(synthetic(), golden, floor=-1)
    with pytest.raises(ValueError, match=r"measured: its windows differ"):
        assert_drift_within(drift_envelope(synthetic(), windows=3), golden)
    with pytest.raises(ValueError, match=r"windows must be in 1 … 1000, got 0"):
        drift_envelope(synthetic(), windows=0)
    with pytest.raises(ValueError, match=r"windows must be in 1 … 1000, got 1000000000"):
        drift_envelope(synthetic(), windows=10**9)
    no_conserved = dataclasses.replace(synthetic(), conserved=())
    with pytest.raises(ValueError, match=r"result: the scene has no conserved monitor"):
        drift_envelope(no_conserved)


# ---------------------------------------------------------------------- the pytest plugin
USER_TEST = """
import numpy as np
from cayley_heyoka import Result

EPS = 2.0**-52

def run(scale):
    t = np.linspace(0.0, 100.0, 101)
    energy = 1.0 + np.round(scale * np.sqrt(t)) * EPS
    return Result(t=t, variables={{"x": t}}, monitors={{"energy": energy}}, conserved=("energy",))

def test_drift(drift_golden):
    drift_golden(run({scale}))

def test_named(drift_golden):
    drift_golden(run({scale}), "named")
    drift_golden(run({scale}), path="elsewhere/file.h5")
"""


def test_plugin_writes_then_compares_golden_files(pytester):
    pytester.makepyfile(test_user=USER_TEST.format(scale=1.0))
    # The module itself, registered under its entry-point name (loaded once where installed).
    # Hypothesis's plugin re-imports hypothesis in each in-process run (~1 s): not wanted here.
    plugin = {"plugins": [pytest_plugin]}
    quiet = ("-p", "no:hypothesispytest")
    missing = pytester.runpytest(*quiet, "-k", "test_drift", **plugin)
    missing.assert_outcomes(failed=1)
    missing.stdout.fnmatch_lines(
        [
            "*golden drift file golden/test_drift.h5 does not exist: run pytest with "
            "--update-golden to write it from this run*"
        ]
    )
    written = pytester.runpytest(*quiet, "--update-golden", **plugin)
    written.assert_outcomes(passed=2)
    written.stdout.fnmatch_lines(["*golden drift files written: 3*", "golden/test_drift.h5"])
    for name in ("golden/test_drift.h5", "golden/named.h5", "elsewhere/file.h5"):
        assert DriftEnvelope.load(pytester.path / name).peaks["energy"][-1] == 10
    pytester.runpytest(*quiet, **plugin).assert_outcomes(passed=2)

    pytester.makepyfile(test_user=USER_TEST.format(scale=10.0))
    worse = pytester.runpytest(*quiet, "-k", "test_drift", **plugin)
    worse.assert_outcomes(failed=1)
    worse.stdout.fnmatch_lines(
        [
            "*drift exceeds the golden envelope for 1 of 1 conserved monitors (double, *",
            "*energy: 4 of 8 windows exceed; worst t in (50, 100]: max |drift| 2.220e-14 (100 ε) "
            "vs golden 2.220e-15 (10 ε), ratio 10, allowed 1.954e-14; first t in (6.25, 12.5]",
            "*(golden file golden/test_drift.h5; if the change is intended, rewrite it with pytest "
            "--update-golden)",
        ]
    )


def test_plugin_loads_through_its_entry_point_without_heyoka(pytester, monkeypatch):
    """The pyproject entry point, as an install declares it; `-p` on top loads it once."""
    table = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["entry-points"]
    dist = pytester.path / "site" / "cayley_heyoka-0.1.0.dist-info"
    dist.mkdir(parents=True)
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: cayley_heyoka\nVersion: 0.1.0\n")
    lines = [f"{name} = {target}" for name, target in table["pytest11"].items()]
    (dist / "entry_points.txt").write_text("[pytest11]\n" + "\n".join(lines) + "\n")
    path = os.pathsep.join([str(dist.parent), str(ROOT), os.environ.get("PYTHONPATH", "")])
    monkeypatch.setenv("PYTHONPATH", path)
    pytester.makepyfile(
        test_probe="import sys\n\ndef test_probe(drift_golden, pytestconfig):\n"
        "    assert pytestconfig.getoption('update_golden')\n"
        "    assert 'heyoka' not in sys.modules\n"
    )
    quiet = ("-p", "no:hypothesispytest")
    pytester.runpytest_subprocess(*quiet, "--update-golden").assert_outcomes(passed=1)
    twice = pytester.runpytest_subprocess(
        *quiet, "-p", "cayley_heyoka.pytest_plugin", "--update-golden"
    )
    twice.assert_outcomes(passed=1)


def test_plugin_import_is_cheap():
    code = (
        "import sys, cayley_heyoka.pytest_plugin\n"
        "print(sorted({'heyoka', 'numpy'} & set(sys.modules)))"
    )
    path = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    env = {**os.environ, "PYTHONPATH": path}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"
