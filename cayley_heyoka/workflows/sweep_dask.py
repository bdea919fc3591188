"""The Dask backend of sweeps: chunks of members as tasks, gathered into one file.

Each task runs :func:`.members.propagate_members` on a chunk of members in a worker process,
the same code as the local backend, so the two give identical arrays. A worker compiles each
model structure once (the engine's in-memory cache lives as long as the worker process, and
heyoka's disk cache serves the next process); its chunks then cost a copy of the compiled
integrator per member. Chunks are written to the sweep file as they complete.

Without a scheduler address a ``distributed.LocalCluster`` of ``workers`` processes (one
thread each: heyoka releases the GIL, but a process per worker also keeps the Python parts,
building the members' models and evaluating monitors, in parallel) is started and closed.
With one (``[run] scheduler = "tcp://host:8786"`` or ``--scheduler``) the cluster's workers,
which must have cayley_heyoka installed, run the tasks.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from typing import Any

from .members import propagate_members, reason, split
from .study import DEFAULT_CHUNK, Member, RunOptions, Study
from .sweep_result import Chunk, Layout

#: Seconds to wait for a scheduler to answer and for its first worker to join.
CONNECT_TIMEOUT = 60


def propagate(
    study: Study,
    members: Sequence[Member],
    layout: Layout,
    run: RunOptions,
    take: Callable[[Chunk], None],
) -> dict[str, Any]:
    """Integrate ``members`` on a Dask cluster, handing each chunk to ``take`` as it completes.

    Parameters
    ----------
    study, members, layout
        As for :func:`.members.propagate_members`.
    run
        ``scheduler`` (None: a LocalCluster of ``workers`` processes), ``chunk``.
    take
        Called in this process with every chunk's rows (a task that raised, a worker lost
        with its task, gives its members marked failed with the reason).

    Returns
    -------
    dict
        For the file's metadata: the cluster, its workers, the chunk size.

    Raises
    ------
    RuntimeError
        dask.distributed is not installed, or the scheduler cannot be reached or has no
        workers.
    """
    try:
        import distributed
    except ImportError:
        raise RuntimeError(
            "the dask backend needs dask.distributed: python -m pip install "
            "'cayley_heyoka[dask]' (or 'dask[distributed]')"
        ) from None

    cluster = None
    if run.scheduler:
        try:
            client = distributed.Client(run.scheduler, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError) as exc:
            raise RuntimeError(
                f"cannot reach the Dask scheduler at {run.scheduler}: {exc}"
            ) from None
        where = f"scheduler {run.scheduler}"
    else:
        n = run.workers or os.cpu_count() or 1
        cluster = distributed.LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = distributed.Client(cluster)
        where = "LocalCluster"
    try:
        try:
            client.wait_for_workers(1, timeout=CONNECT_TIMEOUT)
        except TimeoutError:
            raise RuntimeError(
                f"the Dask {where} has no workers after {CONNECT_TIMEOUT} s"
            ) from None
        workers = len(client.scheduler_info()["workers"])
        # Several tasks per worker, so that a slow chunk does not leave the others idle.
        chunk = run.chunk or max(1, min(DEFAULT_CHUNK, math.ceil(len(members) / (4 * workers))))
        parts = list(split(list(members), chunk))
        futures = {
            client.submit(propagate_members, study, part, layout, 1, pure=False): part
            for part in parts
        }
        prec = study.precision
        for future in distributed.as_completed(futures):
            part = futures[future]
            try:
                rows = future.result()
            except Exception as exc:  # a task's failure marks its members, not the sweep
                rows = Chunk.failed(part, layout, prec, f"the Dask task failed: {reason(exc)}")
            take(rows)
            future.release()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return {"cluster": where, "workers": workers, "chunk": chunk}
