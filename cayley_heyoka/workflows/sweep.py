"""Conservation studies: one scene swept over a grid or a random ensemble of its numbers.

A *study file* (:mod:`.study`, which shows one) names a scene and the numbers to vary.
Every *member* is the scene with its numbers substituted exactly (a grid's values as decimal
text, so a quad study keeps exact inputs; a random draw as the double drawn), validated like
any scene, and integrated over the scene's own output times. The file written by
:func:`run_sweep` holds, for each member, the relative drift of each conserved monitor at every
output time, the final values of the result variables, the Taylor steps, the count of each
recorded event and whether it completed (layout: :class:`SweepResult` and
docs/tutorials/sweeps.md).

Members are integrated by :mod:`.members` (its docstring says how); the Dask backend
(:mod:`.sweep_dask`) runs the same code on chunks of members in worker processes and gathers
the chunks into the one file.
"""

from __future__ import annotations

import os
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..core.files import WriteFailed
from ..core.scene import Scene
from ..core.signals import Cancel, begin_work, held_signals
from . import sweep_dask
from .members import (
    Tabled,
    integrate_members,
    prepare_members,
    propagate_members,
    split,
    tabulate,
)
from .study import DEFAULT_CHUNK, Parameter, RunOptions, Study, load_study, override_run
from .sweep_result import (
    FAILED,
    NOT_RUN,
    OK,
    Chunk,
    Layout,
    SweepResult,
    empty_result,
    fill_chunk,
    load_sweep,
)

#: Most members whose validated scenes a local sweep keeps between validating and running.
_KEEP_SCENES = 2**16


Progress = Callable[[int, int], None]


#: Members tried for the file's columns before a study whose models cannot be built is refused.
LAYOUT_TRIES = 64


def layout_of(study: Study, first: tuple[Scene, Any] | None = None) -> Layout:
    """The file's columns, from the first member whose model builds (among the first
    :data:`LAYOUT_TRIES`: a member whose numbers its model refuses — a body at rest with
    invariable-plane events — fails alone, wherever it stands in the study), or from
    ``first``, that member's scene and model where the caller has them (a table's template).

    Raises
    ------
    SceneError
        No member among those has a model: the first one's refusal, naming the member.
    """
    from ..core.scene import check_units

    if first is not None:
        scene, model = first
    else:
        scene, model = _first_model(study)
    check_units(scene, [*model.outputs, *model.monitors])
    events = tuple(dict.fromkeys(e.name for e in model.events))
    grid = scene.time_grid
    return Layout(tuple(model.conserved), tuple(model.outputs), events, len(grid))


def _first_model(study: Study) -> tuple[Scene, Any]:
    from ..core.errors import SceneError
    from ..core.structures import model_for

    refused: SceneError | None = None
    for index, values in enumerate(study.members()[:LAYOUT_TRIES]):
        scene = study.member_scene(index, values)
        try:
            return scene, model_for(scene)
        except SceneError as exc:
            if refused is None:
                where = f"member {index} ({study.describe(values)}): {exc.field}"
                refused = SceneError(where, exc.constraint)
    raise refused if refused is not None else SceneError("sweep", "has no member")


def _validated(study: Study, indexed: list, keep: bool) -> tuple[list[Scene] | None, Tabled | None]:
    """Validate every member before anything runs (a member its scene refuses refuses the
    study, by name). Where the members' family computes their numbers at once
    (:func:`.members.tabulate`) only the members its table does not vouch for are validated
    one by one; otherwise each member's scene is, and the scenes are returned for the local
    backend (``keep``) when they fit in memory (~2.5 kB each), not validated a second time.
    Returns the scenes kept and the table."""
    tabled = tabulate(study, indexed)
    if tabled is not None:
        for k in np.flatnonzero(tabled.table.suspect).tolist():
            study.member_scene(*indexed[k])
        return None, tabled
    scenes: list[Scene] | None = [] if keep and len(indexed) <= _KEEP_SCENES else None
    for i, values in indexed:
        scene = study.member_scene(i, values)
        if scenes is not None:
            scenes.append(scene)
    return scenes, None


def _pipeline(
    study: Study,
    indexed: list,
    layout: Layout,
    threads: int,
    size: int,
    scenes: list[Scene] | None,
    tabled: Tabled | None,
    take: Callable[[Chunk], None],
) -> None:
    """Chunk by chunk, building the next chunk's models while the current one integrates:
    heyoka steps without the GIL, so the Python work of one overlaps the stepping of the other.
    An exception (Ctrl-C in ``take``'s progress) cancels the chunk in flight (dropped: its
    members stay NOT_RUN) within a step (:class:`~cayley_heyoka.core.signals.Cancel`)."""
    from concurrent.futures import ThreadPoolExecutor

    prec = study.precision
    cancel = Cancel()
    pending = None
    with ThreadPoolExecutor(max_workers=1) as pool:
        try:
            for part in split(indexed, size):
                lo, hi = part[0][0], part[-1][0] + 1
                given = scenes[lo:hi] if scenes is not None else None
                rows = tabled.rows(lo, hi) if tabled is not None else None
                prepared = prepare_members(study, part, layout, given, rows)
                if pending is not None:
                    take(pending.result())
                pending = pool.submit(integrate_members, prepared, layout, prec, threads, cancel)
            if pending is not None:
                take(pending.result())
        except BaseException:
            cancel.set()
            raise


