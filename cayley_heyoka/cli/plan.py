"""``cayley-heyoka plan SCENE.toml --error E``: the cheapest route to an error, from pilots."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def add_parser(subparsers: Any) -> None:
    """Add ``plan`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser(
        "plan",
        help="pilot a scene's formulations in double and quad and recommend the cheapest that "
        "reaches an error (exit 1 if none does)",
    )
    p.add_argument("scene", type=Path, help="scene TOML file")
    p.add_argument(
        "--error",
        required=True,
        help="the relative error wanted at the end (a decimal number > 0, read exactly)",
    )
    p.add_argument(
        "--quantity",
        choices=("state", "invariants"),
        default="state",
        help="what the error bounds: the state along the motion (default) or the drift of "
        "the conserved quantities",
    )
    p.add_argument(
        "--formulation",
        action="append",
        metavar="NAME",
        help="only this formulation (repeatable; default: every one the scene allows)",
    )
    p.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    return _plan(args)


#: The option of each argument of :func:`~cayley_heyoka.workflows.planner.plan`.
_OPTIONS = {"error": "--error", "quantity": "--quantity", "formulations": "--formulation"}


def _plan(args: argparse.Namespace) -> int:
    from ..core.scene import load_scene
    from ..workflows.planner import RequestError, plan

    try:
        scene = load_scene(args.scene)
        result = plan(
            scene,
            args.error,
            args.quantity,
            args.formulation,
            progress=lambda line: print(line, file=sys.stderr),
        )
    except RequestError as exc:  # the command line's fault, not the scene's
        print(f"error: {_OPTIONS[exc.parameter]}: {exc.rule}", file=sys.stderr)
        return 2
    except ValueError as exc:  # SceneError, nothing could be piloted
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    print(result.text())
    return 0 if result.recommended is not None else 1
