"""Certified reference solutions: ``cayley-heyoka reference SCENE.toml --digits 30 --out REF.h5``.

A reference solution is a scene's trajectory at its output times, written with an error
certificate: the estimated absolute error of every variable at every time. The cheapest
certified route is taken:

* **Closed form** (``method="auto"`` or ``"closed-form"``), where the scene has one — the
  torque-free body (:class:`~cayley_heyoka.reference.FreeRigidBody`, also its invariable-plane
  crossings) and Hamilton's projectile (:func:`~cayley_heyoka.reference.projectile_solution`):
  the closed form itself is the reference, evaluated at each output time in mpmath with its own
  certified error bound (two working precisions), in parallel over cores
  (:mod:`cayley_heyoka.workflows.closed_form`), and rounded once to the file's precision; the
  certificate is that rounding, measured exactly, plus the bound. Nothing is integrated.
* **Integration** (``method="integrate"``, or ``"auto"`` with a ``tolerance``, or
  ``"two-precisions"``), the independent check of the integrator and the only route where
  there is no closed form:

  1. *Precision.* The smallest of double, quad (``real128``) or MPFR ``real`` whose epsilon
     leaves :data:`GUARD_DIGITS` digits beyond the requested ones; the tolerance is that
     precision's epsilon (heyoka's default), unless given.
  2. *Certificate.* With a closed form (``"integrate"``) the run is compared with it.
     Otherwise the scene is integrated again at a higher precision (its epsilon as
     tolerance), independent in both round-off and truncation; the more precise run is
     written and the difference of the two is its certificate (an estimate of the less
     precise run's error, so a conservative one of the written run's).

Both routes escalate: if the certificate does not reach the requested digits (scaled errors:
absolute where |x| ≤ 1, relative above), the precision is raised and the work repeated, up to
``max_bits``; past that the file is written marked uncertified and the command exits 1.

Integrations go through :class:`~cayley_heyoka.workflows.checkpoint.CheckpointedRun` in a work
directory beside the output (``REF.h5.work``): an interrupted command, run again, continues
where it stopped and writes the same bits as an uninterrupted one. Once the file is written,
the files the runs wrote there are removed (and the directory, if nothing else is in it); a
``OUT.work`` that this command did not make (it carries the marker file :data:`WORK_MARKER`)
is refused, not touched. The closed-form route needs no work directory: it writes the file
at the end, whole or not at all (:func:`cayley_heyoka.core.files.write_hdf5`). Either way the file
is an ordinary result file (``cayley_heyoka.load_result``) with a ``certificate`` group and
the metadata needed to reproduce it (``metadata["reference"]``, whose ``method`` is
``"closed form"`` or ``"integration"``).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import platform
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..core.files import OutputError, check_destination, write_hdf5
from ..core.precision import Precision
from ..core.scene import Scene

#: Digits of working precision beyond those requested: room for the error a long run builds.
GUARD_DIGITS = 4
#: Largest precision the escalation goes to, unless told otherwise.
MAX_BITS = 1024
#: Stretches between checkpoints (each ends a step; the count is part of what the file records).
STRETCHES = 64
_BITS_PER_DIGIT = math.log2(10)
#: How the reference is made: "closed-form" evaluates the closed form; "integrate" integrates
#: and certifies against the closed form where there is one, else as "two-precisions" does;
#: "auto" is "closed-form" where the scene has one (and no tolerance is asked for), else an
#: integration.
METHODS = ("auto", "closed-form", "integrate", "two-precisions")
#: The file that marks a work directory as made by :func:`generate_reference`.
WORK_MARKER = ".cayley_heyoka-reference-work"


def precision_for(digits: float) -> Precision:
    """The cheapest precision with ``digits`` significant decimal digits."""
    bits = math.ceil(digits * _BITS_PER_DIGIT) + 1
    if bits <= 53:
        return Precision("double")
    if bits <= 113:
        return Precision("quad")
    return Precision("real", 32 * math.ceil(bits / 32))


def label(prec: Precision) -> str:
    """How a precision is named to people: heyoka's ``real128`` is IEEE quad, not MPFR."""
    names = {"double": "double", "quad": "quad (IEEE binary128)"}
    return names.get(prec.kind, f"MPFR {prec.bits} bits")


