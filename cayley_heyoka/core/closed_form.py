"""A scene's closed form, as a family offers it (``Family.closed_form``): evaluated as a
reference solution at the scene's output times, or compared with a run (its certificate).

A family subclasses :class:`ClosedForm` with ``_job`` (what the worker processes of
:func:`cayley_heyoka.core.evaluation.evaluate` compute), ``certificate`` and, where the scene
records events the closed form also gives, ``_events``.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from .certificate import Certificate, worst, written
from .precision import Precision
from .scene import Scene


def with_precision(scene: Scene, prec: Precision, tolerance: Any = None) -> Scene:
    """``scene`` in ``prec`` with ``tolerance`` (None: ``"auto"``, the precision's epsilon),
    every other option kept and checked as the scene's own fields are: the one way a
    reference, a closed form's job and the planner's routes change a scene's precision.

    Raises
    ------
    OptionError
        A number or the tolerance that ``prec`` cannot take, naming ``precision`` or
        ``tolerance`` (:class:`~cayley_heyoka.core.errors.OptionError`).
    """
    return scene.derive(
        {
            "integrator.precision": prec.to_spec(),
            "integrator.tolerance": "auto" if tolerance is None else tolerance,
        },
        options={"integrator.precision": "precision", "integrator.tolerance": "tolerance"},
    )


class ClosedForm:
    """A scene's closed form: evaluated as the reference, or compared with a run."""

    name = ""
    #: The family's evaluation proves its bounds (ball arithmetic) rather than estimating them.
    proved = False

    def __init__(self, scene: Scene) -> None:
        self.scene = scene

    def certificate(self, result: Any, digits: int) -> Certificate:
        raise NotImplementedError

    def job(self, prec: Precision) -> Any:
        """What workers evaluate to write the scene's outputs in ``prec`` (None: it cannot).

        The names come from the model the integration would build, so that the file holds
        every output variable and monitor the integrated run would write, and nothing else.
        """
        from .structures import model_for

        variant = with_precision(self.scene, prec, None)
        model = model_for(variant)
        grid = variant.time_grid
        return self._job(variant, model, prec, prec.to_text(grid[:1])[0])

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        raise NotImplementedError

    @staticmethod
    def _outputs(model: Any, job: Any, events: tuple[str, ...] = ()) -> tuple[tuple, tuple] | None:
        """The model's output variables and monitors when the closed form (its ``job`` class's
        ``VARIABLES`` and ``MONITORS``) gives every one of them and the model records only the
        ``events`` it also gives; None otherwise."""
        variables, monitors = tuple(model.outputs), tuple(model.monitors)
        if (
            set(variables) <= set(job.VARIABLES)
            and set(monitors) <= set(job.MONITORS)
            and all(e.name in events for e in model.events)
        ):
            return variables, monitors
        return None

    def evaluate(
        self, prec: Precision, workers: int | None, progress: Any, store: Path | None = None
    ) -> tuple[Any, Certificate, int]:
        """The scene's outputs in ``prec`` from the closed form, their certificate, and the
        number of chunks read back from ``store`` (see :func:`.reference.evaluate.evaluate`)."""
        from .evaluation import evaluate
        from .result import Result, versions
        from .structures import model_for

        wall = time.perf_counter()
        variant = with_precision(self.scene, prec, None)
        model = model_for(variant)
        grid = variant.time_grid
        texts = list(prec.to_text(grid))
        job = self._job(variant, model, prec, texts[0])
        tick = None
        if progress is not None:
            tick = lambda done: progress("closed form", grid[done - 1])  # noqa: E731
        rows, (events, event_errors), resumed = evaluate(
            job, texts, workers, tick, lambda: self._events(job, model, prec, grid), store
        )
        variables = {
            n: prec.from_text(np.array([v[n] for v, _ in rows], dtype=object))
            for n in job.variables
        }
        monitors = {
            n: prec.from_text(np.array([v[n] for v, _ in rows], dtype=object)) for n in job.monitors
        }
        result = Result(
            t=grid,
            variables=variables,
            monitors=monitors,
            conserved=model.conserved,
            events=events,
            precision=prec,
            message="every output time was reached (closed form)",
            scene=variant.to_dict(),
            metadata={**versions(), "wall_seconds": time.perf_counter() - wall},
        )
        # Every variable and monitor written has its error: the job gives both.
        names = (*job.variables, *job.monitors)
        errors = {n: np.array([e[n] for _, e in rows], dtype=float) for n in names}
        cert = Certificate("closed form", self.name, errors, event_errors, self.proved)
        return result, worst(cert, written(result), np.asarray(grid, dtype=float)), resumed

    def _events(self, job: Any, model: Any, prec: Precision, grid: np.ndarray) -> tuple[dict, dict]:
        return {}, {}
