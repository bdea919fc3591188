"""The engine's limits: the step budget, watching for signals (bit-identical to not),
interruption keeping results, refusals before compiling, and signals while compiling."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from helpers import SLOW_COMPILE, free_body

import cayley_heyoka as ch
from cayley_heyoka.core import compiler, engine, span_probe
from cayley_heyoka.core.errors import IntegrationError, Interrupted, SceneError

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
HEAVY_TOP = {"heavy_top": {"weight": "1", "center_of_mass": ["0.1", "-0.05", "0.3"]}}


def _scene(prec="double", **tables) -> ch.Scene:
    """A heavy top with invariable-plane events and chart re-basings (terminal events)."""
    data = free_body(
        forces=HEAVY_TOP,
        attitude={"max_chart_angle": 60},
        integrator={"precision": prec, **tables.pop("integrator", {})},
        output={
            "times": {"start": "0", "stop": "40", "count": 81},
            "events": ["invariable_plane"],
            **tables.pop("output", {}),
        },
        **tables,
    )
    return ch.Scene.from_dict(data)


def _same(a: ch.Result, b: ch.Result, rows: int | None = None) -> None:
    """Bit-for-bit equality of two results (of their first ``rows`` rows)."""
    prec = a.precision
    n = len(a.t) if rows is None else rows
    for name in [*a.variables, *a.monitors]:
        assert np.array_equal(prec.to_text(a[name][:n]), prec.to_text(b[name][:n])), name


def _in_a_thread(scene: ch.Scene) -> ch.Result:
    """``ch.run`` outside the main thread: no signal can arrive, so no per-step callback."""
    box = []
    worker = threading.Thread(target=lambda: box.append(ch.run(scene)))
    worker.start()
    worker.join()
    return box[0]


def _orbit(formulation: str) -> ch.Scene:
    data = ch.load_scene(EXAMPLES / "orbit_j2_third_body.toml").to_dict()
    data["orbit"]["formulation"] = formulation
    if formulation == "encke":
        del data["orbit"]["sigma0"]
    data["output"]["times"] = {"start": "0", "stop": "30", "count": 61}
    return ch.Scene.from_dict(data)


def _henon_heiles(stop: str) -> ch.Scene:
    """Hénon–Heiles below its escape energy: equations of integers, no runtime parameter."""
    H = "(varpi1**2 + varpi2**2)/2 + (eta1**2 + eta2**2)/2 + eta1**2*eta2 - eta2**3/3"
    return ch.Scene.from_dict(
        {
            "hamiltonian": {"H": H},
            "initial": {"eta": ["0", "0.1"], "varpi": ["0.35", "0"]},
            "output": {"times": {"start": "0", "stop": stop, "count": 801}},
        }
    )


@pytest.mark.parametrize(
    "build",
    [
        lambda: _scene("double"),
        lambda: _scene("quad"),
        lambda: _orbit("encke"),  # time-dependent forces, Encke's rectifications
        lambda: _orbit("cayley"),
        lambda: _henon_heiles("2000"),  # watched without a callback, its state poisoned
    ],
    ids=["heavy-top-double", "heavy-top-quad", "orbit-encke", "orbit-cayley", "hamiltonian"],
)
def test_watching_for_signals_changes_no_bit(build):
    """The main thread's run (a callback after each step, watching for signals) and a run
    without it: the same bits, events and counters."""
    watched, plain = ch.run(build()), _in_a_thread(build())
    assert watched.counters == plain.counters and watched.counters["steps"] > 50
    _same(watched, plain)
    for name, log in watched.events.items():
        assert np.array_equal(
            watched.precision.to_text(log.time), plain.precision.to_text(plain.events[name].time)
        )


def test_step_budget_stops_cleanly_and_keeps_the_same_bits():
    whole = ch.run(_scene())
    budget = whole.counters["steps"] // 2
    with pytest.raises(IntegrationError) as info:
        ch.run(_scene(integrator={"max_steps": budget}))
    part = info.value.result
    assert part.status == -1 and f"integrator.max_steps = {budget}" in part.message
    assert part.counters["steps"] == budget
    assert 10 < len(part.t) < len(whole.t)
    _same(part, whole, rows=len(part.t))


def test_a_stopped_run_can_be_returned_instead_of_raised(tmp_path):
    """``raise_on_failure=False``: the same partial result the error carries, returned with
    ``success`` False (solve_ivp's convention), and it survives a save and load."""
    whole = ch.run(_scene())
    budget = whole.counters["steps"] // 2
    part = ch.run(_scene(integrator={"max_steps": budget}), raise_on_failure=False)
    assert not part.success and part.status == -1
    assert f"integrator.max_steps = {budget}" in part.message
    _same(part, whole, rows=len(part.t))
    part.save(tmp_path / "part.h5")
    back = ch.load_result(tmp_path / "part.h5")
    assert not back.success and back.message == part.message and len(back.t) == len(part.t)
    assert ch.run(_scene(), raise_on_failure=False).success


def test_interrupt_keeps_what_was_computed():
    """SIGINT during propagation (sent from the progress callback, so at a known time, after
    the first call's steps, whose progress is held until they are kept): an Interrupted
    carrying the rows computed, the same bits as the uninterrupted run."""
    long = {"output": {"times": {"start": "0", "stop": "4000", "count": 81}}}
    whole = ch.run(_scene(**long))

    def progress(t: float) -> None:
        if t > 1500:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(Interrupted) as info:
        ch.run(_scene(**long), progress=progress)
    part = info.value.result
    assert part.status == engine.INTERRUPTED and "interrupted (SIGINT)" in part.message
    assert 30 <= len(part.t) < len(whole.t)
    _same(part, whole, rows=len(part.t))
    # Python's handler is back: Ctrl-C outside a run is a KeyboardInterrupt again.
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.parametrize(
    "build",
    [
        lambda: _scene(output={"times": {"start": "0", "stop": "200000", "count": 801}}),
        lambda: _henon_heiles("1000000"),
    ],
    ids=["parameters", "state"],
)
def test_an_interrupt_without_callback_keeps_the_uninterrupted_bits(build):
    """In the main thread, without a progress callback, heyoka steps in the engine's watch
    thread and a signal poisons the parameters (or, for equations without any, the state):
    the rows kept are the uninterrupted run's, the parameters are restored, and the next run
    of the scene is whole."""
    # Long enough (~1 s of stepping) that a signal sent halfway lands inside the run on a busy
    # machine too (at 0.13 s the run sometimes ended before the timer fired).
    scene = build()
    whole = _in_a_thread(scene)  # no signal can reach it
    # Halfway through the stepping: a cold first run's wall time is mostly compilation, which
    # the run below (from the cache) does not repeat.
    halfway = (whole.metadata["wall_seconds"] - whole.metadata["compile_seconds"]) / 2
    timer = threading.Timer(halfway, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(Interrupted) as info:
            ch.run(scene)
    finally:
        timer.cancel()
    part = info.value.result
    assert part.status == engine.INTERRUPTED and "interrupted (SIGINT) at t = " in part.message
    assert "nan" not in part.message
    assert 0 < len(part.t) < len(whole.t)
    _same(part, whole, rows=len(part.t))
    again = ch.run(scene)  # on the integrator handed back: parameters restored
    _same(again, whole)


def test_interrupt_without_progress_callback_stops_after_a_step():
    """Without a progress callback the engine's own callback sees the signal (within a step)."""
    ch.run(_scene())  # compiled and cached, so that the signal finds the propagation
    scene = _scene(output={"times": {"start": "0", "stop": "1e6", "count": 101}})
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    t0 = time.monotonic()
    try:
        with pytest.raises(Interrupted) as info:
            ch.run(scene)
    finally:
        timer.cancel()
    assert time.monotonic() - t0 < 10
    part = info.value.result
    assert part.status == engine.INTERRUPTED and part.counters["steps"] > 0
    assert len(part.t) < 101


@pytest.mark.parametrize(
    ("change", "field", "words"),
    [
        (
            {
                "body": {"inertia": ["1e307", "1.5e307", "2.5e307"]},
                "initial": {"rates": [10, 20, 30]},
            },
            "body.inertia, initial.rates",
            "overflow double",
        ),
        ({"initial": {"rates": ["1e200", "0", "0"]}}, "body.inertia, initial.rates", "overflow"),
        (
            {"forces": {"potential": {"V": "R33 + 1/0"}}},
            "forces.potential.V",
            "1 / 0 divides by zero",
        ),
        ({"integrator": {"max_step": "1e-300"}}, "integrator.max_step", "step budget"),
        (
            {"integrator": {"max_step": "0.001", "max_steps": 1000}},
            "integrator.max_step",
            "1e+04 steps",
        ),
        (
            {"output": {"times": {"start": "0", "stop": "1", "count": 9_000_000}}},
            "output.times",
            "GiB",
        ),
        ({"output": {"times": ["0.1", "0.10000000000000000001"]}}, "output.times", "double"),
    ],
)
def test_refused_before_integrating(change, field, words):
    with pytest.raises(SceneError) as info:
        ch.run(ch.Scene.from_dict(free_body(**change)))
    assert info.value.field.startswith(field) and words in str(info.value)


def test_times_distinct_in_quad_run_in_quad():
    """The same times are distinct in quad: the run records both."""
    data = free_body(
        integrator={"precision": "quad"}, output={"times": ["0.1", "0.10000000000000000001"]}
    )
    result = ch.run(ch.Scene.from_dict(data))
    assert len(result.t) == 2 and result.t[1] > result.t[0]


def test_a_run_going_non_finite_logs_nothing(capfd):
    data = free_body(
        forces={"potential": {"V": "exp(100 * (t - 6)) * lambda"}},
        output={"times": {"start": "0", "stop": "20", "count": 21}},
    )
    with pytest.raises(IntegrationError):
        ch.run(ch.Scene.from_dict(data))
    captured = capfd.readouterr()
    assert "warning" not in captured.err + captured.out


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_during_compilation_ends_the_process_at_once(tmp_path, sig):
    """This scene compiles for minutes (non-compact quad); the signal ends it within seconds."""
    V = " + ".join(f"{i}*sin(R33*{i % 7 + 1})*cos(R13*{i % 5 + 1})" for i in range(1, 120))
    scene = tmp_path / "slow.toml"
    scene.write_text(SLOW_COMPILE.format(V=V))
    cmd = [sys.executable, "-m", "cayley_heyoka.cli", "run", str(scene), "--no-progress"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(5)
        sent = time.monotonic()
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    # Nothing computed yet: the process ends at once, cleanly (the LLVM compilation holds no
    # GIL, so the signal policy's watching thread can end it).
    assert proc.returncode == 130, err
    assert f"interrupted ({signal.Signals(sig).name}): nothing was computed" in err
    assert time.monotonic() - sent < 15 and "Traceback" not in err


@pytest.mark.parametrize("attitude", ["none", "rodrigues"])
def test_a_span_far_beyond_the_budget_is_refused_from_its_first_steps(attitude):
    """stop = 1e300 would spend the whole budget (10⁹ steps, minutes) before stopping; the
    first steps' rate, extrapolated, refuses it — also when chart re-basings (terminal events
    every ~16 steps) split the first steps into many calls."""
    data = free_body(
        attitude={"formulation": attitude},
        output={"times": {"start": "0", "stop": "1e300", "count": 11}},
    )
    if attitude == "none":
        data.pop("initial", None)
        data["initial"] = {"rates": ["0.75", "-0.5", "0.625"]}
    with pytest.raises(SceneError, match="output.times: the span to t = 1e300 needs about"):
        ch.run(ch.Scene.from_dict(data))


def test_a_span_within_the_budget_runs(monkeypatch):
    """A long run is cut after its first steps for the estimate and started again: the same
    bits as a run that is never cut, and a budget a little above its steps suffices."""

    def scene(**integrator) -> ch.Scene:
        data = free_body(
            attitude={"formulation": "quaternion"},
            integrator=integrator,
            output={"times": {"start": "0", "stop": "2000", "count": 201}},
        )
        return ch.Scene.from_dict(data)

    whole = ch.run(scene())
    assert whole.counters["steps"] > 2 * max(span_probe.PROBES)
    monkeypatch.setattr(span_probe, "PROBES", ())
    uncut = ch.run(scene())
    assert whole.counters == uncut.counters
    _same(whole, uncut)
    monkeypatch.undo()
    snug = ch.run(scene(max_steps=whole.counters["steps"] + 1))
    _same(snug, whole)


def test_a_scene_run_again_is_not_probed_again_and_a_refused_span_stays_refused(monkeypatch):
    """The probe's estimate is made of the scene's first steps, the same at every run of that
    scene object: once it found the span fits, a run of the scene again takes no probe (the
    same bits); a span refused is refused at every run."""
    data = free_body(
        attitude={"formulation": "quaternion"},
        output={"times": {"start": "0", "stop": "2000", "count": 201}},
    )
    scene = ch.Scene.from_dict(data)
    estimates = []
    real = span_probe.SpanProbe.after
    monkeypatch.setattr(
        span_probe.SpanProbe, "after", lambda self, *a: estimates.append(a) or real(self, *a)
    )
    first = ch.run(scene)
    probed = len(estimates)
    again = ch.run(scene)
    assert probed >= 1 and len(estimates) == probed
    assert first.counters == again.counters
    _same(first, again)
    data["integrator"] = {"max_steps": 1000}
    data["output"] = {"times": {"start": "0", "stop": "1e9", "count": 2}}
    refused = ch.Scene.from_dict(data)
    for _ in range(2):
        with pytest.raises(SceneError, match="output.times: the span to t = 1e9 needs about"):
            ch.run(refused)


@pytest.mark.parametrize("terminal", [False, True])
def test_a_run_well_inside_its_budget_pays_only_the_short_probe(monkeypatch, terminal):
    """The estimate's first probe is short (16 steps), so a run pays a few steps for it; the
    longer probe (1000 steps) is taken only when the short one's estimate is not clearly
    within the budget — here a budget of a few times the run's steps."""
    data = free_body(
        attitude={"formulation": "rodrigues" if terminal else "quaternion"},
        output={"times": {"start": "0", "stop": "1000", "count": 101}},
    )
    cuts: list[int] = []
    restart = engine.Propagation._restart

    def counted(self):
        cuts.append(1)
        return restart(self)

    monkeypatch.setattr(engine.Propagation, "_restart", counted)
    whole = ch.run(ch.Scene.from_dict(data))
    assert whole.counters["steps"] > 1000 and len(cuts) == 1
    cuts.clear()
    data["integrator"] = {"max_steps": 3 * whole.counters["steps"]}
    tight = ch.run(ch.Scene.from_dict(data))
    assert len(cuts) == 2
    assert tight.counters == whole.counters
    _same(tight, whole)


def test_a_signal_stops_a_run_without_progress_bar_or_terminal_events(tmp_path):
    """The watch alone (no progress callback, and no terminal event returning to Python
    between calls) must let Python note the signal: a run of minutes ends within seconds."""
    scene = tmp_path / "long.toml"
    scene.write_text(
        "[body]\ninertia = [1, 2, 3]\n[initial]\nrates = [0.75, -0.5, 0.625]\n"
        'quaternion = [1, 0, 0, 0]\n[attitude]\nformulation = "quaternion"\n'
        "[output]\ntimes = { start = 0, stop = 1e8, count = 101 }\n"
    )
    out = tmp_path / "r.h5"
    cmd = [sys.executable, "-m", "cayley_heyoka.cli", "run", str(scene), "--out", str(out)]
    # A signal during start-up or compilation ends the process at once (nothing was computed,
    # by design); on a loaded machine that can outlast the wait, so wait longer.
    for wait in (4, 12, 30):
        proc = subprocess.Popen(cmd + ["--no-progress"], stderr=subprocess.PIPE, text=True)
        time.sleep(wait)
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=20)
        finally:
            proc.kill()
        if "nothing was computed" not in err:
            break
    assert proc.returncode == 130, err
    assert "interrupted (SIGINT)" in err
    assert "interrupted" in ch.load_result(out).message


@pytest.mark.parametrize(
    "build",
    [lambda: _scene("double"), lambda: _scene("quad"), lambda: _orbit("cayley")],
    ids=["heavy-top-double", "heavy-top-quad", "orbit-cayley"],
)
def test_a_reused_integrator_gives_the_bits_of_a_fresh_copy(build):
    """Runs hand their integrator back for the next run of the structure (reset, not copied):
    a run on a reused integrator — after a run that stopped midway on its step budget, with
    events recorded and chart re-basings or revolutions handled — has the bits, events and
    counters of a run on a fresh copy of the template."""
    scene = build()
    compiled = engine.Propagation(scene).compiled
    compiled.spare.clear()
    fresh = ch.run(scene)  # on a copy of the template (no spare yet)
    budget = fresh.counters["steps"] // 3
    stopped = scene.to_dict()
    stopped["integrator"] = {**stopped.get("integrator", {}), "max_steps": budget}
    with pytest.raises(IntegrationError):
        ch.run(ch.Scene.from_dict(stopped))
    assert len(compiled.spare) == 1  # the stopped run's integrator, handed back
    again = ch.run(scene)
    assert again.counters == fresh.counters and fresh.counters["steps"] > 50
    _same(again, fresh)
    assert fresh.events and set(again.events) == set(fresh.events)
    for name, log in fresh.events.items():
        prec = fresh.precision
        assert np.array_equal(prec.to_text(log.time), prec.to_text(again.events[name].time))


def test_an_integrator_handed_back_keeps_no_reference_to_its_run():
    """Terminal events are handled by callbacks pointed at the run using the integrator; one
    handed back for reuse points nowhere (it would otherwise keep the run and its rows)."""
    scene = ch.Scene.from_dict(free_body(attitude={"formulation": "rodrigues"}))
    result = ch.run(scene)
    assert result.counters["rebasings"] > 0
    compiled, cached = compiler.compile_model(engine.model_of(scene), scene.integrator)
    assert cached and compiled.spare
    for ta in compiled.spare:
        assert all(ev.callback.target is None for ev in ta.t_events)
    assert all(ev.callback.target is None for ev in compiled.integrator.t_events)


@pytest.mark.parametrize("stop", ["40", "4000"])
def test_progress_reports_each_kept_step_once_in_order(stop):
    """The first call may be cut after its first steps and taken again (the span estimate):
    its progress is held until its steps are kept, so the times reported never go back and
    there is one per step — for a run shorter than that first call (89 steps) and longer
    (~8900)."""
    times: list[float] = []
    result = ch.run(
        _scene(output={"times": {"start": "0", "stop": stop, "count": 81}}), progress=times.append
    )
    assert len(times) == result.counters["steps"]
    assert np.all(np.diff(times) > 0) and times[-1] == float(stop)


def test_a_scene_refused_at_its_start_is_refused_at_every_run():
    """A scene's checks are kept with its model once they pass: one that fails is run again
    and refused again, never taken for checked."""
    scene = ch.Scene.from_dict(
        free_body(
            monitors={"spike": {"expression": "1/t"}},
            output={"times": {"start": "0", "stop": "1", "count": 3}},
        )
    )
    for _ in range(2):
        with pytest.raises(SceneError, match="spike"):
            ch.run(scene)


@pytest.mark.parametrize("mine", ["handler", "ignored"])
def test_a_run_gives_back_the_callers_own_signal_handler(mine):
    """The run's handlers are swapped in and out at C level: the caller's Python handler, or
    an ignored SIGINT, is what stands after the run."""
    own = (lambda signum, frame: None) if mine == "handler" else signal.SIG_IGN
    old = signal.signal(signal.SIGINT, own)
    try:
        ch.run(ch.Scene.from_dict(free_body()))
        assert signal.getsignal(signal.SIGINT) is own
    finally:
        signal.signal(signal.SIGINT, old)
