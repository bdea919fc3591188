"""``cayley-heyoka check SCENE.toml``: a scene against an independent computation."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from . import OVERWRITE_HELP, destination


def add_parser(subparsers: Any) -> None:
    """Add ``check`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser(
        "check", help="check a scene against an independent computation (exit 1 if it fails)"
    )
    p.add_argument("scene", type=Path, help="scene TOML file")
    p.add_argument("--out", type=Path, help="write the check's rows and series to HDF5")
    p.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="an option of the scene's check, e.g. upsilon0=2.5 or twin=quaternion "
        "(repeatable; docs/scenes.md, 'Consistency checks')",
    )
    p.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    return _check(args)


def _check(args: argparse.Namespace) -> int:
    from ..core.consistency import parse_settings
    from ..core.errors import IntegrationError
    from ..core.files import OutputError
    from ..core.scene import load_scene
    from ..core.signals import held_signals
    from ..workflows.checks import check_scene

    if not destination(args, "check"):
        return 2
    try:
        report = check_scene(load_scene(args.scene), parse_settings(args.set))
    except ValueError as exc:  # SceneError, or a check that cannot be carried through
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 2
    except IntegrationError as exc:  # a run the check needs stopped early
        print(f"error: {args.scene}: {exc}", file=sys.stderr)
        return 1
    # The check is done: a signal from here on takes effect once it is saved and shown.
    with held_signals():
        if args.out:
            try:
                report.save(args.out)
            except OutputError as exc:
                print(report.text())
                print(f"error: {exc}", file=sys.stderr)
                return 1
        print(report.text())
        if args.out:
            print(f"check written to {args.out}")
        return 0 if report.passed else 1