def run_sweep(
    study: Study,
    *,
    out: str | Path | None = None,
    backend: str | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    chunk: int | None = None,
    progress: Progress | None = None,
) -> SweepResult:
    """Integrate every member of a study and gather the results (into one file).

    Parameters
    ----------
    study
        A validated study (:func:`load_study`).
    out
        The HDF5 sweep file, written (:func:`~cayley_heyoka.core.files.write_hdf5`) when the
        sweep ends: a sweep stopped midway (an interruption, a lost cluster) leaves a
        readable file with what it computed, its other members marked ``NOT_RUN`` and
        ``metadata["complete"]`` false. One stopped before any member ended writes nothing:
        a file already there stays as it was.
    backend, scheduler, workers, chunk
        Override the study's ``[run]`` table (see :class:`RunOptions`). ``chunk`` defaults to
        256 members locally and, on Dask, to a quarter of an even share per worker (at most
        256), so that every worker gets several tasks.
    progress
        Called with (members done, members) after each chunk.

    Returns
    -------
    SweepResult
        Every member's drifts, final state, steps, status.

    Raises
    ------
    TypeError
        ``study`` is not a :class:`~cayley_heyoka.workflows.study.Study`.
    SceneError
        A member whose scene is invalid (naming the member, its values and the field), bad
        run options, or a Dask scheduler that does not answer within
        :data:`.sweep_dask.CONNECT_TIMEOUT` or has no worker (naming ``run.scheduler``, or
        ``--scheduler`` for the ``scheduler`` argument); raised before anything is integrated
        or written.
    """
    if not isinstance(study, Study):
        # The same rule as run(scene): a validated object, never a dictionary parsed here.
        how = "Study.from_dict(d)" if isinstance(study, dict) else "load_study(path)"
        raise TypeError(f"study must be a Study (build it with {how}), got {type(study).__name__}")
    run = override_run(study.run, backend, scheduler, workers, chunk)
    members = study.members()
    indexed = list(enumerate(members))
    scenes, tabled = _validated(study, indexed, keep=run.backend == "local")
    layout = layout_of(study, (tabled.scene, tabled.model) if tabled is not None else None)
    prec = study.precision
    result = empty_result(study, members, layout, prec)
    # The cluster first: a scheduler that cannot be reached is refused before anything is
    # integrated or written.
    cluster = sweep_dask.connect(run) if run.backend == "dask" else None
    paths: Counter = Counter()
    why: dict[str, str] = {}
    compile_seconds = 0.0
    done = 0
    wall0 = time.perf_counter()
    info: dict[str, Any] = {"backend": run.backend}

    def take(part: Chunk) -> None:
        nonlocal compile_seconds, done
        # Something to keep from here on: a signal stops the sweep, which writes what it
        # computed (before, it ends the process at once: :mod:`~cayley_heyoka.core.signals`).
        begin_work()
        fill_chunk(result, part, prec)
        paths.update(part.paths)
        why.update(part.why)
        compile_seconds += part.compile_seconds
        done += len(part.index)
        if progress is not None:
            progress(done, len(members))

    stopped = None
    try:
        if run.backend == "local":
            threads = run.workers or os.cpu_count() or 1
            info["workers"] = threads
            size = run.chunk or DEFAULT_CHUNK
            info["chunk"] = size
            _pipeline(study, indexed, layout, threads, size, scenes, tabled, take)
        else:
            info.update(sweep_dask.propagate(cluster, study, indexed, layout, run, take))
    except BaseException as exc:
        stopped = f"{type(exc).__name__}: {exc}"
        raise
    finally:
        if cluster is not None:
            cluster.close()
        from ..core.result import versions

        # Also when the sweep stopped midway (a second Ctrl-C included): what it computed
        # is kept. A sweep that stopped before any member ended has nothing to keep: the
        # file already at ``out`` (a completed sweep, perhaps) stays as it was.
        with held_signals():
            result.metadata = {
                **versions(),
                **info,
                "wall_seconds": time.perf_counter() - wall0,
                "compile_seconds": compile_seconds,
                "paths": dict(paths),
                "why": why,
                "complete": stopped is None,
                "stopped": stopped,
            }
            if out is not None and done:
                try:
                    result.save(out)
                except WriteFailed as exc:
                    exc.result = result
                    raise
    return result


# The public names of a sweep, from the modules that hold them.
__all__ = [
    "FAILED",
    "NOT_RUN",
    "OK",
    "Layout",
    "Parameter",
    "RunOptions",
    "Study",
    "SweepResult",
    "load_study",
    "load_sweep",
    "propagate_members",
    "run_sweep",
]