def next_precision(prec: Precision) -> Precision:
    """The next rung of the ladder: at least 32 more bits, or a quarter more."""
    if prec.kind == "double":
        return Precision("quad")
    bits = prec.bits + max(32, prec.bits // 4)
    return Precision("real", 32 * math.ceil(bits / 32))


@dataclass
class Certificate:
    """The error bound of a reference solution.

    Attributes
    ----------
    method
        ``"closed form"`` or ``"two precisions"``.
    compared_with
        What the solution was compared with (the closed form's name, or the other precision).
    errors
        Estimated absolute error of each variable at each output time.
    event_errors
        Estimated absolute error of each recorded event's times.
    scaled
        The largest error, absolute where |value| ≤ 1 and relative above.
    worst
        Where the largest scaled error is: ``(variable, time)``.
    """

    method: str
    compared_with: str
    errors: dict[str, np.ndarray]
    event_errors: dict[str, np.ndarray] = field(default_factory=dict)
    scaled: float = 0.0
    worst: tuple[str, float] = ("", 0.0)

    def digits(self) -> float:
        """Decimal digits certified: -log10 of the largest scaled error."""
        return math.inf if self.scaled == 0 else -math.log10(self.scaled)


@dataclass
class ReferenceOutcome:
    """What :func:`generate_reference` wrote."""

    path: Path
    certified: bool
    certificate: Certificate
    precision: Precision
    attempts: list[dict[str, Any]]


def generate_reference(
    scene: Scene,
    digits: int,
    out: str | Path,
    *,
    precision: Precision | None = None,
    tolerance: str | None = None,
    max_bits: int = MAX_BITS,
    stretches: int = STRETCHES,
    workdir: str | Path | None = None,
    keep_work: bool = False,
    overwrite: bool = False,
    method: str = "auto",
    progress: Any = None,
    report: Any = None,
    command: list[str] | None = None,
    workers: int | None = None,
) -> ReferenceOutcome:
    """Write the reference file of ``scene``, certified to ``digits`` digits.

    Parameters
    ----------
    scene
        The scene (its ``[integrator]`` precision and tolerance are replaced).
    digits
        Significant decimal digits to certify (scaled: absolute for |x| ≤ 1).
    out
        The HDF5 file to write.
    precision
        Start from this precision instead of the one chosen for ``digits`` (the closed form:
        write in it).
    tolerance
        heyoka's tolerance for the first run (decimal text); default: its precision's epsilon.
        Asks for an integration: with ``method="auto"`` the closed form is not taken.
    max_bits
        Give up raising the precision beyond this many bits.
    stretches
        Checkpoints per run (see :class:`~cayley_heyoka.workflows.checkpoint.CheckpointedRun`).
    workdir
        Where runs are checkpointed; default ``OUT.work`` beside ``out`` (integrations only).
    keep_work
        Keep the work directory after the file is written.
    overwrite
        Replace ``out`` even if it is not a result file of ours (see
        :func:`cayley_heyoka.core.files.check_destination`).
    method
        ``"auto"`` (the closed form where there is one and no ``tolerance`` is given, else an
        integration), ``"closed-form"`` (evaluate it), ``"integrate"`` (integrate, certified
        by the closed form where there is one, else by a second precision) or
        ``"two-precisions"``.
    progress
        ``progress(label, time)`` after each step of a run, or each chunk of closed-form
        evaluations; or None.
    report
        ``report(text)`` for one-line accounts of the plan and each run, or None.
    command
        The command line, for the file's metadata.
    workers
        Processes evaluating the closed form; default: every core. The file's values are
        the same bits whatever the count.

    Returns
    -------
    ReferenceOutcome
        ``certified`` is False when ``max_bits`` was reached first (the file is still written,
        marked so).

    Raises
    ------
    OutputError
        Before anything is integrated: ``out`` may not be written, or ``workdir`` exists and
        is not a work directory of this function.
    RuntimeError
        The closed form could not certify its own digits at some time (next to a singular
        configuration), or an integration stopped.
    """
    if isinstance(digits, bool) or not isinstance(digits, int) or digits < 1:
        raise ValueError(f"digits must be an integer >= 1, got {digits!r}")
    if max_bits < 53:
        raise ValueError(f"max_bits must be >= 53, got {max_bits}")
    if tolerance is not None and not _positive(tolerance):
        raise ValueError(f"tolerance must be a number > 0, got {tolerance!r}")
    from .checkpoint import check_count

    check_count(stretches)
    out = Path(out)
    workdir = Path(workdir) if workdir is not None else out.with_name(out.name + ".work")
    say = report or (lambda text: None)
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if workers is not None and (isinstance(workers, bool) or workers < 1):
        raise ValueError(f"workers must be an integer >= 1, got {workers!r}")
    closed = closed_form_for(scene) if method != "two-precisions" else None
    if method == "closed-form" and closed is None:
        raise ValueError(
            "method 'closed-form': this scene has none here (a torque-free body without user "
            "events, or Hamilton's projectile in canonical form); use 'two-precisions'"
        )
    if method == "closed-form" and tolerance is not None:
        raise ValueError("tolerance applies to an integration; the closed form integrates nothing")
    first = precision or precision_for(digits + GUARD_DIGITS)
    if first.bits > max_bits:
        raise ValueError(f"max_bits ({max_bits}) is below the precision needed ({label(first)})")
    evaluated = None
    if closed is not None and (method == "closed-form" or (method == "auto" and not tolerance)):
        evaluated = closed.job(first)
        if evaluated is None and method == "closed-form":
            raise ValueError(
                "method 'closed-form': the scene asks for outputs the closed form does not "
                "give (it gives the state, the attitude and the conserved monitors); use "
                "'integrate'"
            )
    check_destination(out, "result", overwrite=overwrite)
    _claim_workdir(workdir)
    if evaluated is not None:
        outcome = _closed_form_reference(
            scene, closed, digits, out, first, max_bits, workers, workdir, progress, say, command
        )
        if not keep_work:
            _remove_workdir(workdir)
        return outcome
    say(
        f"plan: {digits} digits; {label(first)} first; certificate "
        + (f"from the closed form ({closed.name})" if closed else "from a second precision")
    )
    started = time.perf_counter()
    attempts: list[dict[str, Any]] = []
    runs: dict[str, Any] = {}

    def integrate(prec: Precision, tol: str | None) -> Any:
        key = f"{prec.name}:{tol}"
        if key not in runs:
            from .checkpoint import CheckpointedRun

            variant = _with_precision(scene, prec, tol)
            where = workdir / f"run-{prec.name}" if tol is None else workdir / f"run-{prec.name}-t"
            job = CheckpointedRun(variant, where, stretches, _labelled(progress, prec.name))
            resumed = job.completed()
            t0 = time.perf_counter()
            result = job.run()
            note = f" (resumed after {resumed} of {stretches} stretches)" if resumed else ""
            say(
                f"run {label(prec)}: {result.counters.get('steps', 0)} steps, "
                f"{time.perf_counter() - t0:.2f} s{note}"
            )
            if not result.success:
                # What was computed is kept, as `run --out` keeps it; it certifies nothing.
                stopped = Certificate("none", "the run stopped", {}, scaled=math.inf)
                meta = {"command": command or [], "digits": digits, "certified": False}
                _write(out, result, stopped, digits, False, meta)
                raise RuntimeError(
                    f"the {label(prec)} run stopped: {result.message}; what it computed is in "
                    f"{out} (not certified)"
                )
            runs[key] = (result, where)
        return runs[key][0]

    prec, tol = first, tolerance
    while True:
        result = integrate(prec, tol)
        if closed is not None:
            written = result
            cert = closed.certificate(result, digits)
        else:
            check = next_precision(prec)
            if check.bits > max_bits:
                # No higher rung left to compare with: the last comparison stands.
                break
            written = integrate(check, None)
            cert = difference_certificate(written, result)
        attempts.append(
            {
                "precision": prec.name,
                "tolerance": tol or "epsilon",
                "compared_with": cert.compared_with,
                "scaled_error": cert.scaled,
                "worst": list(cert.worst),
            }
        )
        where = cert.worst[0]
        if math.isfinite(cert.worst[1]):  # an event's error is of its time, not at an output
            where += f" at t = {cert.worst[1]:.6g}"
        say(
            f"certificate: {cert.digits():.1f} digits (largest scaled error {cert.scaled:.2e} "
            f"in {where})"
        )
        if cert.scaled <= 10.0**-digits:
            break
        # Up one rung; with two precisions the more precise run becomes the one checked.
        prec, tol = (next_precision(prec) if closed else written.precision), None
        if (next_precision(prec) if closed is None else prec).bits > max_bits:
            break
        say(f"not enough: raising the precision to {label(prec)}")
    if not attempts:
        raise ValueError(f"max_bits ({max_bits}) leaves no higher precision to compare with")
    certified = attempts[-1]["scaled_error"] <= 10.0**-digits
    metadata = _metadata(
        scene,
        command,
        "integration",
        digits,
        certified,
        written.precision,
        attempts,
        max_bits,
        started,
        stretches=stretches,
    )
    _write(out, written, cert, digits, certified, metadata)
    if not keep_work:
        _remove_workdir(workdir)
    return ReferenceOutcome(out, certified, cert, written.precision, attempts)


def _closed_form_reference(
    scene: Scene,
    closed: _ClosedForm,
    digits: int,
    out: Path,
    prec: Precision,
    max_bits: int,
    workers: int | None,
    workdir: Path,
    progress: Any,
    say: Any,
    command: list[str] | None,
) -> ReferenceOutcome:
    """The closed-form route of :func:`generate_reference`: evaluate, certify, write."""
    from ..core.accuracy import PrecisionNotReached

    say(f"plan: {digits} digits; the closed form ({closed.name}) in {label(prec)}")
    started = time.perf_counter()
    attempts: list[dict[str, Any]] = []
    while True:
        t0 = time.perf_counter()
        try:
            result, cert, resumed = closed.evaluate(
                prec, workers, progress, workdir / f"closed-form-{prec.name}"
            )
        except PrecisionNotReached as exc:
            raise RuntimeError(f"the closed form cannot certify its digits: {exc}") from None
        attempts.append(
            {
                "precision": prec.name,
                "compared_with": cert.compared_with,
                "scaled_error": cert.scaled,
                "worst": list(cert.worst),
            }
        )
        note = f" (resumed after {resumed} chunks)" if resumed else ""
        say(
            f"closed form: {len(result.t)} times in {label(prec)}, "
            f"{time.perf_counter() - t0:.2f} s{note}; certificate: {cert.digits():.1f} digits "
            f"(largest scaled error {cert.scaled:.2e} in {cert.worst[0]} at "
            f"t = {cert.worst[1]:.6g})"
        )
        if cert.scaled <= 10.0**-digits or next_precision(prec).bits > max_bits:
            break
        prec = next_precision(prec)
        say(f"not enough: raising the precision to {label(prec)}")
    certified = cert.scaled <= 10.0**-digits
    metadata = _metadata(
        scene, command, "closed form", digits, certified, prec, attempts, max_bits, started
    )
    _write(out, result, cert, digits, certified, metadata)
    return ReferenceOutcome(out, certified, cert, prec, attempts)


# ---------------------------------------------------------------------- certificates
def _scaled(values: np.ndarray, errors: np.ndarray) -> np.ndarray:
    mag = np.abs(np.asarray(values, dtype=float))
    return errors / np.maximum(mag, 1.0)


def _worst(cert: Certificate, values: dict[str, np.ndarray], t: np.ndarray) -> Certificate:
    best = (0.0, "", 0.0)
    for name, err in cert.errors.items():
        s = _scaled(values[name], err)
        if s.size and np.max(s) > best[0]:
            k = int(np.argmax(s))
            best = (float(s[k]), name, float(t[k]))
    for name, err in cert.event_errors.items():
        if err.size and np.max(err) > best[0]:
            best = (float(np.max(err)), f"event {name}", math.nan)
    cert.scaled, cert.worst = best[0], (best[1], best[2])
    return cert


def difference_certificate(written: Any, other: Any) -> Certificate:
    """The certificate of ``written`` from a less precise run ``other`` of the same scene."""
    import mpmath

    errors = {}
    with mpmath.workdps(written.precision.dps + 5):
        for name, values in written.variables.items():
            errors[name] = _abs_difference(
                values, other.variables[name], written.precision, other.precision
            )
        event_errors = {}
        for name, log in written.events.items():
            theirs = other.events.get(name)
            if theirs is None or len(theirs) != len(log) or list(theirs.label) != list(log.label):
                raise RuntimeError(
                    f"event {name!r}: {len(log)} occurrences in {written.precision.name}, "
                    f"{0 if theirs is None else len(theirs)} in {other.precision.name} — the "
                    "runs disagree on an event (one grazing zero?): no certificate"
                )
            event_errors[name] = _abs_difference(
                log.time, theirs.time, written.precision, other.precision
            )
    cert = Certificate("two precisions", other.precision.name, errors, event_errors)
    return _worst(cert, written.variables, np.asarray(written.t, dtype=float))


def _abs_difference(a: np.ndarray, b: np.ndarray, pa: Precision, pb: Precision) -> np.ndarray:
    """|a - b| as float64, the subtraction done in mpmath on the operands' exact values."""
    fa, fb = _exact(np.ravel(a), pa), _exact(np.ravel(b), pb)
    out = np.array([float(abs(x - y)) for x, y in zip(fa, fb, strict=True)])
    return out.reshape(np.shape(a))


def _precision_of(result: Any) -> Precision:
    """The precision of a result, or of a thinned view of one (which has only the arrays)."""
    if hasattr(result, "precision"):
        return result.precision
    x = np.ravel(result.t)[0]
    if isinstance(x, float | np.floating):
        return Precision("double")
    return Precision("real", x.prec) if hasattr(x, "prec") else Precision("quad")


def _exact(values: Any, prec: Precision) -> list[Any]:
    """The exact values of numbers of ``prec``, as mpmath numbers (``str`` of a double is its
    shortest decimal, which is not its value: up to half an ulp off)."""
    rnd = _rounding(prec)
    return [rnd.read(x) for x in prec.to_text(np.asarray(values))]


class _ClosedForm:
    """A scene's closed form: evaluated as the reference, or compared with a run."""

    name = ""

    def __init__(self, scene: Scene) -> None:
        self.scene = scene

    def certificate(self, result: Any, digits: int) -> Certificate:
        raise NotImplementedError

    def job(self, prec: Precision) -> Any:
        """What workers evaluate to write the scene's outputs in ``prec`` (None: it cannot).

        The names come from the model the integration would build, so that the file holds
        every output variable and monitor the integrated run would write, and nothing else.
        """
        from ..core.families import FAMILIES

        variant = _with_precision(self.scene, prec, None)
        model = FAMILIES[variant.family].build(variant)
        grid = variant.output.time_grid(prec)
        return self._job(variant, model, prec, prec.to_text(grid[:1])[0])

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        raise NotImplementedError

    def evaluate(
        self, prec: Precision, workers: int | None, progress: Any, store: Path | None = None
    ) -> tuple[Any, Certificate, int]:
        """The scene's outputs in ``prec`` from the closed form, their certificate, and the
        number of chunks read back from ``store`` (see :func:`.reference.evaluate.evaluate`)."""
        from ..core.families import FAMILIES
        from ..core.result import Result, versions
        from .closed_form import evaluate

        wall = time.perf_counter()
        variant = _with_precision(self.scene, prec, None)
        model = FAMILIES[variant.family].build(variant)
        grid = variant.output.time_grid(prec)
        texts = list(prec.to_text(grid))
        job = self._job(variant, model, prec, texts[0])
        tick = None
        if progress is not None:
            tick = lambda done: progress("closed form", float(grid[done - 1]))  # noqa: E731
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
        errors = {n: np.array([e[n] for _, e in rows]) for n in job.variables}
        cert = Certificate("closed form", self.name, errors, event_errors)
        return result, _worst(cert, variables, np.asarray(grid, dtype=float)), resumed

    def _events(self, job: Any, model: Any, prec: Precision, grid: np.ndarray) -> tuple[dict, dict]:
        return {}, {}


def closed_form_for(scene: Scene) -> _ClosedForm | None:
    """The closed form of ``scene``'s motion, or None when it has none here."""
    if scene.family == "rotation" and scene.model.torque_free and not scene.events:
        return _FreeBody(scene)
    if scene.family == "hamiltonian" and scene.model.model == "projectile":
        if scene.model.formulation == "canonical" and not scene.events:
            return _Projectile(scene)
    return None


class _FreeBody(_ClosedForm):
    name = "FreeRigidBody, Jacobi elliptic functions"

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        from .closed_form import FreeBodyJob

        variables, monitors = tuple(model.outputs), tuple(model.monitors)
        if not (
            set(variables) <= set(FreeBodyJob.VARIABLES)
            and set(monitors) <= set(FreeBodyJob.MONITORS)
            and all(e.name == "invariable_plane" for e in model.events)
        ):
            return None
        body = self.scene.model
        dps = prec.dps
        # The attitude as the run starts it (a matrix or an unnormalised quaternion included),
        # computed well beyond the digits asked for.
        quaternion = body.initial_quaternion(Precision("real", int(dps * _BITS_PER_DIGIT) + 96))
        return FreeBodyJob(
            inertia=tuple(str(x) for x in body.inertia),
            rates=tuple(str(x) for x in body.rates),
            attitude=tuple(str(c) for c in quaternion),
            dps=dps,
            t0=t0,
            variables=variables,
            monitors=monitors,
            rounding=_rounding(prec),
        )

    def _events(self, job: Any, model: Any, prec: Precision, grid: np.ndarray) -> tuple[dict, dict]:
        """The invariable-plane crossings of the output span, as the run records them."""
        import mpmath

        from ..core.result import EventLog

        axes = [e.label for e in model.events]
        if not axes:
            return {}, {}
        body = job.body()
        rnd = job.rounding
        t0 = rnd.read(job.t0)
        crossings = []
        with mpmath.workdps(job.dps + 30):
            span = rnd.read(prec.to_text(grid[-1:])[0]) - t0
            for axis in axes:
                # A zero at the start time is where the run starts, not a crossing it detects.
                crossings += [c for c in body.crossing_times(axis, 0, span) if c.time > 0]
            crossings.sort(key=lambda c: c.time)
            times, errors = [], []
            for c in crossings:
                exact = t0 + c.time
                text, written = rnd.write(exact)
                times.append(text)
                # The crossing's error is scaled (relative above 1): made absolute here.
                bound = c.error * max(1, abs(c.time)) + 2 * mpmath.eps * abs(exact)
                errors.append(_upper(abs(written - exact) + bound))
        log = EventLog(
            time=prec.from_text(np.array(times, dtype=object)) if times else prec.array([]),
            direction=np.array([c.direction for c in crossings], dtype=int),
            label=np.array([c.axis for c in crossings], dtype=str),
        )
        return {"invariable_plane": log}, {"invariable_plane": np.array(errors)}

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from ..rotation.closed_form import FreeRigidBody

        body = self.scene.model
        dps = digits + 10
        # The attitude as the run starts it (a matrix or an unnormalised quaternion included),
        # computed well beyond the digits asked for.
        quaternion = body.initial_quaternion(Precision("real", int(dps * _BITS_PER_DIGIT) + 64))
        exact = FreeRigidBody(
            body.inertia, body.rates, attitude=[str(c) for c in quaternion], dps=dps
        )
        t = result.t
        names = [n for n in ("p", "q", "r", "qw", "qx", "qy", "qz") if n in result.variables]
        has_rodrigues = "lambda" in result.variables
        cols: dict[str, list[float]] = {
            n: [] for n in names + (["lambda", "mu", "nu"] if has_rodrigues else [])
        }
        prec = _precision_of(result)
        times = _exact(t, prec)
        columns = {n: _exact(result.variables[n], prec) for n in cols}
        with mpmath.workdps(dps + 10):
            t0 = times[0]
            for k in range(len(t)):
                s = exact.at(times[k] - t0)
                bound = max(s.errors.values())
                got = {n: columns[n][k] for n in cols}
                exact_q = list(s.quaternion)
                if "qw" in got:
                    # q and −q are one attitude: compare with the sign the run took.
                    ours = [got["qw"], got["qx"], got["qy"], got["qz"]]
                    if sum(a * b for a, b in zip(ours, exact_q, strict=True)) < 0:
                        exact_q = [-c for c in exact_q]
                want = {"p": s.p, "q": s.q, "r": s.r}
                want.update(zip(("qw", "qx", "qy", "qz"), exact_q, strict=True))
                if has_rodrigues:
                    w = exact_q[0]
                    want.update(
                        {"lambda": exact_q[1] / w, "mu": exact_q[2] / w, "nu": exact_q[3] / w}
                    )
                for n in cols:
                    if n in ("lambda", "mu", "nu"):
                        # λ = x/w: an error b in x and w becomes b(1 + |λ|)/|w|.
                        bound_n = bound * (1 + abs(want[n])) / abs(exact_q[0])
                    else:
                        bound_n = bound * max(1, abs(want[n]))
                    # The division and the subtraction round at the working precision.
                    rounding = 4 * mpmath.eps * (abs(want[n]) + abs(got[n]))
                    cols[n].append(_upper(abs(got[n] - want[n]) + bound_n + rounding))
            event_errors = {}
            log = result.events.get("invariable_plane")
            if log is not None:
                event_errors["invariable_plane"] = self._crossings(exact, log, times[-1], t0, prec)
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, event_errors)
        return _worst(cert, result.variables, np.asarray(t, dtype=float))

    @staticmethod
    def _crossings(exact: Any, log: Any, t1: Any, t0: Any, prec: Precision) -> np.ndarray:
        """Each recorded crossing's error, in the log's order."""
        span = t1 - t0
        errors = np.zeros(len(log))
        for axis in ("x1", "y1", "z1"):
            ours = [x - t0 for x in _exact(log.where(axis), prec)]
            theirs = exact.crossing_times(axis, 0, span)
            if len(ours) != len(theirs):
                raise RuntimeError(
                    f"invariable-plane crossings of {axis}: {len(ours)} recorded, "
                    f"{len(theirs)} in the closed form — no certificate"
                )
            # The crossing's error is scaled (relative above 1): made absolute here.
            errors[np.flatnonzero(log.label == axis)] = [
                _upper(abs(a - c.time) + c.error * max(1, abs(c.time)))
                for a, c in zip(ours, theirs, strict=True)
            ]
        return errors


