"""Certified reference solutions: ``cayley-heyoka reference SCENE.toml --digits 30 --out REF.h5``.

A reference solution is a scene's trajectory at its output times, written with an error
certificate: the estimated absolute error of every variable at every time. The cheapest
certified route is taken:

* **Closed form** (``method="auto"`` or ``"closed-form"``), where the scene has one — the
  torque-free body (:class:`~cayley_heyoka.reference.FreeRigidBody`, also its invariable-plane
  crossings) and Hamilton's projectile (:func:`~cayley_heyoka.reference.projectile_solution`):
  the closed form itself is the reference, evaluated at each output time in mpmath with its own
  certified error bound (two working precisions), in parallel over cores
  (:mod:`cayley_heyoka.core.evaluation`), and rounded once to the file's precision; the
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
where it stopped and writes the same bits as an uninterrupted one (every checkpoint verified by
its checksum and the run's identity first). The running command holds the directory locked
(:data:`WORK_LOCK`): a second one on the same output is refused. Once the file is written,
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
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core.certificate import (
    BITS_PER_DIGIT,
    Certificate,
    difference_certificate,
    label,
    next_precision,
    precision_for,
    uncovered,
)
from ..core.closed_form import ClosedForm, with_precision
from ..core.errors import OptionError, SceneError
from ..core.families import FAMILIES
from ..core.files import OutputError, check_destination, write_hdf5
from ..core.precision import MAX_BITS, Precision, number_argument, shown
from ..core.scene import Scene, require_scene

#: Digits of working precision beyond those requested: room for the error a long run builds.
GUARD_DIGITS = 4
#: Most digits a reference may ask for: those the largest precision (:data:`MAX_BITS`) holds,
#: its guard digits kept.
MAX_DIGITS = int((MAX_BITS - 1) / BITS_PER_DIGIT) - GUARD_DIGITS
#: Stretches between checkpoints (each ends a step; the count is part of what the file records).
STRETCHES = 64
#: How the reference is made: "closed-form" evaluates the closed form; "integrate" integrates
#: and certifies against the closed form where there is one, else as "two-precisions" does;
#: "auto" is "closed-form" where the scene has one (and no tolerance is asked for), else an
#: integration.
METHODS = ("auto", "closed-form", "integrate", "two-precisions")
#: The file that marks a work directory as made by :func:`generate_reference`.
WORK_MARKER = ".cayley_heyoka-reference-work"
#: The file a running :func:`generate_reference` holds locked in its work directory.
WORK_LOCK = ".cayley_heyoka-reference-lock"


@dataclass
class ReferenceOutcome:
    """What :func:`generate_reference` wrote."""

    path: Path
    certified: bool
    certificate: Certificate
    precision: Precision
    attempts: list[dict[str, Any]]
    #: The variables and monitors written without an error bound (the file is then not
    #: certified, whatever the digits of the others).
    uncovered: tuple[str, ...] = ()


def generate_reference(
    scene: Scene,
    digits: int,
    out: str | Path,
    *,
    precision: Precision | None = None,
    tolerance: Any = None,
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
        Significant decimal digits to certify (scaled: absolute for ``|x| ≤ 1``).
    out
        The HDF5 file to write.
    precision
        Start from this precision instead of the one chosen for ``digits`` (the closed form:
        write in it).
    tolerance
        heyoka's tolerance for the first run (any number
        :func:`~cayley_heyoka.core.precision.as_number` takes; decimal text keeps it exact);
        default: its precision's epsilon. Asks for an integration: with ``method="auto"`` the
        closed form is not taken.
    max_bits
        Give up raising the precision beyond this many bits (at most :data:`MAX_BITS`, the
        largest precision of a scene).
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
    TypeError
        ``scene`` is not a :class:`~cayley_heyoka.core.scene.Scene`, or ``tolerance`` is not a
        number.
    ValueError
        A bad argument, named (:class:`~cayley_heyoka.core.errors.OptionError` for a
        ``precision`` or ``tolerance`` the scene refuses, such as a tolerance below 1e-6 of
        the precision's epsilon).
    OutputError
        Before anything is integrated: ``out`` may not be written, ``workdir`` exists and
        is not a work directory of this function, or another process is running this
        function on it. After: :class:`~cayley_heyoka.core.files.WriteFailed`, a file could
        not be written (a full disk); what was checkpointed is kept.
    CheckpointMismatch
        ``workdir`` holds the checkpoints of another run (another scene, precision, ...).
    RuntimeError
        The closed form could not certify its own digits at some time (next to a singular
        configuration), or an integration stopped.
    """
    scene = require_scene(scene)
    if isinstance(digits, bool) or not isinstance(digits, int) or not 1 <= digits <= MAX_DIGITS:
        raise ValueError(
            f"digits must be an integer in 1 … {MAX_DIGITS} (what {MAX_BITS} bits hold beside "
            f"{GUARD_DIGITS} guard digits), got {shown(digits)}"
        )
    if (
        isinstance(max_bits, bool)
        or not isinstance(max_bits, int)
        or not 53 <= max_bits <= MAX_BITS
    ):
        raise ValueError(
            f"max_bits must be an integer in 53 … {MAX_BITS} (the largest precision of a "
            f"scene), got {max_bits!r}"
        )
    if precision is not None and not isinstance(precision, Precision):
        raise TypeError(f"precision must be a Precision or None, got {precision!r}")
    if tolerance is not None:
        tolerance = number_argument(tolerance, "tolerance", positive=True)
    from .checkpoint import check_count

    check_count(stretches)
    out = Path(out)
    # "." or "/": no name to add to; another scene's result is not replaced (the reference
    # chooses its own integrator).
    check_destination(
        out,
        "result",
        overwrite=overwrite,
        holding=("scene", scene.to_dict()),
        ignoring=("integrator",),
    )
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
    # The first run's scene, checked as the scene's own fields are (the tolerance against the
    # precision's epsilon, every number in the precision) before anything is written.
    try:
        with_precision(scene, first, tolerance)
    except OptionError:
        raise
    except SceneError as exc:
        if precision is not None:
            raise
        raise SceneError(
            exc.field,
            f"{exc.constraint} (in {label(first)}, the precision chosen for {digits} digits: "
            "give a precision that holds the scene)",
        ) from None
    evaluated = None
    if closed is not None and (method == "closed-form" or (method == "auto" and not tolerance)):
        evaluated = closed.job(first)
        if evaluated is None and method == "closed-form":
            raise ValueError(
                "method 'closed-form': the scene asks for outputs the closed form does not "
                "give (it gives the state, the attitude and the conserved monitors); use "
                "'integrate'"
            )
    if closed is not None and evaluated is None and closed.job(first) is None:
        # The closed form lacks some output the file writes (a user monitor, an output it
        # does not give): it cannot certify the file, a second precision can.
        closed = None
    # Held to the end: a second command on the same --out is refused, not mixed in.
    with _claim_workdir(workdir):
        if evaluated is not None:
            outcome = _closed_form_reference(
                scene,
                closed,
                digits,
                out,
                first,
                max_bits,
                workers,
                workdir,
                progress,
                say,
                command,
                None if keep_work else workdir,
            )
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

                variant = with_precision(scene, prec, tol)
                where = (
                    workdir / f"run-{prec.name}" if tol is None else workdir / f"run-{prec.name}-t"
                )
                job = CheckpointedRun(variant, where, stretches, _labelled(progress, prec.name))
                t0 = time.perf_counter()
                result = job.run()
                for line in job.notes:
                    say(f"work directory: {line}")
                resumed = job.resumed
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
            say(
                f"certificate: {cert.digits_text()} {'proved' if cert.proved else 'estimated'} "
                f"(largest scaled error {cert.scaled:.2e} in {_where(cert)})"
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
        missing = _write(
            out, written, cert, digits, certified, metadata, None if keep_work else workdir
        )
        return ReferenceOutcome(
            out, certified and not missing, cert, written.precision, attempts, missing
        )


def _closed_form_reference(
    scene: Scene,
    closed: ClosedForm,
    digits: int,
    out: Path,
    prec: Precision,
    max_bits: int,
    workers: int | None,
    workdir: Path,
    progress: Any,
    say: Any,
    command: list[str] | None,
    remove: Path | None,
) -> ReferenceOutcome:
    """The closed-form route of :func:`generate_reference`: evaluate, certify, write (and
    remove the work directory ``remove``, if given)."""
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
            f"{time.perf_counter() - t0:.2f} s{note}; certificate: {cert.digits_text()} "
            f"{'proved' if cert.proved else 'estimated'} (largest scaled error "
            f"{cert.scaled:.2e} in {_where(cert)})"
        )
        if cert.scaled <= 10.0**-digits or next_precision(prec).bits > max_bits:
            break
        prec = next_precision(prec)
        say(f"not enough: raising the precision to {label(prec)}")
    certified = cert.scaled <= 10.0**-digits
    metadata = _metadata(
        scene, command, "closed form", digits, certified, prec, attempts, max_bits, started
    )
    missing = _write(out, result, cert, digits, certified, metadata, remove)
    return ReferenceOutcome(out, certified and not missing, cert, prec, attempts, missing)


