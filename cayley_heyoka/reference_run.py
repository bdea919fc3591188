"""Certified reference solutions: ``cayley-heyoka reference SCENE.toml --digits 30 --out REF.h5``.

A reference solution is a scene's trajectory at its output times, written with an error
certificate: the estimated absolute error of every variable at every time. How it is made:

1. **Precision.** The smallest of double, quad (``real128``) or MPFR ``real`` whose epsilon
   leaves :data:`GUARD_DIGITS` digits beyond the requested ones; the tolerance is that
   precision's epsilon (heyoka's default), unless given.
2. **Certificate.** Where the scene has a closed form — the torque-free body
   (:class:`~cayley_heyoka.reference.FreeRigidBody`, also its invariable-plane crossings) and
   Hamilton's projectile (:func:`~cayley_heyoka.reference.projectile_solution`) — the run is
   compared with it, evaluated in mpmath with its own certified error. Otherwise the scene is
   integrated again at a higher precision (its epsilon as tolerance), independent in both
   round-off and truncation; the more precise run is written and the difference of the two is
   its certificate (an estimate of the less precise run's error, so a conservative one of the
   written run's).
3. **Escalation.** If the certificate does not reach the requested digits (scaled errors:
   absolute where |x| ≤ 1, relative above), the precisions are raised and the run repeated, up
   to ``max_bits``; past that the file is written marked uncertified and the command exits 1.

Runs go through :class:`~cayley_heyoka.checkpoint.CheckpointedRun` in a work directory beside
the output (``REF.h5.work``): an interrupted command, run again, continues where it stopped
and writes the same bits as an uninterrupted one. Once the file is written, the files the runs
wrote there are removed (and the directory, if nothing else is in it); a ``OUT.work`` that this
command did not make (it carries the marker file :data:`WORK_MARKER`) is refused, not touched.
The file is an ordinary result file (``cayley_heyoka.load_result``) with a ``certificate`` group
and the metadata needed to reproduce it (``metadata["reference"]``).
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

from .files import OutputError, check_destination, write_hdf5
from .precision import Precision
from .scene import Scene

#: Digits of working precision beyond those requested: room for the error a long run builds.
GUARD_DIGITS = 4
#: Largest precision the escalation goes to, unless told otherwise.
MAX_BITS = 1024
#: Stretches between checkpoints (each ends a step; the count is part of what the file records).
STRETCHES = 64
_BITS_PER_DIGIT = math.log2(10)
#: How the certificate is made.
METHODS = ("auto", "closed-form", "two-precisions")
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
) -> ReferenceOutcome:
    """Integrate ``scene`` to ``digits`` certified digits and write the reference file.

    Parameters
    ----------
    scene
        The scene (its ``[integrator]`` precision and tolerance are replaced).
    digits
        Significant decimal digits to certify (scaled: absolute for |x| ≤ 1).
    out
        The HDF5 file to write.
    precision
        Start from this precision instead of the one chosen for ``digits``.
    tolerance
        heyoka's tolerance for the first run (decimal text); default: its precision's epsilon.
    max_bits
        Give up raising the precision beyond this many bits.
    stretches
        Checkpoints per run (see :class:`~cayley_heyoka.checkpoint.CheckpointedRun`).
    workdir
        Where runs are checkpointed; default ``OUT.work`` beside ``out``.
    keep_work
        Keep the work directory after the file is written.
    overwrite
        Replace ``out`` even if it is not a result file of ours (see
        :func:`cayley_heyoka.files.check_destination`).
    method
        ``"auto"`` (the closed form where there is one), ``"closed-form"`` or
        ``"two-precisions"``.
    progress
        ``progress(run_label, time)`` after each step, or None.
    report
        ``report(text)`` for one-line accounts of the plan and each run, or None.
    command
        The command line, for the file's metadata.

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
    closed = closed_form_for(scene) if method != "two-precisions" else None
    if method == "closed-form" and closed is None:
        raise ValueError(
            "method 'closed-form': this scene has none here (a torque-free body without user "
            "events, or Hamilton's projectile in canonical form); use 'two-precisions'"
        )
    first = precision or precision_for(digits + GUARD_DIGITS)
    if first.bits > max_bits:
        raise ValueError(f"max_bits ({max_bits}) is below the precision needed ({label(first)})")
    check_destination(out, "result", overwrite=overwrite)
    _claim_workdir(workdir)
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
        say(
            f"certificate: {cert.digits():.1f} digits (largest scaled error {cert.scaled:.2e} "
            f"in {cert.worst[0]} at t = {cert.worst[1]:.6g})"
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
    metadata = {
        "command": command or [],
        "digits": digits,
        "certified": certified,
        "precision": written.precision.name,
        "stretches": stretches,
        "attempts": attempts,
        "guard_digits": GUARD_DIGITS,
        "max_bits": max_bits,
        "wall_seconds": time.perf_counter() - started,
        "scene_sha256": hashlib.sha256(
            json.dumps(scene.to_dict(), sort_keys=True).encode()
        ).hexdigest(),
        "environment": _environment(),
    }
    _write(out, written, cert, digits, certified, metadata)
    if not keep_work:
        _remove_workdir(workdir)
    return ReferenceOutcome(out, certified, cert, written.precision, attempts)


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
            errors[name] = _abs_difference(values, other.variables[name])
        event_errors = {}
        for name, log in written.events.items():
            theirs = other.events.get(name)
            if theirs is None or len(theirs) != len(log) or list(theirs.label) != list(log.label):
                raise RuntimeError(
                    f"event {name!r}: {len(log)} occurrences in {written.precision.name}, "
                    f"{0 if theirs is None else len(theirs)} in {other.precision.name} — the "
                    "runs disagree on an event (one grazing zero?): no certificate"
                )
            event_errors[name] = _abs_difference(log.time, theirs.time)
    cert = Certificate("two precisions", other.precision.name, errors, event_errors)
    return _worst(cert, written.variables, np.asarray(written.t, dtype=float))


def _abs_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """|a - b| as float64, the subtraction done in mpmath (exact for both operands' types)."""
    import mpmath

    fa, fb = np.ravel(a), np.ravel(b)
    out = np.array(
        [float(abs(mpmath.mpf(str(x)) - mpmath.mpf(str(y)))) for x, y in zip(fa, fb, strict=True)]
    )
    return out.reshape(np.shape(a))


class _ClosedForm:
    """A closed form that a scene's run can be compared with."""

    name = ""

    def certificate(self, result: Any, digits: int) -> Certificate:
        raise NotImplementedError


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

    def __init__(self, scene: Scene) -> None:
        self.scene = scene

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from .rotation.closed_form import FreeRigidBody

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
        with mpmath.workdps(dps + 10):
            t0 = mpmath.mpf(str(t[0]))
            for k in range(len(t)):
                s = exact.at(mpmath.mpf(str(t[k])) - t0)
                bound = max(s.errors.values())
                got = {n: mpmath.mpf(str(result.variables[n][k])) for n in cols}
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
                    err = abs(got[n] - want[n]) + bound * max(1, abs(want[n]))
                    cols[n].append(float(err))
            event_errors = {}
            log = result.events.get("invariable_plane")
            if log is not None:
                event_errors["invariable_plane"] = self._crossings(exact, log, t, t0)
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors, event_errors)
        return _worst(cert, result.variables, np.asarray(t, dtype=float))

    @staticmethod
    def _crossings(exact: Any, log: Any, t: np.ndarray, t0: Any) -> np.ndarray:
        import mpmath

        span = mpmath.mpf(str(t[-1])) - t0
        errors = []
        for axis in ("x1", "y1", "z1"):
            ours = [mpmath.mpf(str(x)) - t0 for x in log.where(axis)]
            theirs = exact.crossing_times(axis, 0, span)
            if len(ours) != len(theirs):
                raise RuntimeError(
                    f"invariable-plane crossings of {axis}: {len(ours)} recorded, "
                    f"{len(theirs)} in the closed form — no certificate"
                )
            errors += [float(abs(a - c.time) + c.error) for a, c in zip(ours, theirs, strict=True)]
        return np.array(errors)


