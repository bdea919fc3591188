"""``cayley-heyoka run SCENE.toml [--out RESULT.h5]``: integrate a scene file."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from . import OVERWRITE_HELP, add_progress, destination, show_progress


def add_parser(subparsers: Any) -> None:
    """Add ``run`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser("run", help="integrate a scene file")
    p.add_argument("scene", type=Path, help="scene TOML file")
    p.add_argument("--out", type=Path, help="write the result to this HDF5 file")
    p.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    add_progress(p)
    p.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    return _run(args)


def _run(args: argparse.Namespace) -> int:
    from ..core.errors import IntegrationError, Interrupted, SceneError
    from ..core.files import OutputError
    from ..core.scene import load_scene
    from .show import summary, time_bar

    if not destination(args, "result"):
        return 2
    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    from ..core.engine import run  # heyoka: only once the scene is known to be good

    bar = None
    if show_progress(args):
        grid = scene.output.time_grid(scene.integrator.precision)
        bar = time_bar(float(grid[0]), float(grid[-1]))
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
