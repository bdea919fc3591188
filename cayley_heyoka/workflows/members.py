"""How the members of a sweep are integrated, on one machine (:func:`propagate_members`):

* members are grouped by compiled structure (scenes differing only in numbers share code);
* in double precision a group goes through heyoka's batch integrators in SIMD lanes, one per
  thread (:mod:`cayley_heyoka.core.lanes`, which ``propagate_ensemble`` shares), terminal
  events included (the Rodrigues chart's re-basing, the orbit's revolution count and
  equatorial stop, Encke's rectification: each member's handler acts on its lane): the steps,
  events and counts of :func:`cayley_heyoka.run`, its states to a few ulps;
* in quad or multiprecision, a group without terminal events goes through heyoka's ensemble
  propagation (``heyoka.ensemble_propagate_grid``, threads), each member's state, parameters and
  start time set on a copy of the compiled integrator (run()'s bits); one with terminal events
  through :func:`cayley_heyoka.run`, since their handlers cannot run inside heyoka's ensemble;
* monitors are evaluated from the recorded states
  (:func:`cayley_heyoka.core.recording.evaluate_outputs`).

The local backend (:func:`cayley_heyoka.workflows.sweep.run_sweep`) and the Dask backend
(:mod:`.sweep_dask`) both run :func:`propagate_members` on chunks of members.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.errors import IntegrationError
from ..core.precision import Precision
from ..core.scene import Scene
from .study import (
    Member,
    Study,
)
from .sweep_result import (
    FAILED,
    OK,
    Chunk,
    Layout,
    nan_final,
)

#: How a member was integrated (the counts by path are in the file's metadata).
PATH_LANES = "cayley_heyoka.core.lanes"
PATH_ENSEMBLE = "heyoka.ensemble_propagate_grid"
PATH_RUN = "cayley_heyoka.run"


# ---------------------------------------------------------------------- running
def propagate_members(
    study: Study,
    members: Sequence[Member],
    layout: Layout,
    threads: int = 1,
    scenes: Sequence[Scene] | None = None,
) -> Chunk:
    """Integrate some members of a study on this machine (the local path, run by each Dask
    task too).

    Parameters
    ----------
    study
        The study.
    members
        ``(index, values)`` pairs: the member's index in the study and its parameter values.
    layout
        The columns to fill (:func:`layout_of`).
    threads
        Threads for heyoka's ensemble propagation and for the members run one by one.
    scenes
        The members' validated scenes, if the caller has them (else validated here).

    Returns
    -------
    Chunk
        The members' rows. A member that fails (a non-finite state, a stop before the last
        output time, a model that cannot be built) is marked ``FAILED`` with the reason; the
        others are unaffected.
    """
    prepared = prepare_members(study, members, layout, scenes)
    return integrate_members(prepared, layout, study.precision, threads)


@dataclass
class Entry:
    """A member of a :class:`Group`: its row in the chunk, its numbers (initial state and whole
    parameter vector, in the study's precision) and its validated scene, made when asked for
    (a member integrated by ``run()``)."""

    row: int
    initial: Sequence[Any]
    pars: Sequence[Any]
    scene: Callable[[], Scene]


@dataclass
class Group:
    """Members sharing compiled code: the first one's scene and model (the structure, the
    options, the output times) and every member's numbers."""

    scene: Scene
    model: Any
    entries: list[Entry] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.entries)


#: A chunk's rows and its members grouped by compiled structure.
Prepared = tuple[Chunk, dict[str, Group]]


#: Members tried, in order, for the one whose scene and model the table starts from.
TEMPLATE_TRIES = 8


@dataclass(frozen=True)
class Tabled:
    """Members of one structure whose numbers its family computed at once
    (:func:`cayley_heyoka.core.structures.table_for`): the scene and model of the first member
    that has one, and the table (a suspect row is validated and built alone)."""

    scene: Scene
    model: Any
    table: Any

    def rows(self, lo: int, hi: int) -> Tabled:
        """The members ``lo`` to ``hi`` (excluded) of this table."""
        t = self.table
        part = type(t)(t.initial[lo:hi], t.pars[lo:hi], t.suspect[lo:hi])
        return Tabled(self.scene, self.model, part)


