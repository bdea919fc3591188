"""Hostile numbers downstream of the engine (issue 32, classes 4, 5 and 12): values undefined
by design, differences below double's ε, certificates that must cover what a file holds,
terminal handlers that cannot act, results too short to plot. Each case ends as conftest.py
requires, and the numbers it prints or writes are checked against what they must be.

The one mechanism behind most of them is :mod:`cayley_heyoka.core.exact`: exact values of a
run's numbers, and differences in which a value undefined (NaN) in both results agrees and one
undefined in one result only is an infinite disagreement.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import mpmath
import numpy as np
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core import engine
from cayley_heyoka.core.certificate import written
from cayley_heyoka.core.exact import difference
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.core.result import EventLog
from cayley_heyoka.testing import (
    DriftEnvelope,
    assert_drift_within,
    assert_trajectory_close,
)
from cayley_heyoka.workflows.reference import read_certificate

PRECISIONS = ["double", "quad"]

#: A Kepler orbit whose reference plane tilts through it (docs/orbits.md, "Near-equatorial
#: orbits"): at t = 0.5 the run is on the tilted frame, so Theta and Sigma are NaN there.
PASSAGE = {
    "orbit": {
        "mu": "1",
        "elements": {
            "a": "1",
            "e": "0.1",
            "inclination": "0.05",
            "node": "0",
            "argument_of_pericentre": "0",
            "mean_anomaly": "0",
        },
    },
    "reference_plane": {"phi_rate": "0.1"},
    "output": {"times": {"start": "0", "stop": "1", "count": 11}},
}
#: A J2 orbit for the twin checks.
ORBIT = {
    "orbit": {"mu": "1", "position": ["0.9", "0.2", "0.1"], "velocity": ["-0.25", "0.85", "0.45"]},
    "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.8"}},
    "output": {"times": {"start": "0", "stop": "1", "count": 3}},
}
#: The torque-free body with Psi (output.invariable_angle).
PSI = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.125", "0.25", "1"]},
    "output": {"times": {"start": "0", "stop": "2", "count": 3}, "invariable_angle": True},
}


def _in(data: dict, precision: str) -> dict:
    return {**data, "integrator": {"precision": precision}}


def _nan(values: np.ndarray) -> np.ndarray:
    return np.array([v != v for v in values])


@pytest.fixture(scope="module")
def passages() -> dict[str, ch.Result]:
    return {p: ch.run(ch.Scene.from_dict(_in(PASSAGE, p))) for p in PRECISIONS}


# ---------------------------------------------------------------------- class 4: NaN by design
@pytest.mark.covers("class:4", "verb:reference", "option:reference --precision")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_reference_through_the_reference_plane(hostile, tmp_path, precision):
    """Both runs are tilted at t = 0.5: undefined in both, Theta and Sigma agree there (error
    0), and every other value is certified; the file reads back and matches itself."""
    out = tmp_path / "ref.h5"
    argv = ["reference", str(hostile.scene(PASSAGE)), "--digits", "8", "--out", str(out)]
    if precision == "quad":
        argv += ["--precision", "quad"]
    o = hostile.run([*argv, "--no-progress"], expect="done", out=out)
    assert "certified: " in o.stdout
    ref, cert = ch.load_result(out), read_certificate(out)
    assert cert["certified"] and json.loads(cert["uncovered"]) == []
    assert set(cert["errors"]) == {*ref.variables, *ref.monitors}
    for name in ("Theta", "Sigma"):
        undefined = _nan(ref[name])
        assert undefined.tolist() == [k == 5 for k in range(11)], name
        assert np.all(cert["errors"][name][undefined] == 0)
        assert np.all(np.isfinite(cert["errors"][name]))
    assert_trajectory_close(out, out)


@pytest.mark.covers("class:4", "api:assert_trajectory_close")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_a_passage_matches_itself_and_not_a_one_sided_nan(passages, tmp_path, precision):
    r = passages[precision]
    assert _nan(r["Theta"]).sum() == 1
    assert_trajectory_close(r, r)
    r.save(tmp_path / "r.h5")
    assert_trajectory_close(tmp_path / "r.h5", r)
    # The double run against the quad one: the same rows are undefined in both.
    assert_trajectory_close(passages["double"], passages["quad"])
    # A value where the other result has none is a disagreement, named as such.
    other = ch.Result(**{**vars(r), "variables": dict(r.variables)})
    theta = np.array(r["Theta"], copy=True)
    theta[5] = theta[4]
    other.variables["Theta"] = theta
    with pytest.raises(
        AssertionError, match=r"Theta: 1 of 11 .*undefined \(NaN\) in the reference"
    ):
        assert_trajectory_close(other, r)
    with pytest.raises(AssertionError, match=r"undefined \(NaN\) in the result only"):
        assert_trajectory_close(r, other)


@pytest.mark.covers("class:4", "api:assert_drift_within")
def test_drift_window_undefined_in_both_agrees():
    windows = np.array([[0.0, 1.0], [1.0, 2.0]])
    golden = DriftEnvelope(windows, {"energy": np.array([1.0, np.nan])}, Precision("double"))
    assert_drift_within(
        DriftEnvelope(windows, {"energy": np.array([2.0, np.nan])}, golden.precision), golden
    )
    one_sided = DriftEnvelope(windows, {"energy": np.array([np.nan, 3.0])}, golden.precision)
    with pytest.raises(AssertionError, match="energy: 2 of 2 windows exceed"):
        assert_drift_within(one_sided, golden)


# ---------------------------------------------------------------------- class 5: below double's ε
def _errors(stdout: str) -> list[float]:
    """The error column of a check's rows."""
    rows = [ln for ln in stdout.splitlines() if re.match(r"\s+(position|velocity):", ln)]
    return [float(re.split(r"\s{2,}", ln.strip())[1]) for ln in rows]


