"""The ``cayley-heyoka`` command: run scenes, check them, summarise result files."""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from importlib import import_module
from pathlib import Path
from typing import Any

import numpy as np

from .checks import check_scene, parse_settings
from .engine import run, signals_end_compilation
from .errors import IntegrationError, Interrupted, SceneError
from .files import OutputError, ResultFileError, check_destination, identify
from .result import Result
from .scene import load_scene

#: Modules that each add one subcommand through ``add_command(subparsers)``.
WORKFLOW_COMMANDS: tuple[str, ...] = (
    "reference_run",
    "plots",
    "sweep",
)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``cayley-heyoka`` console script.

    What it prints goes through :class:`~cayley_heyoka.terminal.SafeStream` (text from files
    cannot drive the terminal); output cut short by a closed pipe (``| head``) ends quietly.
    """
    from .terminal import SafeStream

    out, err = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = SafeStream(out), SafeStream(err, allow_cr=True)
    try:
        with _interruptible():
            code = _main(argv)
        out.flush()  # a closed pipe shows here, not in the interpreter's exit
        return code
    except KeyboardInterrupt:  # before anything was computed, or in a command that keeps nothing
        print("interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # Nothing more can be printed; point stdout at /dev/null so that the interpreter's
        # final flush does not complain either.
        _silence(out)
        return 1
    finally:
        sys.stdout, sys.stderr = out, err


@contextlib.contextmanager
def _interruptible() -> Iterator[None]:
    """SIGTERM ends a command as Ctrl-C does (results kept, exit 130), and either ends the
    process at once while LLVM compiles (:func:`~cayley_heyoka.engine.signals_end_compilation`)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        with signals_end_compilation():
            yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _silence(stream: object) -> None:
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
    except (OSError, AttributeError, ValueError):  # not a real file (a test's capture)
        pass


def _version() -> str:
    from importlib import metadata

    def of(name: str) -> str:
        try:
            return metadata.version(name)
        except metadata.PackageNotFoundError:
            return "unknown"

    return f"cayley-heyoka {of('cayley_heyoka')} (heyoka {of('heyoka')})"


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(
        prog="cayley-heyoka", description="High-accuracy Taylor integration of classical dynamics."
    )
    parser.add_argument("--version", action="version", version=_version())
    sub = parser.add_subparsers(dest="command", required=True)
    p_run = sub.add_parser("run", help="integrate a scene file")
    p_run.add_argument("scene", type=Path, help="scene TOML file")
    p_run.add_argument("--out", type=Path, help="write the result to this HDF5 file")
    p_run.add_argument("--overwrite", action="store_true", help=_OVERWRITE_HELP)
    bar = p_run.add_mutually_exclusive_group()
    bar.add_argument("--progress", action="store_true", default=None, help="show a progress bar")
    bar.add_argument("--no-progress", dest="progress", action="store_false")
    p_info = sub.add_parser("info", help="summarise a result file")
    p_info.add_argument("result", type=Path)
    p_check = sub.add_parser(
        "check", help="check a scene against an independent computation (exit 1 if it fails)"
    )
    p_check.add_argument("scene", type=Path, help="scene TOML file")
    p_check.add_argument("--out", type=Path, help="write the check's rows and series to HDF5")
    p_check.add_argument("--overwrite", action="store_true", help=_OVERWRITE_HELP)
    p_check.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="an option of the scene's check, e.g. upsilon0=2.5 or twin=quaternion "
        "(repeatable; docs/scenes.md, 'Consistency checks')",
    )
    # The workflows register their own subcommands (each sets ``handler``); their modules
    # import heyoka, h5py or matplotlib only when the command runs.
    for name in WORKFLOW_COMMANDS:
        import_module(f".{name}", __package__).add_command(sub)
    args = parser.parse_args(argv)

    if getattr(args, "handler", None) is not None:
        return args.handler(args)
    if args.command == "info":
        return _info(args.result)
    if args.command == "check":
        return _check(args)
    return _run(args)


#: Help of every writing command's ``--overwrite``.
_OVERWRITE_HELP = "replace --out even if it is not a file of ours of the same kind"


def _info(path: Path) -> int:
    from .checks import CheckReport
    from .sweep_result import SweepResult

    try:
        kind = identify(path)
        if kind == "sweep":
            text = SweepResult.load(path).summary()
        elif kind == "check":
            text = CheckReport.load(path).text()
        else:  # a result, or whatever it is: the loader says what is wrong with it
            text = summary(Result.load(path))
    except ResultFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(text)
    return 0


def _destination(args: argparse.Namespace, kind: str) -> bool:
    """Refuse ``--out`` up front (printing why) if it cannot or may not be written."""
    if not args.out:
        return True
    try:
        check_destination(args.out, kind, overwrite=args.overwrite)
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return False
    return True


def _check(args: argparse.Namespace) -> int:
    if not _destination(args, "check"):
        return 2
    try:
        report = check_scene(load_scene(args.scene), parse_settings(args.set))
    except ValueError as exc:  # SceneError, or a check that cannot be carried through
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    except IntegrationError as exc:  # a run the check needs stopped early
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 1
    if args.out:
        try:
            report.save(args.out)
        except OutputError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 1
    print(report.text())
    if args.out:
        print(f"check written to {args.out}")
    return 0 if report.passed else 1