def tabulate(study: Study, members: Sequence[Member]) -> Tabled | None:
    """The members' numbers as arrays, where their family computes them at once (double
    precision, swept fields it knows); None: validate and build each member."""
    from ..core.structures import model_for, table_for

    if study.precision.kind != "double":
        return None
    for member in members[:TEMPLATE_TRIES]:
        try:
            scene = study.member_scene(*member)
            model = model_for(scene)
            break
        except Exception:  # that member alone says why, as it would without a table
            continue
    else:
        return None
    template = members.index(member)
    table = table_for(
        scene,
        model,
        [p.path for p in study.parameters],
        [values for _, values in members],
        lambda k: scene if k == template else study.member_scene(*members[k]),
    )
    return None if table is None else Tabled(scene, model, table)


def prepare_members(
    study: Study,
    members: Sequence[Member],
    layout: Layout,
    scenes: Sequence[Scene] | None = None,
    tabled: Tabled | None = None,
) -> Prepared:
    """The first half of :func:`propagate_members`: each member's numbers, grouped by compiled
    structure (Python work, run while the previous chunk integrates) — from its family's table
    where it has one (``tabled`` if the caller has it, else :func:`tabulate`), else from the
    member's scene and model."""
    from ..core.structures import model_for

    prec = study.precision
    n = len(members)
    part = Chunk(
        index=np.array([i for i, _ in members], dtype=np.int64),
        status=np.full(n, FAILED),
        message=[""] * n,
        steps=np.zeros(n, dtype=np.int64),
        drift={k: np.full((n, layout.n_times), np.nan) for k in layout.drift},
        final=nan_final(n, len(layout.final), prec),
        events={k: np.zeros(n, dtype=np.int64) for k in layout.events},
    )
    groups: dict[str, Group] = {}
    alone = range(n)
    if tabled is None and scenes is None:
        tabled = tabulate(study, members)
    if tabled is not None:
        table = tabled.table
        group = groups[_group_key(tabled.model, tabled.scene)] = Group(tabled.scene, tabled.model)
        for row in np.flatnonzero(~table.suspect).tolist():
            member = members[row]
            group.entries.append(
                Entry(row, table.initial[row], table.pars[row], _later(study, member))
            )
        alone = np.flatnonzero(table.suspect).tolist()
    for row in alone:
        index, values = members[row]
        try:
            scene = scenes[row] if scenes is not None else study.member_scene(index, values)
            model = model_for(scene)
        except Exception as exc:  # one member's bad numbers must not end the sweep
            part.message[row] = reason(exc)
            continue
        key = _group_key(model, scene)
        if key not in groups:
            groups[key] = Group(scene, model)
        entry = Entry(row, model.initial_state, model.pars.values, lambda scene=scene: scene)
        groups[key].entries.append(entry)
    for group in groups.values():
        group.entries.sort(key=lambda e: e.row)
    return part, groups


def _later(study: Study, member: Member) -> Callable[[], Scene]:
    return lambda: study.member_scene(*member)


def integrate_members(
    prepared: Prepared,
    layout: Layout,
    prec: Precision,
    threads: int = 1,
    cancel: threading.Event | None = None,
) -> Chunk:
    """The second half of :func:`propagate_members`: integrate the groups and fill the rows.

    ``cancel``, once set, ends the lanes (within a step if a
    :class:`~cayley_heyoka.core.signals.Cancel`); the chunk is then incomplete: the caller
    drops it.
    """
    part, groups = prepared
    for group in groups.values():
        terminal = group.model.terminal
        if prec.kind == "double":
            handed = _lanes_group(group, part, layout, prec, threads, cancel)
            for path, count in ((PATH_RUN, handed), (PATH_LANES, len(group) - handed)):
                if count:
                    part.paths[path] = part.paths.get(path, 0) + count
            continue
        elif terminal:
            counters = ", ".join(t.counter for t in terminal)
            part.why[PATH_RUN] = f"{prec.name} with terminal events ({counters})"
            _run_group(group, part, layout, prec, threads)
            path = PATH_RUN
        else:
            part.why[PATH_ENSEMBLE] = f"{prec.name}: heyoka's batch integrators are double only"
            _ensemble_group(group, part, layout, prec, threads)
            path = PATH_ENSEMBLE
        part.paths[path] = part.paths.get(path, 0) + len(group)
    return part