# ---------------------------------------------------------------------- certificates
# ---------------------------------------------------------------------- files
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


def _where(cert: Certificate) -> str:
    """Where the largest scaled error is: a variable at an output time, or an event (whose
    error is of its time, at no output time)."""
    name, at = cert.worst
    where = f"{name} at t = {at:.6g}" if math.isfinite(at) else name
    if math.isfinite(cert.scaled):
        return where
    if name in ("lambda", "mu", "nu"):
        return where + (
            ": unbounded, as λ, μ, ν are where the body is a half-turn from the space frame "
            "(w = 0); choose output times away from it"
        )
    return where + (
        ": unbounded, the value is undefined (NaN) or infinite in one of the results compared "
        "and not in the other"
    )


def _write(
    out: Path,
    result: Any,
    cert: Certificate,
    digits: int,
    certified: bool,
    meta: dict,
    remove: Path | None = None,
) -> tuple[str, ...]:
    """Write the reference file (``result`` and ``cert``), then remove the work directory
    ``remove`` (if given): both, even under a signal, which takes effect after them.

    A variable or monitor the certificate gives no error for makes the file uncertified and
    unproved, and is named in the certificate's ``uncovered``
    (:func:`cayley_heyoka.core.certificate.uncovered`). Returns those names.
    """
    from ..core.signals import held_signals

    missing = uncovered(cert, result)
    if missing:
        certified = False
        meta = {**meta, "certified": False}
    result.metadata = {**result.metadata, "reference": meta}

    def fill(f: Any) -> None:
        result.fill(f)
        g = f.create_group("certificate")
        g.attrs["method"] = cert.method
        g.attrs["proved"] = cert.proved and not missing
        g.attrs["uncovered"] = json.dumps(list(missing))
        g.attrs["compared_with"] = cert.compared_with
        g.attrs["digits_requested"] = digits
        g.attrs["digits_certified"] = cert.digits()
        g.attrs["largest_scaled_error"] = cert.scaled
        g.attrs["worst"] = json.dumps(list(cert.worst))
        g.attrs["certified"] = certified
        g.attrs["scaling"] = "absolute where |value| <= 1, relative above"
        for name, err in cert.errors.items():
            ds = g.create_dataset(name, data=err)
            kind = "proved bound of the absolute error" if cert.proved else "absolute error"
            ds.attrs["long_name"] = f"{kind} of {name}"
            if ds.ndim and ds.shape[0] == len(result.t):  # over the output times
                ds.dims[0].attach_scale(f["time"])
        ge = g.create_group("events")
        for name, err in cert.event_errors.items():
            ge.create_dataset(name, data=err)

    with held_signals():
        write_hdf5(out, fill)
        if remove is not None:
            _remove_workdir(remove)
    return missing


