"""``cayley-heyoka reference SCENE.toml --digits N --out REF.h5``: a certified reference
solution (:mod:`cayley_heyoka.workflows.reference`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from . import add_progress, show_progress

if TYPE_CHECKING:
    from ..core.precision import Precision
    from ..core.scene import Scene

# The workflow's defaults and choices, written here so that building the parser imports
# nothing of it; tests/test_cli_imports.py holds them equal to reference_run's.
MAX_BITS = 1024
STRETCHES = 64
METHODS = ("auto", "closed-form", "integrate", "two-precisions")


def add_parser(subparsers: Any) -> None:
    """Add ``reference`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser(
        "reference",
        help="write a certified reference solution of a scene (resumable)",
        description=(
            "Write SCENE's solution at its output times to DIGITS certified digits, with its "
            "error certificate: the closed form where the scene has one (torque-free body, "
            "Hamilton's projectile), evaluated in parallel; else an integration certified by a "
            "second precision. Interrupted (Ctrl-C, or killed), the same command continues "
            "from its last checkpoint and writes the same bits."
        ),
    )
    p.add_argument("scene", type=Path, help="scene TOML file")
    p.add_argument("--digits", type=int, required=True, help="decimal digits to certify")
    p.add_argument("--out", type=Path, required=True, help="the HDF5 file to write")
    p.add_argument(
        "--precision", help="start from this precision: double, quad or a number of bits"
    )
    p.add_argument("--tolerance", help="heyoka's tolerance of the first run (default: epsilon)")
    p.add_argument("--max-bits", type=int, default=MAX_BITS, help="stop raising precision here")
    p.add_argument(
        "--checkpoints", type=int, default=STRETCHES, help="checkpoints per run (default 64)"
    )
    p.add_argument(
        "--certificate",
        choices=METHODS,
        default="auto",
        help=(
            "auto (the closed form where there is one and no --tolerance is given, else "
            "integrate), closed-form (evaluate it), integrate (integrate, certified by the "
            "closed form where there is one, else by a second precision), two-precisions"
        ),
    )
    p.add_argument(
        "--workers",
        type=_positive_int,
        default=None,
        help="processes evaluating a closed form (default: every core; same bits whatever "
        "the count)",
    )
    p.add_argument("--keep-work", action="store_true", help="keep the work directory")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace --out even if it is not a result file of ours",
    )
    add_progress(p)
    p.set_defaults(handler=command)


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}")
    return value


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    return _reference(args)


def _reference(args: argparse.Namespace) -> int:
    from ..core.errors import OptionError, SceneError
    from ..core.files import WriteFailed, file_id
    from ..core.scene import load_scene
    from ..workflows.reference import generate_reference, label

    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    try:
        start = _parse_precision(args.precision)
    except OptionError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    bar = _Bars(scene) if show_progress(args) else None
    before = file_id(args.out)
    try:
        try:
            outcome = generate_reference(
                scene,
                args.digits,
                args.out,
                precision=start,
                tolerance=args.tolerance,
                max_bits=args.max_bits,
                stretches=args.checkpoints,
                keep_work=args.keep_work,
                overwrite=args.overwrite,
                method=args.certificate,
                workers=args.workers,
                progress=bar.update if bar else None,
                report=print,
                command=["cayley-heyoka", *sys.argv[1:]],
            )
        finally:
            if bar:  # before any message: a bar drawn after it would end stderr
                bar.close()
    except KeyboardInterrupt:
        if file_id(args.out) not in (None, before):  # it came while the file was written
            print(f"\ninterrupted after the reference was written to {args.out}", file=sys.stderr)
        else:
            print(
                f"\ninterrupted: what was checkpointed is in {args.out}.work; "
                "run the same command to continue",
                file=sys.stderr,
            )
        return 130
    except OptionError as exc:  # an option the scene refuses: named as the command line has it
        print(f"error: {_option(exc)}", file=sys.stderr)
        return 2
    except SceneError as exc:  # found when the model is built or its output times rounded
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    except WriteFailed as exc:
        print(
            f"error: {exc}; the checkpoints are kept in {args.out}.work: run the same command "
            "to continue from them",
            file=sys.stderr,
        )
        return 1
    except (ValueError, TypeError, RuntimeError) as exc:
        print(f"error: {_option(exc)}", file=sys.stderr)
        return 1 if isinstance(exc, RuntimeError) else 2
    cert = outcome.certificate
    verdict = "certified" if outcome.certified else "NOT CERTIFIED"
    print(
        f"{verdict}: {cert.digits_text()} of {args.digits} requested "
        f"({label(outcome.precision)}, {cert.method}: {cert.compared_with})"
    )
    if outcome.uncovered:
        print(f"the certificate gives no error for: {', '.join(outcome.uncovered)}")
    print(f"reference written to {outcome.path}")
    return 0 if outcome.certified else 1


#: The keyword arguments of generate_reference that this command's options give.
_OPTIONS = {
    "digits": "--digits",
    "precision": "--precision",
    "tolerance": "--tolerance",
    "max_bits": "--max-bits",
    "checkpoints (stretches of a run)": "--checkpoints",
    "workers": "--workers",
}


def _option(exc: Exception) -> str:
    """The refusal of a keyword argument, with the name of the option that gave it."""
    text = str(exc)
    for keyword, option in _OPTIONS.items():
        if text.startswith(keyword + " ") or text.startswith(keyword + ":"):
            return option + text[len(keyword) :]
    return text


def _parse_precision(text: str | None) -> Precision | None:
    """``--precision`` as a :class:`~cayley_heyoka.core.precision.Precision`, or None; bits
    within a scene's limits (``Precision.from_spec``), refused by the option's name."""
    from ..core.errors import OptionError, SceneError
    from ..core.precision import Precision

    if text is None:
        return None
    if text in ("double", "quad"):
        return Precision(text)
    if text.isascii() and text.isdigit() and len(text) < 10:
        try:
            return Precision.from_spec({"bits": int(text)})
        except SceneError as exc:
            raise OptionError("--precision", f"(bits) {exc.constraint}") from None
    raise OptionError("--precision", f"must be double, quad or a number of bits, got {text!r}")


class _Bars:
    """One progress bar per run."""

    def __init__(self, scene: Scene) -> None:
        # The scene's checked grid, in its own precision: each run's times (in its precision,
        # or the closed form's) are placed on it.
        self.t0, self.t1 = scene.time_grid[0], scene.time_grid[-1]
        self.bar = None
        self.label = None

    def update(self, label: str, t: Any) -> None:
        from .show import time_bar

        if label != self.label:
            self.close()
            self.label = label
            self.bar = time_bar(self.t0, self.t1, desc=label)
        self.bar.update_to(t)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
