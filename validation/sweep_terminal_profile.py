"""Where a sweep of members with terminal events spends its time, beside the hand-written floor.

Run:  python validation/sweep_terminal_profile.py [--members N] [--top K]

The two studies of users_engine.py's terminal rows (Cayley's orbit with ρ's revolutions; a
free body in a Rodrigues chart with its re-basings). For each:

* the phases of ``run_sweep``'s local path, each timed alone on one thread in CPU seconds
  (``time.process_time``: the least and the median of a few, which other processes on a shared
  machine disturb less than wall time): the members' scenes (``Study.member_scene``), the
  file's columns (``layout_of``), their models (``prepare_members``), the lanes
  (``lanes.integrate_lanes``), and ``integrate_members`` (the lanes and the outputs' evaluation
  and recording), beside the whole ``run_sweep`` on one worker and the hand-written floor
  on one thread (users_engine.HandWrittenLanes);
* the time in the terminal events' callbacks, within heyoka's calls, per event: the lanes'
  (``_Lanes._on_terminal``: the member's handler on a view of its lane, and its bookkeeping) and
  the floor's hand-written ones, each wrapped in a timer for the measurement (one thread);
* a cProfile of the same work in the main thread on one thread (cProfile sees one thread
  only): scenes, ``prepare_members`` and ``integrate_members(threads=1)``, its top entries by
  own time and by cumulative time.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import pstats
import statistics
import time
from collections.abc import Callable

from users_engine import (
    TERMINAL_CASES,
    HandWrittenLanes,
    _LaneCharts,
    _LaneRevolutions,
    _our_lanes,
    terminal_study,
)

from cayley_heyoka.core import lanes
from cayley_heyoka.workflows.members import integrate_members, prepare_members
from cayley_heyoka.workflows.sweep import layout_of, run_sweep

REPEATS = 7


def _times(fn: Callable[[], object]) -> list[float]:
    fn()
    times = []
    for _ in range(REPEATS):
        t0 = time.process_time()
        fn()
        times.append(time.process_time() - t0)
    return times


def _callback_seconds(ours: Callable[[], object], floor: HandWrittenLanes) -> dict[str, float]:
    """Seconds a terminal event's callback takes, ours and the floor's (least of the repeats'
    means), each wrapped in a timer while measured."""
    spent = {"ours": 0.0, "floor": 0.0}
    calls = {"ours": 0, "floor": 0}

    def timed(side: str, fn: Callable[..., bool]) -> Callable[..., bool]:
        def call(*args: object) -> bool:
            t0 = time.perf_counter()
            try:
                return fn(*args)
            finally:
                spent[side] += time.perf_counter() - t0
                calls[side] += 1

        return call

    kept = lanes._Lanes._on_terminal
    floor_kept = {cls: cls.__call__ for cls in (_LaneRevolutions, _LaneCharts)}
    lanes._Lanes._on_terminal = timed("ours", kept)  # type: ignore[method-assign]
    for cls, fn in floor_kept.items():
        cls.__call__ = timed("floor", fn)  # type: ignore[method-assign]
    best = {"ours": float("inf"), "floor": float("inf")}
    try:
        for _ in range(REPEATS):
            for side, fn in (("ours", ours), ("floor", floor)):
                spent[side], calls[side] = 0.0, 0
                fn()
                best[side] = min(best[side], spent[side] / max(calls[side], 1))
    finally:
        lanes._Lanes._on_terminal = kept  # type: ignore[method-assign]
        for cls, fn in floor_kept.items():
            cls.__call__ = fn  # type: ignore[method-assign]
    return best


def _case(label: str, members: int, top: int) -> None:
    study = terminal_study(label, members)
    listed = list(enumerate(study.members()))
    model, initial, pars, _ = _our_lanes(study)
    scene0 = study.member_scene(*listed[0])
    grid = scene0.time_grid
    floor = HandWrittenLanes(model, initial, pars, grid, 1)
    layout = layout_of(study)
    scenes = [study.member_scene(i, v) for i, v in listed]
    prec = study.precision

    def lanes_phase() -> float:
        t0 = time.process_time()
        lanes.integrate_lanes(model, scene0.integrator, grid, initial, pars, 1)
        return time.process_time() - t0

    def members_phase() -> float:
        prepared = prepare_members(study, listed, layout)
        t0 = time.process_time()
        integrate_members(prepared, layout, prec, 1)
        return time.process_time() - t0

    phases = {
        "run_sweep (whole, 1 worker)": _times(lambda: run_sweep(study, workers=1)),
        "hand-written floor (1 thread)": _times(floor),
        "member scenes (validated)": _times(lambda: [study.member_scene(*m) for m in listed]),
        "layout_of": _times(lambda: layout_of(study)),
        "prepare_members (as the sweep: its table)": _times(
            lambda: prepare_members(study, listed, layout)
        ),
        "prepare_members (each member's model_for)": _times(
            lambda: prepare_members(study, listed, layout, scenes)
        ),
        "integrate_lanes": [lanes_phase() for _ in range(REPEATS)],
        "integrate_members (lanes + outputs)": [members_phase() for _ in range(REPEATS)],
    }
    print(f"## {label}: {members} members, one thread, CPU ms ({REPEATS} repeats)")
    print(f"  {'phase':40s} {'least':>8s} {'median':>8s}  least ÷ run_sweep's least")
    whole = min(phases["run_sweep (whole, 1 worker)"])
    for name, times in phases.items():
        least, median = min(times), statistics.median(times)
        print(f"  {name:40s} {least * 1e3:8.1f} {median * 1e3:8.1f}  {least / whole:5.1%}")

    def single() -> None:
        prepared = prepare_members(study, listed, layout)
        integrate_members(prepared, layout, prec, 1)

    terminal = [model.terminal] * len(listed)
    per_event = _callback_seconds(
        lambda: lanes.integrate_lanes(
            model, scene0.integrator, grid, initial, pars, 1, terminal=terminal
        ),
        floor,
    )
    print(
        f"  terminal callback, µs an event (least of {REPEATS} means): lanes "
        f"{per_event['ours'] * 1e6:.1f}, floor {per_event['floor'] * 1e6:.1f} "
        f"({per_event['ours'] / per_event['floor']:.1f}×)"
    )

    single()
    profile = cProfile.Profile()
    profile.enable()
    single()
    profile.disable()
    for key in ("tottime", "cumulative"):
        out = io.StringIO()
        pstats.Stats(profile, stream=out).sort_stats(key).print_stats(top)
        text = out.getvalue()
        start = text.find("   ncalls")
        print(f"\n### cProfile, one thread, by {key}\n")
        print(text[start:] if start >= 0 else text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=256)
    parser.add_argument("--top", type=int, default=25)
    args = parser.parse_args(argv)
    for label in TERMINAL_CASES:
        _case(label, args.members, args.top)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