def _claim_workdir(workdir: Path) -> Any:
    """Make ``workdir`` ours and hold it (a context manager), or refuse one that someone else
    made or that another command holds (before any run)."""
    from ..core.files import write_bytes

    marker = workdir / WORK_MARKER
    if not marker.is_file():
        if workdir.is_dir() and any(workdir.iterdir()):
            raise OutputError(
                workdir,
                "exists and was not made by `cayley-heyoka reference` (no "
                f"{WORK_MARKER} in it); move it away, it is left untouched",
            )
        if workdir.exists() and not workdir.is_dir():
            raise OutputError(workdir, "exists and is not a directory; move it away")
        made = not workdir.exists()
        try:
            workdir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise OutputError(workdir, f"cannot be created ({exc.strerror or exc})") from exc
        try:
            write_bytes(marker, b"work directory of cayley-heyoka reference\n")
        except OutputError as exc:
            if made:
                with contextlib.suppress(OSError):
                    workdir.rmdir()
            raise OutputError(workdir, f"cannot be made ours: {WORK_MARKER} {exc.what}") from exc
    return _held(workdir)


@contextlib.contextmanager
def _held(workdir: Path) -> Any:
    from ..core.files import locked_directory

    try:
        with locked_directory(workdir, WORK_LOCK, "`cayley-heyoka reference`"):
            yield
    finally:
        if not (workdir / WORK_MARKER).exists():  # emptied by _remove_workdir
            with contextlib.suppress(OSError):  # not empty: what is left is not ours
                workdir.rmdir()


def _remove_workdir(workdir: Path) -> None:
    """Remove what the runs wrote in ``workdir``; anything else stays, with its directory
    (which goes once its lock is released, if that empties it)."""
    from ..core.evaluation import remove_saved
    from .checkpoint import remove_checkpoints

    for run_dir in workdir.glob("run-*"):
        remove_checkpoints(run_dir)
    for store in workdir.glob("closed-form-*"):
        remove_saved(store)
    (workdir / WORK_MARKER).unlink(missing_ok=True)


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


def closed_form_for(scene: Scene) -> ClosedForm | None:
    """The closed form of ``scene``'s motion, as its family offers it, or None."""
    offer = FAMILIES[scene.family].closed_form
    return None if offer is None else offer(scene)