@pytest.mark.covers("class:5", "verb:check")
def test_quad_orbit_check_measures_below_double(hostile):
    """The Cayley and Cartesian twins of a quad run differ by ~1e-34: measured, not 0."""
    o = hostile.run(["check", str(hostile.scene(_in(ORBIT, "quad")))], expect="done")
    errors = _errors(o.stdout)
    assert len(errors) == 2 and all(1e-37 < e < 1e-31 for e in errors), errors


@pytest.mark.covers("class:5", "verb:check")
@pytest.mark.parametrize(("precision", "planted"), [("double", "1e-13"), ("quad", "3e-32")])
def test_orbit_check_sees_a_planted_difference(hostile, monkeypatch, precision, planted):
    """The twin's x moved by a few times the bound (1.1e-14 double, 1.1e-32 quad) fails the
    check, and the error printed is the planted difference."""
    real = engine.run
    runs = []

    def perturbed(scene, *args, **kwargs):
        result = real(scene, *args, **kwargs)
        runs.append(result)
        if len(runs) == 2:  # the twin
            prec = result.precision
            result.variables["x"] = result["x"] + prec.number(planted)
        return result

    monkeypatch.setattr(engine, "run", perturbed)
    o = hostile.run(["check", str(hostile.scene(_in(ORBIT, precision)))], expect="stopped")
    assert "FAILED" in o.stdout
    position = _errors(o.stdout)[0]
    assert abs(position - float(planted)) < 0.01 * float(planted), position


@pytest.mark.covers("class:5", "verb:check", "verb:reference")
def test_results_do_not_depend_on_mpmath_precision(hostile, tmp_path, monkeypatch):
    """mpmath's global precision decides nothing — a quad check's errors, a reference by two
    precisions and one by the closed form, their certificates — and is left as it was."""
    check = ["check", str(hostile.scene(_in(ORBIT, "quad")))]
    scenes = {
        "two precisions": hostile.scene(ORBIT),
        "closed form": hostile.scene(_in(PSI, "quad")),
    }
    seen = []
    for bits in (12, 300):
        monkeypatch.setattr(mpmath.mp, "prec", bits)
        got: dict = {"check": _errors(hostile.run(check, expect="done").stdout)}
        for route, scene in scenes.items():
            out = tmp_path / f"{route}{bits}.h5"
            argv = ["reference", str(scene), "--digits", "8", "--out", str(out)]
            hostile.run(argv, expect="done", out=out)
            ref = ch.load_result(out)
            got[route] = {k: ref.precision.to_text(v).tolist() for k, v in written(ref).items()}
            got[route]["certificate"] = {
                k: v.tolist() for k, v in read_certificate(out)["errors"].items()
            }
        assert mpmath.mp.prec == bits
        seen.append(got)
    assert seen[0] == seen[1]


