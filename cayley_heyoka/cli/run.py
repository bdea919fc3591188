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
    from ..core.signals import held_signals
    from .show import summary, time_bar

    if not destination(args, "result"):
        return 2
    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    if not destination(args, "result", holding=("scene", scene.to_dict())):
        return 2  # a result of another scene
    from ..core.engine import run  # heyoka: only once the scene is known to be good

    bar = None
    if show_progress(args):
        bar = time_bar(scene.time_grid[0], scene.time_grid[-1])
    try:
        try:
            result = run(scene, progress=bar.update_to if bar else None)
        finally:
            if bar:  # before any message: a bar drawn after it would end stderr
                bar.close()
        code, why = 0, None
    except Interrupted as exc:
        result, code, why = exc.result, 130, f"\n{exc}"
    except IntegrationError as exc:
        result, code, why = exc.result, 1, f"error: {exc}"
    except SceneError as exc:  # found when the model is built (expressions, event names)
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    # The run is over: a signal from here on (a second Ctrl-C) takes effect once its result
    # is saved and reported.
    with held_signals():
        if why:
            print(why, file=sys.stderr)
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