class _Projectile(_ClosedForm):
    name = "Hamilton's projectile, (113.)-(114.), (120.)"

    def __init__(self, scene: Scene) -> None:
        self.scene = scene

    def certificate(self, result: Any, digits: int) -> Certificate:
        import mpmath

        from .hamilton.projectile import projectile_solution

        h = self.scene.model
        c = h.constants
        dps = digits + 10
        t = result.t
        names = [n for n in result.variables if n[:-1] in ("eta", "varpi") or n == "S"]
        cols: dict[str, list[float]] = {n: [] for n in names}
        with mpmath.workdps(dps + 10):
            t0 = mpmath.mpf(str(t[0]))
            for k in range(len(t)):
                tk = mpmath.mpf(str(t[k])) - t0
                s = projectile_solution(c["g"], c["mu"], c["nu"], h.eta, h.varpi, tk, dps=dps)
                want = {f"eta{i + 1}": s.eta[i] for i in range(3)}
                want.update({f"varpi{i + 1}": s.varpi[i] for i in range(3)})
                want["S"] = s.S
                for n in names:
                    got = mpmath.mpf(str(result.variables[n][k]))
                    bound = s.errors[n] * max(1, abs(want[n]))
                    cols[n].append(float(abs(got - want[n]) + bound))
        errors = {n: np.array(v) for n, v in cols.items()}
        cert = Certificate("closed form", self.name, errors)
        return _worst(cert, result.variables, np.asarray(t, dtype=float))


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


def _environment() -> dict[str, str]:
    import h5py
    import mpmath

    return {
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "machine": platform.machine(),
        "mpmath": mpmath.__version__,
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

    for run_dir in workdir.glob("run-*"):
        remove_checkpoints(run_dir)
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
    from .files import ResultFileError, open_ours

    with open_ours(path, "result") as f:
        if "certificate" not in f:
            raise ResultFileError(path, "not a reference file (no certificate group)")
        g = f["certificate"]
        out: dict[str, Any] = dict(g.attrs)
        out["errors"] = {k: g[k][()] for k in g if k != "events"}
        out["event_errors"] = {k: g["events"][k][()] for k in g["events"]}
    return out
