"""``cayley-heyoka plot FILE --kind KIND [--out F.png]``: a result or sweep file as a PNG
(:mod:`cayley_heyoka.workflows.plots`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def add_parser(subparsers: Any) -> None:
    """Add ``plot`` to the ``cayley-heyoka`` command."""
    parser = subparsers.add_parser(
        "plot",
        help="draw a result or sweep file as a PNG",
        description="Draw a result or sweep file: drift against time (log-log), or a plot "
        "the result's model family draws (a rigid body's polhode and invariable-plane "
        "crossings, an orbit's path).",
    )
    parser.add_argument("file", type=Path, help="result or sweep HDF5 file")
    # No fixed choices: a family of another package may add kinds; the plot says what the
    # result supports when a kind is not one of them.
    parser.add_argument(
        "--kind",
        required=True,
        help="what to draw: drift, or one of the result's family's plots "
        "(ours: polhode, crossings, orbit)",
    )
    parser.add_argument(
        "--out", type=Path, help="figure file to write (default: FILE's stem + _KIND.png)"
    )
    parser.add_argument(
        "--overwrite", action="store_true", help="replace --out even if it is not a plot of ours"
    )
    parser.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    from ..core.files import OutputError, ResultFileError, WriteFailed, check_destination
    from ..workflows.plots import PlotError, plot_file

    path = Path(args.file)
    try:
        out = args.out or path.with_name(f"{path.stem}_{args.kind}.png")
        check_destination(out, "plot", overwrite=args.overwrite)
        out = plot_file(args.file, args.kind, out)
    except PlotError as exc:
        print(f"error: {args.file}: {exc}", file=sys.stderr)
        return 2
    except WriteFailed as exc:  # drawn, but the figure could not be written (a full disk)
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except (ImportError, OSError, OutputError, ResultFileError) as exc:  # says which file
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"plot written to {out}")
    return 0
