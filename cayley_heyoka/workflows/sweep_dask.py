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
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ..core.errors import SceneError
from .members import propagate_members, reason, split
from .study import DEFAULT_CHUNK, Member, RunOptions, Study
from .sweep_result import Chunk, Layout

#: Seconds to wait for a scheduler to answer and for its first worker to join; a scheduler
#: that does neither within it is refused.
CONNECT_TIMEOUT = 60


@dataclass
class Cluster:
    """A Dask client with its workers, and the LocalCluster it started (None: a scheduler's)."""

    client: Any
    local: Any
    where: str

    def close(self) -> None:
        self.client.close()
        if self.local is not None:
            self.local.close()


def connect(run: RunOptions) -> Cluster:
    """The cluster of ``run``, with at least one worker, before anything is integrated or written.

    Raises
    ------
    SceneError
        Naming ``run.scheduler`` (or ``--scheduler``): the scheduler does not answer within
        :data:`CONNECT_TIMEOUT` (a port that accepts and stays silent included), or has no
        worker by then.
    RuntimeError
        dask.distributed is not installed.
    """
    try:
        import distributed
    except ImportError:
        raise RuntimeError(
            "the dask backend needs dask.distributed: python -m pip install "
            "'cayley_heyoka[dask]' (or 'dask[distributed]')"
        ) from None
    seconds = CONNECT_TIMEOUT
    if run.scheduler:
        field, where = run.scheduler_field, f"scheduler {run.scheduler}"
        # distributed's own timeout does not cover its handshake: a listener that accepts and
        # never answers would hold Client() for ever. Ask first, with a deadline of our own.
        _answers(run.scheduler, seconds, field)
        try:
            client = distributed.Client(run.scheduler, timeout=seconds)
        except (OSError, TimeoutError) as exc:
            raise SceneError(field, f"cannot reach the Dask scheduler: {exc}") from None
        local = None
    else:
        field, where = "run.backend", "LocalCluster"
        # Still before any work: a signal while it starts ends this process at once, and
        # its worker processes end with it (a KeyboardInterrupt inside its start-up would
        # leave distributed's AssertionError tracebacks).
        n = run.workers or os.cpu_count() or 1
        local = distributed.LocalCluster(
            n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = distributed.Client(local)
    cluster = Cluster(client, local, where)
    try:
        client.wait_for_workers(1, timeout=seconds)
    except TimeoutError:
        cluster.close()
        raise SceneError(field, f"the Dask {where} has no workers after {seconds} s") from None
    except BaseException:
        cluster.close()
        raise
    return cluster


def _answers(address: str, seconds: float, field: str) -> None:
    """Return once the scheduler at ``address`` answers a request, or refuse it after
    ``seconds``.

    The request runs in an event loop of its own, in a daemon thread: the main thread waits
    where a signal reaches it, and a scheduler that never answers is left behind.
    """
    import asyncio

    from distributed.comm import connect as open_comm

    async def identity() -> None:
        comm = await open_comm(address, timeout=seconds)
        try:
            await comm.write({"op": "identity", "reply": True})
            await comm.read()
        finally:
            comm.abort()

    box: dict[str, BaseException] = {}

    def ask() -> None:
        try:
            asyncio.run(asyncio.wait_for(identity(), seconds))
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc

    asker = threading.Thread(target=ask, name="cayley_heyoka-dask-connect", daemon=True)
    asker.start()
    asker.join(seconds + 5)  # the asker's own deadline ends it first
    error = box.get("error")
    why = None
    if asker.is_alive() or isinstance(error, TimeoutError):
        why = f"no answer within {seconds} s (is a Dask scheduler running there?)"
    elif error is not None:
        why = str(error)  # distributed's, e.g. its own timeout: nothing listening
    if why is not None:
        raise SceneError(field, f"cannot reach the Dask scheduler at {address}: {why}")


def propagate(
    cluster: Cluster,
    study: Study,
    members: Sequence[Member],
    layout: Layout,
    run: RunOptions,
    take: Callable[[Chunk], None],
) -> dict[str, Any]:
    """Integrate ``members`` on a Dask cluster (:func:`connect`), handing each chunk to
    ``take`` as it completes.

    Parameters
    ----------
    cluster
        The client and its workers; closed by the caller.
    study, members, layout
        As for :func:`.members.propagate_members`.
    run
        ``chunk`` (None: a quarter of an even share per worker, at most 256).
    take
        Called in this process with every chunk's rows (a task that raised, a worker lost
        with its task, gives its members marked failed with the reason).

    Returns
    -------
    dict
        For the file's metadata: the cluster, its workers, the chunk size.
    """
    import distributed

    client = cluster.client
    workers = len(client.scheduler_info()["workers"])
    # Several tasks per worker, so that a slow chunk does not leave the others idle.
    chunk = run.chunk or max(1, min(DEFAULT_CHUNK, math.ceil(len(members) / (4 * workers))))
    parts = list(split(list(members), chunk))
    futures = {
        client.submit(propagate_members, study, part, layout, 1, pure=False): part for part in parts
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
    return {"cluster": cluster.where, "workers": workers, "chunk": chunk}