# ---------------------------------------------------------------------- class 12: Encke
@pytest.mark.covers("class:12", "key:orbit.elements", "key:orbit.formulation")
@pytest.mark.parametrize(
    ("precision", "e"), [("double", "0.99999999999999999"), ("quad", "0." + "9" * 36)]
)
def test_encke_start_whose_eccentricity_rounds_to_one_is_refused(hostile, precision, e):
    data = _in(PASSAGE, precision)
    data["orbit"] = {**data["orbit"], "formulation": "encke"}
    data["orbit"]["elements"] = {**data["orbit"]["elements"], "e": e, "mean_anomaly": "1"}
    data.pop("reference_plane")
    o = hostile.run(["run", str(hostile.scene(data))], expect="refused", field="orbit.elements")
    assert "rounds to 1 in the run's precision" in o.error_line and precision in o.error_line


@pytest.mark.covers("class:12", "verb:run")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_encke_orbit_that_stops_being_an_ellipse_stops_with_its_rows(
    hostile, tmp_path, monkeypatch, precision
):
    """At its first rectification after the start the osculating orbit is (made) hyperbolic:
    the run stops there, its rows kept, with Encke's own message."""
    from cayley_heyoka.orbit import encke

    real, calls = encke._rectify, []

    def unbound(ar, mu, X, V):
        calls.append(1)
        if len(calls) == 2:
            raise encke.Unbound(ar.exact(1) + ar.exact(2) ** -40)
        return real(ar, mu, X, V)

    monkeypatch.setattr(encke, "_rectify", unbound)
    monkeypatch.setattr(encke, "_rectify_compiled", lambda enc, ta, pars: False)
    data = _in(ORBIT, precision)
    data["orbit"] = {**data["orbit"], "formulation": "encke"}
    data["output"] = {"times": {"start": "0", "stop": "20", "count": 21}}
    out = tmp_path / "r.h5"
    o = hostile.run(["run", str(hostile.scene(data)), "--out", str(out)], expect="stopped", out=out)
    assert "not an ellipse" in o.stderr and "formulation = 'cartesian'" in o.stderr
    r = ch.load_result(out)
    assert r.status == -1 and 0 < len(r.t) < 21


# ---------------------------------------------------------------------- class 12: handlers
def _raising(exc: BaseException):
    def handler(self, *args, **kwargs):
        raise exc

    return handler


HANDLERS = [
    pytest.param(
        "cayley_heyoka.orbit.tilt.EquatorialHandover.__call__",
        PASSAGE,
        ValueError("cannot convert NaN to integer"),
        "equatorial_handovers",
        id="tilt",
    ),
    pytest.param(
        "cayley_heyoka.orbit.revolutions.Revolutions.__call__",
        {**ORBIT, "output": {"times": {"start": "0", "stop": "20", "count": 5}}},
        ZeroDivisionError("division by zero"),
        "revolutions",
        id="revolutions",
    ),
    pytest.param(
        "cayley_heyoka.rotation.charts.RodriguesAtlas.rebase",
        {
            "body": {"inertia": [1.0, 1.5, 2.5]},
            "initial": {"rates": [0.125, 0.25, 1.0], "rodrigues": [0.1, 0.2, -0.3]},
            "attitude": {"formulation": "rodrigues"},
            "output": {"times": {"start": 0.0, "stop": 20.0, "count": 5}},
        },
        OverflowError("math range error"),
        "rebasings",
        id="charts",
    ),
]