def _run(args: argparse.Namespace) -> int:
    if not _destination(args, "result"):
        return 2
    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    show = sys.stderr.isatty() if args.progress is None else args.progress
    bar = _progress_bar(scene) if show else None
    try:
        result = run(scene, progress=bar.update_to if bar else None)
        code = 0
    except Interrupted as exc:
        result, code = exc.result, 130
        print(f"\n{exc}", file=sys.stderr)
    except IntegrationError as exc:
        result, code = exc.result, 1
        print(f"error: {exc}", file=sys.stderr)
    except SceneError as exc:  # found when the model is built (expressions, event names)
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    finally:
        if bar:
            bar.close()
    if args.out:
        try:
            result.save(args.out)
        except OutputError as exc:
            print(summary(result))
            print(f"error: {exc}", file=sys.stderr)
            return 1
    print(summary(result))
    if args.out:
        print(f"result written to {args.out}")
    return code


def _progress_bar(scene):
    grid = scene.output.time_grid(scene.integrator.precision)
    return time_bar(float(grid[0]), float(grid[-1]))


def time_bar(t0: float, t1: float, desc: str | None = None, file: Any = None) -> Any:
    """A progress bar of simulated time on stderr: ``t = 3141.59 of 6283.19  50%``.

    ``update_to(t)`` moves it to time ``t``; times are shown to six significant digits (the
    bar's own counter, t − t0, would print every digit of a float).
    """
    from tqdm import tqdm

    class Bar(tqdm):
        @property
        def format_dict(self) -> dict:
            d = super().format_dict
            d["t_now"], d["t_end"] = f"{t0 + d['n']:.6g}", f"{t1:.6g}"
            return d

        def update_to(self, t: float) -> None:
            self.n = min(max(float(t) - t0, 0.0), self.total)
            self.refresh() if self.n >= self.total else self.update(0)

    label = f"{desc}: " if desc else ""
    return Bar(
        total=t1 - t0,
        file=file or sys.stderr,
        mininterval=0.2,
        dynamic_ncols=True,
        bar_format=label + "t = {t_now} of {t_end} {percentage:4.0f}%|{bar}| {elapsed}<{remaining}",
    )


def summary(result: Result) -> str:
    """A one-screen account of a run: counts, timing, drifts, events."""
    meta, counters = result.metadata, result.counters
    title = result.scene.get("title") or "(untitled scene)"
    lines = [title, ""]
    status = "completed" if result.success else "STOPPED EARLY"
    t_last = f"{float(result.t[-1]):.6g}" if len(result.t) else "-"
    lines.append(f"  status        {status}: {result.message}")
    lines.append(
        f"  precision     {result.precision.name}, tolerance {meta.get('tolerance')}, "
        f"order {meta.get('order')}"
    )
    lines.append(f"  outputs       {len(result.t)} times, last t = {t_last}")
    for name, value in counters.items():
        lines.append(f"  {name:<13} {value}")
    ref = meta.get("reference")
    if ref and ref.get("attempts"):
        last = ref["attempts"][-1]
        verdict = "certified" if ref["certified"] else "NOT certified"
        lines.append(
            f"  reference     {verdict} to {ref['digits']} digits: largest scaled error "
            f"{last['scaled_error']:.2e} against {last['compared_with']}"
        )
    wall = meta.get("wall_seconds", float("nan"))
    compile_s = meta.get("compile_seconds", 0.0)
    cached = " (compiled code from cache)" if meta.get("compiled_from_cache") else ""
    lines.append(f"  wall time     {wall:.3f} s, of which compiling {compile_s:.3f} s{cached}")
    steps = counters.get("steps", 0)
    if steps and wall - compile_s > 0:
        lines.append(f"  throughput    {steps / (wall - compile_s):,.0f} steps/s (incl. recording)")
    if result.monitors:
        lines.append("  monitors      final relative drift (conserved) or largest value:")
        for name, arr in result.monitors.items():
            if name in result.conserved and len(arr):
                d = float(np.max(np.abs(result.drift(name)[-1])))
                lines.append(f"    {name:<20} {d:.3e}")
            elif len(arr):
                lines.append(f"    {name:<20} largest |value| {_sci(np.max(np.abs(arr)))}")
    for name, log in result.events.items():
        labels, counts = np.unique(log.label, return_counts=True)
        detail = ", ".join(f"{lab}: {c}" for lab, c in zip(labels, counts, strict=True))
        lines.append(f"  event {name:<12} {len(log)} occurrences ({detail or 'none'})")
    return "\n".join(lines)


def _sci(value: Any) -> str:
    """``value`` to four digits; a quad or MPFR number beyond double's range is not 'inf'."""
    if np.isfinite(x := float(value)):
        return f"{x:.3e}"
    import mpmath

    return mpmath.nstr(mpmath.mpf(str(value)), 4, min_fixed=0, max_fixed=0)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