class _Projectile(_ClosedForm):
    name = "Hamilton's projectile, (113.)-(114.), (120.)"

    def _job(self, variant: Scene, model: Any, prec: Precision, t0: str) -> Any:
        from .closed_form import ProjectileJob

        variables, monitors = tuple(model.outputs), tuple(model.monitors)
        if not (
            set(variables) <= set(ProjectileJob.VARIABLES)
            and set(monitors) <= set(ProjectileJob.MONITORS)
            and not model.events
        ):
            return None
        h = self.scene.model
        c = h.constants
        return ProjectileJob(
            g=str(c["g"]),
            mu=str(c["mu"]),
            nu=str(c["nu"]),
            eta=tuple(str(x) for x in h.eta),
            varpi=tuple(str(x) for x in h.varpi),
            dps=prec.dps,
            t0=t0,
            variables=variables,
            monitors=monitors,
            rounding=_rounding(prec),
        )

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from ..hamilton.projectile import projectile_solution

        h = self.scene.model
        c = h.constants
        dps = digits + 10
        t = result.t
        names = [n for n in result.variables if n[:-1] in ("eta", "varpi") or n == "S"]
        cols: dict[str, list[float]] = {n: [] for n in names}
        prec = _precision_of(result)
        times = _exact(t, prec)
        columns = {n: _exact(result.variables[n], prec) for n in names}
        with mpmath.workdps(dps + 10):
            for k in range(len(t)):
                tk = times[k] - times[0]
                s = projectile_solution(c["g"], c["mu"], c["nu"], h.eta, h.varpi, tk, dps=dps)
                want = {f"eta{i + 1}": s.eta[i] for i in range(3)}
                want.update({f"varpi{i + 1}": s.varpi[i] for i in range(3)})
                want["S"] = s.S
                for n in names:
                    got = columns[n][k]
                    bound = s.errors[n] * max(1, abs(want[n]))
                    cols[n].append(_upper(abs(got - want[n]) + bound))
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors)
        return _worst(cert, result.variables, np.asarray(t, dtype=float))