@pytest.mark.covers("class:12", "verb:run")
@pytest.mark.parametrize(("target", "scene", "exc", "counter"), HANDLERS)
@pytest.mark.parametrize("precision", PRECISIONS)
def test_handler_that_cannot_act_stops_the_run_with_its_rows(
    hostile, tmp_path, monkeypatch, target, scene, exc, counter, precision
):
    """Whatever arithmetic a terminal handler fails at ends the run there through the
    engine's one stop path (a message, the rows kept), never as a traceback."""
    monkeypatch.setattr(target, _raising(exc))
    out = tmp_path / "r.h5"
    argv = ["run", str(hostile.scene(_in(scene, precision))), "--out", str(out)]
    o = hostile.run(argv, expect="stopped", out=out)
    assert f"terminal event '{counter}' could not be handled" in o.stderr and str(exc) in o.stderr
    r = ch.load_result(out)
    assert r.status == -1 and 0 < len(r.t) < len(
        ch.Scene.from_dict(scene).output.time_grid(r.precision)
    )


@pytest.mark.covers("class:12", "verb:sweep")
def test_handler_that_cannot_act_fails_its_sweep_member(hostile, tmp_path, monkeypatch):
    """The batch lanes call handlers through the same path: each member fails with the
    message, and the sweep ends as one whose members failed."""
    monkeypatch.setattr(
        "cayley_heyoka.orbit.revolutions.Revolutions.__call__",
        _raising(ZeroDivisionError("division by zero")),
    )
    scene = {**ORBIT, "output": {"times": {"start": "0", "stop": "20", "count": 5}}}
    study = hostile.scene(
        {"title": "s", "scene": scene,
         "sweep": {"kind": "grid", "parameters": {"orbit.velocity[0]": ["-0.25", "-0.24"]}}}
    )  # fmt: skip
    out = tmp_path / "s.h5"
    o = hostile.run(["sweep", str(study), "--out", str(out)], expect="stopped", out=out)
    assert "0 completed, 2 failed" in o.stdout
    assert o.stdout.count("terminal event 'revolutions' could not be handled") == 2


# ---------------------------------------------------------------------- class 12: certificates
@pytest.mark.covers("class:12", "key:output.invariable_angle", "verb:reference")
@pytest.mark.parametrize("precision", PRECISIONS)
def test_reference_certificate_covers_psi(hostile, tmp_path, precision):
    """Psi and the monitors have proved errors on both routes, and they hold: the closed
    form's file and the integrated one differ by no more than their two bounds."""
    digits = "10" if precision == "double" else "25"
    scene = hostile.scene(PSI)
    files = {}
    route = "integrate"
    for method in ("closed-form", route):
        out = tmp_path / f"{method}.h5"
        argv = ["reference", str(scene), "--digits", digits, "--certificate", method]
        argv += ["--out", str(out), "--precision", precision, "--overwrite"]
        hostile.run(argv, expect="done", out=out)
        files[method] = out
    a, b = (ch.load_result(files[k]) for k in ("closed-form", route))
    ca, cb = (read_certificate(files[k]) for k in ("closed-form", route))
    for cert, result in ((ca, a), (cb, b)):
        assert cert["proved"] and cert["certified"] and json.loads(cert["uncovered"]) == []
        assert set(cert["errors"]) == {*result.variables, *result.monitors} >= {"psi", "energy"}
    for name in [*a.variables, *a.monitors]:
        gap = difference(a[name], b[name])
        assert np.all(gap <= (ca["errors"][name] + cb["errors"][name]) * (1 + 1e-12)), name


@pytest.mark.covers("class:12", "key:monitors", "verb:reference")
def test_reference_of_what_the_closed_form_lacks_is_certified_by_a_second_precision(
    hostile, tmp_path
):
    """A user monitor the closed form does not give: two precisions certify every value."""
    data = {**PSI, "monitors": {"spin": {"expression": "p*p + q*q + r*r"}}}
    out = tmp_path / "ref.h5"
    argv = ["reference", str(hostile.scene(data)), "--digits", "8", "--out", str(out)]
    o = hostile.run([*argv, "--certificate", "integrate"], expect="done", out=out)
    assert "certificate from a second precision" in o.stdout
    cert = read_certificate(out)
    assert cert["method"] == "two precisions" and not cert["proved"] and cert["certified"]
    assert {"spin", "psi", "energy"} <= set(cert["errors"])


