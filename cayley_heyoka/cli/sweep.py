"""``cayley-heyoka sweep STUDY.toml --out SWEEP.h5``: a conservation study
(:mod:`cayley_heyoka.workflows.sweep`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from . import add_progress, destination, show_progress

# The backends, written here so that building the parser imports nothing of the sweep;
# tests/test_cli_imports.py holds them equal to study.BACKENDS.
BACKENDS = ("local", "dask")


def add_parser(subparsers: Any) -> None:
    """Add ``sweep`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser(
        "sweep",
        help="integrate a scene over a grid or random ensemble of its numbers (conservation study)",
    )
    p.add_argument("study", type=Path, help="study TOML file")
    p.add_argument("--out", type=Path, help="write the sweep to this HDF5 file")
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace --out even if it is not a sweep file of ours",
    )
    p.add_argument("--backend", choices=BACKENDS, help="override [run] backend")
    p.add_argument("--scheduler", help="a Dask scheduler's address (implies --backend dask)")
    p.add_argument("--workers", type=int, help="threads (local) or LocalCluster processes")
    p.add_argument("--chunk", type=int, help="members per task (Dask) or per batch (local)")
    add_progress(p)
    p.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    return _sweep(args)


def _sweep(args: argparse.Namespace) -> int:
    from ..core.errors import SceneError
    from ..core.files import OutputError, check_destination, file_id
    from ..workflows.study import load_study

    try:
        if args.out:
            check_destination(args.out, "sweep", overwrite=args.overwrite)
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    try:
        study = load_study(args.study)
    except (SceneError, OSError) as exc:
        print(f"error: {args.study}: {exc}", file=sys.stderr)
        return 2
    # A sweep of another study is not replaced; its [run] table (where and how it runs) is not
    # what it is.
    if not destination(args, "sweep", holding=("study", study.to_dict()), ignoring=("run",)):
        return 2
    from ..workflows.sweep import run_sweep  # heyoka: only once the study is known to be good

    bar = None
    if show_progress(args):
        from tqdm import tqdm

        bar = tqdm(total=study.size, unit="member", file=sys.stderr, dynamic_ncols=True)
    before = file_id(args.out) if args.out else None
    try:
        try:
            result = run_sweep(
                study,
                out=args.out,
                backend=args.backend,
                scheduler=args.scheduler,
                workers=args.workers,
                chunk=args.chunk,
                progress=(lambda done, total: bar.update(done - bar.n)) if bar else None,
            )
        finally:
            if bar:  # before any message: a bar drawn after it would end stderr
                bar.close()
    except SceneError as exc:
        print(f"error: {args.study}: {exc}", file=sys.stderr)
        return 2
    except OutputError as exc:  # the file could not be written: the previous one stays
        if getattr(exc, "result", None) is not None:  # computed, and shown, not saved
            print(exc.result.summary())
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        if args.out and file_id(args.out) not in (None, before):  # written as it stopped
            print(f"\ninterrupted: what was computed is in {args.out}", file=sys.stderr)
            return 130
        raise
    except (RuntimeError, OSError) as exc:  # a backend that failed midway: the file is kept
        print(f"error: {exc}", file=sys.stderr)
        if args.out and args.out.exists():
            print(f"what was computed is in {args.out}", file=sys.stderr)
        return 1
    print(result.summary())
    if args.out:
        print(f"sweep written to {args.out}")
    return 0 if result.completed.all() else 1