def _upper(x: Any) -> float:
    from .closed_form import upper

    return upper(x)


def _rounding(prec: Precision) -> Any:
    from .closed_form import Rounding

    return Rounding(prec.kind, prec.bits)


# ---------------------------------------------------------------------- files
def _positive(text: str) -> bool:
    try:
        return float(text) > 0
    except (TypeError, ValueError):
        return False


def _with_precision(scene: Scene, prec: Precision, tolerance: str | None) -> Scene:
    data = scene.to_dict()
    integ = dict(data.get("integrator", {}))
    integ["precision"] = prec.to_spec()
    integ["tolerance"] = "auto" if tolerance is None else tolerance
    data["integrator"] = integ
    return Scene.from_dict(data)


def _labelled(progress: Any, label: str) -> Any:
    if progress is None:
        return None
    return lambda t: progress(label, t)


def _metadata(
    scene: Scene,
    command: list[str] | None,
    method: str,
    digits: int,
    certified: bool,
    prec: Precision,
    attempts: list,
    max_bits: int,
    started: float,
    **extra: Any,
) -> dict[str, Any]:
    """``metadata["reference"]`` of a reference file: how to reproduce it."""
    return {
        "command": command or [],
        "method": method,
        "digits": digits,
        "certified": certified,
        "precision": prec.name,
        **extra,
        "attempts": attempts,
        "guard_digits": GUARD_DIGITS,
        "max_bits": max_bits,
        "wall_seconds": time.perf_counter() - started,
        "scene_sha256": hashlib.sha256(
            json.dumps(scene.to_dict(), sort_keys=True).encode()
        ).hexdigest(),
        "environment": _environment(),
    }