@pytest.mark.covers("class:12", "verb:reference")
def test_a_value_without_error_makes_the_file_unproved_and_uncertified(
    hostile, tmp_path, monkeypatch
):
    """Whatever route made the certificate, a written value it has no error for is named,
    and the file is neither proved nor certified (exit 1)."""
    from cayley_heyoka.rotation.free_body_reference import FreeBodyClosedForm

    real = FreeBodyClosedForm.certificate

    def without_psi(self, result, digits):
        cert = real(self, result, digits)
        del cert.errors["psi"]
        return cert

    monkeypatch.setattr(FreeBodyClosedForm, "certificate", without_psi)
    out = tmp_path / "ref.h5"
    argv = ["reference", str(hostile.scene(PSI)), "--digits", "8", "--out", str(out)]
    o = hostile.run([*argv, "--certificate", "integrate"], expect="stopped", out=out)
    assert "NOT CERTIFIED" in o.stdout and "the certificate gives no error for: psi" in o.stdout
    cert = read_certificate(out)
    assert not cert["proved"] and not cert["certified"] and json.loads(cert["uncovered"]) == ["psi"]
    assert not ch.load_result(out).metadata["reference"]["certified"]


# ---------------------------------------------------------------------- class 12: plots
SHORT = {
    "orbit": (ORBIT, ["orbit", "drift"]),
    "rotation": (
        {**PSI, "output": {"times": {"start": "0", "stop": "1", "count": 3},
                           "events": ["invariable_plane"]}},
        ["polhode", "crossings", "drift"],
    ),
    "hamiltonian": (
        {"hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3", "nu": "0.45"},
         "initial": {"eta": ["0.2", "-0.4", "1.5"], "varpi": ["0.7", "0.3", "2.1"]},
         "output": {"times": {"start": "0", "stop": "1", "count": 3}}},
        ["drift"],
    ),
}  # fmt: skip


@pytest.fixture(scope="module")
def short_files(tmp_path_factory) -> dict[tuple[str, str, int], Path]:
    """Stopped results of 0 and 1 output rows, each family, double and quad."""
    d = tmp_path_factory.mktemp("short")
    files = {}
    for family, (data, _) in SHORT.items():
        for precision in PRECISIONS:
            full = ch.run(ch.Scene.from_dict(_in(data, precision)))
            for n in (0, 1):
                cut = ch.Result(**vars(full))
                cut.t = full.t[:n]
                cut.variables = {k: v[:n] for k, v in full.variables.items()}
                cut.monitors = {k: v[:n] for k, v in full.monitors.items()}
                cut.events = {
                    k: EventLog(log.time[:0], log.direction[:0], log.label[:0])
                    for k, log in full.events.items()
                }
                cut.status, cut.message = -1, "stopped before the second output time"
                path = d / f"{family}-{precision}-{n}.h5"
                cut.save(path)
                files[family, precision, n] = path
    return files


def _short_cases() -> list:
    """Every kind of every family, 0 and 1 rows, double and quad; a drawing (a family's plot
    of one row) in double only: the precision changes nothing in matplotlib's work."""
    cases = []
    for family, (_, kinds) in SHORT.items():
        for kind in kinds:
            for precision in PRECISIONS:
                for rows in (0, 1):
                    if rows == 1 and kind != "drift" and precision == "quad":
                        continue
                    cases.append((family, kind, precision, rows))
    return cases


@pytest.mark.covers("class:12", "verb:plot", "option:plot --kind")
@pytest.mark.parametrize(("family", "kind", "precision", "rows"), _short_cases())
def test_plot_of_a_result_with_too_few_rows(
    hostile, short_files, tmp_path, family, kind, precision, rows
):
    """No row: every kind is refused, naming the file and why; one row: the drift (0 at its
    only time by definition) is refused, a family's plot is drawn."""
    path = short_files[family, precision, rows]
    out = tmp_path / "p.png"
    argv = ["plot", str(path), "--kind", kind, "--out", str(out)]
    if rows == 0 or kind == "drift":
        rule = "no output rows" if rows == 0 else "one output row"
        o = hostile.run(argv, expect="refused", field=rule)
        assert str(path) in o.error_line and "stopped before the second output time" in o.error_line
        assert not out.exists()
    else:
        hostile.run(argv, expect="done")
        assert out.stat().st_size > 0