# ---------------------------------------------------------------------- internals: running
def split(items: list, size: int) -> Iterator[list]:
    for lo in range(0, len(items), size):
        yield items[lo : lo + size]


def _group_key(model: Any, scene: Scene) -> str:
    from ..core.compiler import cache_key

    # A step cap and the step budget are runtime arguments shared by one batch call.
    options = scene.integrator
    return f"{cache_key(model, options)}/{options.max_step}/{options.max_steps}"


def reason(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}"


def _one(values: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """One member's outputs and monitors as a block of one (:func:`_record_block`)."""
    return {k: np.asarray(v)[None] for k, v in values.items()}


def _record_block(
    part: Chunk,
    rows: np.ndarray,
    layout: Layout,
    prec: Precision,
    values: Mapping[str, np.ndarray],
    conserved: Sequence[str],
    complete: bool,
) -> None:
    """Fill the drifts and final values of the members at ``rows`` from their outputs and
    monitors, each ``(members, times[, components])`` (members that reached as many times)."""
    from ..core.result import relative_drift

    reached = next(iter(values.values())).shape[1] if values else 0
    for name in layout.drift:
        if name not in conserved or name not in values or reached == 0:
            continue
        m = values[name]
        d = np.abs(relative_drift(m, vector=m.ndim > 2))
        if d.ndim > 2:
            d = d.max(axis=2)
        part.drift[name][rows, :reached] = d.astype(np.float64)
    missing = [k for k in layout.drift if k not in conserved]
    if missing:
        note = f"; not conserved by this member's flow (drift NaN): {', '.join(missing)}"
        for row in rows:
            part.message[row] += note
    if not complete:
        return
    # An output a member's model does not have stays NaN (:func:`nan_final`).
    columns = [(j, values[k][:, -1]) for j, k in enumerate(layout.final) if k in values]
    if prec.kind == "double":
        for j, column in columns:
            part.final[rows, j] = np.asarray(column, dtype=np.float64)
    else:
        for j, column in columns:
            part.final[rows, j] = prec.to_text(prec.array(list(column)))


def _run_group(group: Group, part: Chunk, layout: Layout, prec: Precision, threads: int) -> None:
    """Members whose scenes have terminal events: one ``engine.run`` each."""
    from concurrent.futures import ThreadPoolExecutor

    from ..core import compiler, engine

    compiled, cached = compiler.compile_model(group.model, group.scene.integrator)  # once
    if not cached:
        part.compile_seconds += compiled.compile_seconds

    def one(entry: Entry) -> None:
        row = entry.row
        try:
            result = engine.run(entry.scene())
        except IntegrationError as exc:
            result = exc.result
        except Exception as exc:  # one member's failure must not end the sweep
            part.message[row] = reason(exc)
            return
        part.status[row] = OK if result.success else FAILED
        part.message[row] = result.message
        part.steps[row] = result.counters.get("steps", 0)
        for name in layout.events:
            log = result.events.get(name)
            part.events[name][row] = len(log) if log is not None else 0
        values = {**result.variables, **result.monitors}
        conserved = group.model.conserved
        _record_block(part, np.array([row]), layout, prec, _one(values), conserved, result.success)

    with ThreadPoolExecutor(max_workers=max(1, min(threads, len(group)))) as pool:
        list(pool.map(one, group.entries))


def _lanes_group(
    group: Group,
    part: Chunk,
    layout: Layout,
    prec: Precision,
    threads: int,
    cancel: threading.Event | None = None,
) -> int:
    """Members sharing compiled code, in double: batch lanes (each member's own terminal-event
    handlers acting on its lane). Returns how many were handed to ``run()`` instead (a
    hand-over to another variant of their model)."""
    from ..core import compiler, lanes, recording

    scene0, model0 = group.scene, group.model
    compiled, cached = compiler.compile_model(model0, scene0.integrator)  # the outputs' evaluator
    batch, batch_cached = lanes.compile_batch(model0, scene0.integrator)
    part.compile_seconds += (0 if cached else compiled.compile_seconds) + (
        0 if batch_cached else batch.compile_seconds
    )
    grid = scene0.time_grid
    entries = group.entries
    initial = np.array([np.asarray(e.initial, dtype=float) for e in entries])
    pars = np.array([np.asarray(e.pars, dtype=float) for e in entries])
    try:
        with compiler.quiet_heyoka():  # a member going non-finite is reported as such
            runs = lanes.integrate_lanes(
                model0,
                scene0.integrator,
                grid,
                initial,
                pars,
                threads,
                cancel,
            )
    except Exception as exc:  # the whole call failed: every member of the group is marked
        for e in entries:
            part.message[e.row] = reason(exc)
        return 0
    if cancel is not None and cancel.is_set():
        return 0  # the chunk is dropped
    handed = [e for e, run in zip(entries, runs, strict=True) if run.handover]
    if handed:
        # A member that reached another variant of its model (Cayley's orbit near the
        # reference plane) needs that variant's code, which its batch does not hold.
        part.why[PATH_RUN] = "a hand-over to another variant of the model (run() compiles it)"
        _run_group(Group(scene0, model0, handed), part, layout, prec, threads)
    kept = [(e, run) for e, run in zip(entries, runs, strict=True) if not run.handover]
    whole = [(item, run) for item, run in kept if run.status == 0 and len(run.states) == len(grid)]
    # The members that reached every output time, their outputs evaluated at once.
    bad = _record_whole(whole, part, layout, prec, compiled, model0, grid)
    recorded = {id(run) for _, run in whole}
    rest = [(e, run) for e, run in kept if id(run) not in recorded or e.row in bad]
    model = model0
    for e, run in rest:
        row = e.row
        reached = len(run.states)
        rows = run.pars if run.pars.ndim == 2 else np.repeat(run.pars[None, :], reached, axis=0)
        values = recording.evaluate_outputs(compiled, model, run.states, rows, grid[:reached])
        complete = run.status == 0
        part.message[row] = run.message
        if complete and (found := recording.first_nonfinite(model, values, grid)) is not None:
            # As a lone run would: the member stops at its first non-finite output.
            k, part.message[row] = found
            complete = False
            values = {n: v[:k] for n, v in values.items()}
        _lane_counts(part, row, layout, run)
        part.status[row] = OK if complete else FAILED
        _record_block(part, np.array([row]), layout, prec, _one(values), model.conserved, complete)
    return len(handed)


def _record_whole(
    whole: list, part: Chunk, layout: Layout, prec: Precision, compiled: Any, model: Any, grid
) -> set[int]:
    """Record the members of ``whole`` (``(Entry, LaneResult)`` pairs, every output
    time reached) together; returns the rows of those with a non-finite output, left to the
    caller (which records each up to its first)."""
    from ..core import recording

    if not whole:
        return set()
    m = len(whole)
    states = np.stack([run.states for _, run in whole])
    if all(run.pars.ndim == 1 for _, run in whole):
        pars = np.stack([run.pars for _, run in whole])
    else:  # terminal handlers changed some members' parameters: one vector per output time
        shape = (len(grid), whole[0][1].pars.shape[-1])
        pars = np.stack(
            [r.pars if r.pars.ndim == 2 else np.broadcast_to(r.pars, shape) for _, r in whole]
        )
    values = recording.evaluate_members(compiled, model, states, pars, grid)
    finite = np.ones(m, dtype=bool)
    for name, v in values.items():
        if name not in model.unbounded:
            finite &= np.all(np.isfinite(v.reshape(m, -1)), axis=1)
    rows = np.array([e.row for e, _ in whole])
    for e, run in whole:
        part.message[e.row] = run.message
        _lane_counts(part, e.row, layout, run)
    part.status[rows[finite]] = OK
    good = values if finite.all() else {k: v[finite] for k, v in values.items()}
    _record_block(part, rows[finite], layout, prec, good, model.conserved, True)
    return set(rows[~finite].tolist())


def _lane_counts(part: Chunk, row: int, layout: Layout, run: Any) -> None:
    """A member's steps and event counts from its lanes' result."""
    part.steps[row] = run.counters["steps"]
    for name in layout.events:
        log = run.events.get(name)
        part.events[name][row] = len(log) if log is not None else 0


def _ensemble_group(
    group: Group, part: Chunk, layout: Layout, prec: Precision, threads: int
) -> None:
    """Members sharing compiled code and without terminal events: heyoka's ensemble."""
    import heyoka as hy

    from ..core import compiler, outcomes, recording

    scene0, model = group.scene, group.model
    compiled, cached = compiler.compile_model(model, scene0.integrator)
    if not cached:
        part.compile_seconds += compiled.compile_seconds
    grid = scene0.time_grid
    held = len(compiled.integrator.pars)
    starts = [prec.array(e.initial) for e in group.entries]
    pars = [prec.array(e.pars) for e in group.entries]
    limit: dict[str, Any] = {"max_steps": scene0.integrator.max_steps}  # the step budget
    if scene0.integrator.max_step is not None:
        limit["max_delta_t"] = prec.number(scene0.integrator.max_step)

    def gen(ta: Any, i: int) -> Any:
        ta.time = grid[0]
        ta.state[:] = starts[i]
        ta.pars[:] = pars[i][:held]
        return ta

    try:
        runs = hy.ensemble_propagate_grid(
            compiled.integrator,
            grid,
            len(group),
            gen,
            algorithm="thread",
            max_workers=threads,
            **limit,
        )
    except Exception as exc:  # the whole call failed: every member of the group is marked
        for e in group.entries:
            part.message[e.row] = reason(exc)
        return
    for i, (entry, run) in enumerate(zip(group.entries, runs, strict=True)):
        row = entry.row
        member = outcomes.EnsembleRun.of(run)
        ta, states = member.integrator, member.states
        outcome, nsteps = member.ended.outcome, member.ended.steps
        reached = len(states)
        complete = outcome == hy.taylor_outcome.time_limit and reached == len(grid)
        if complete:
            part.status[row], part.message[row] = OK, "every output time was reached"
        else:
            # heyoka's time is NaN once the state is: name the last output time kept instead.
            kept = grid[reached - 1] if reached else grid[0]
            if member.ended.zero_step:
                part.message[row] = outcomes.zero_step_message(model, ta.time)
            elif outcome == hy.taylor_outcome.err_nf_state:
                part.message[row] = outcomes.nonfinite(kept)
            elif outcome == hy.taylor_outcome.step_limit:
                part.message[row] = outcomes.out_of_steps(scene0.integrator.max_steps, ta.time)
            else:
                part.message[row] = outcomes.other(outcome, ta.time)
        part.steps[row] = nsteps
        logs = recording.event_logs(model, ta, prec)
        for name in layout.events:
            part.events[name][row] = len(logs[name]) if name in logs else 0
        # Copies row by row: np.repeat aliases the limbs of heyoka's multiprecision dtype.
        rows = np.array([pars[i].copy() for _ in range(reached)]).reshape(reached, len(pars[i]))
        values = recording.evaluate_outputs(compiled, model, states, rows, grid[:reached])
        if complete and (bad := recording.first_nonfinite(model, values, grid)) is not None:
            # As a lone run would: the member stops at its first non-finite output.
            k, part.message[row] = bad
            part.status[row], complete = FAILED, False
            values = {n: v[:k] for n, v in values.items()}
        _record_block(part, np.array([row]), layout, prec, _one(values), model.conserved, complete)