def _environment() -> dict[str, str]:
    import h5py
    import mpmath

    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "machine": platform.machine(),
        "mpmath": mpmath.__version__,
        "mpmath_backend": mpmath.libmp.BACKEND,
        "h5py": h5py.__version__,
    }


def _write(
    out: Path, result: Any, cert: Certificate, digits: int, certified: bool, meta: dict
) -> None:
    result.metadata = {**result.metadata, "reference": meta}

    def fill(f: Any) -> None:
        result.fill(f)
        g = f.create_group("certificate")
        g.attrs["method"] = cert.method
        g.attrs["compared_with"] = cert.compared_with
        g.attrs["digits_requested"] = digits
        g.attrs["digits_certified"] = cert.digits()
        g.attrs["largest_scaled_error"] = cert.scaled
        g.attrs["worst"] = json.dumps(list(cert.worst))
        g.attrs["certified"] = certified
        g.attrs["scaling"] = "absolute where |value| <= 1, relative above"
        for name, err in cert.errors.items():
            g.create_dataset(name, data=err)
        ge = g.create_group("events")
        for name, err in cert.event_errors.items():
            ge.create_dataset(name, data=err)

    write_hdf5(out, fill)


def _claim_workdir(workdir: Path) -> None:
    """Make ``workdir`` ours, or refuse one that someone else made (before any run)."""
    marker = workdir / WORK_MARKER
    if marker.is_file():
        return
    if workdir.is_dir() and any(workdir.iterdir()):
        raise OutputError(
            workdir,
            "exists and was not made by `cayley-heyoka reference` (no "
            f"{WORK_MARKER} in it); move it away, it is left untouched",
        )
    if workdir.exists() and not workdir.is_dir():
        raise OutputError(workdir, "exists and is not a directory; move it away")
    try:
        workdir.mkdir(parents=True, exist_ok=True)
        marker.write_text("work directory of cayley-heyoka reference\n")
    except OSError as exc:
        raise OutputError(workdir, f"cannot be created ({exc.strerror or exc})") from exc


def _remove_workdir(workdir: Path) -> None:
    """Remove what the runs wrote in ``workdir``; anything else stays, with its directory."""
    from .checkpoint import remove_checkpoints
    from .closed_form import remove_saved

    for run_dir in workdir.glob("run-*"):
        remove_checkpoints(run_dir)
    for store in workdir.glob("closed-form-*"):
        remove_saved(store)
    (workdir / WORK_MARKER).unlink(missing_ok=True)
    with contextlib.suppress(OSError):  # not empty: what is left is not ours
        workdir.rmdir()


def read_certificate(path: str | Path) -> dict[str, Any]:
    """The certificate of a reference file: its attributes, and errors by variable name.

    Raises
    ------
    ResultFileError
        The file is not a result file, is damaged, or has no certificate.
    """
    from ..core.files import ResultFileError, open_ours

    with open_ours(path, "result") as f:
        if "certificate" not in f:
            raise ResultFileError(path, "not a reference file (no certificate group)")
        g = f["certificate"]
        out: dict[str, Any] = dict(g.attrs)
        out["errors"] = {k: g[k][()] for k in g if k != "events"}
        out["event_errors"] = {k: g["events"][k][()] for k in g["events"]}
    return out
