"""``cayley-heyoka info FILE``: the summary of a result, sweep or check file.

It reads HDF5 (h5py, numpy) and nothing of the engine: a double result is summarised without
importing heyoka (a quad or multiprecision one needs heyoka's number types to be read).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any


def add_parser(subparsers: Any) -> None:
    """Add ``info`` to the ``cayley-heyoka`` command."""
    p = subparsers.add_parser("info", help="summarise a result file")
    p.add_argument("result", type=Path)
    p.add_argument(
        "--variables",
        action="store_true",
        help="also say what each output and monitor of a result or sweep file is",
    )
    p.set_defaults(handler=command)


def command(args: argparse.Namespace) -> int:
    """Run the command; returns its exit code."""
    from ..core.files import ResultFileError, identify

    path = args.result
    try:
        kind = identify(path)
        if kind == "sweep":
            from ..workflows.sweep_result import SweepResult

            sweep = SweepResult.load(path)
            text = sweep.summary()
            if args.variables:
                from .show import variable_lines

                names = (*sweep.final_names, *sweep.drift)
                text += "\n" + "\n".join(variable_lines(sweep.study["scene"], names))
        elif kind == "check":
            from ..core.consistency import CheckReport

            text = CheckReport.load(path).text()
            if args.variables:
                text += "\n  variables     (a check file has rows of quantities, not variables)"
        else:  # a result, or whatever it is: the loader says what is wrong with it
            from ..core.result import Result
            from .show import summary, variable_lines

            result = Result.load(path)
            text = summary(result)
            if args.variables:
                names = (*result.variables, *result.monitors)
                text += "\n" + "\n".join(variable_lines(result.scene, names))
    except ResultFileError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(text)
    return 0
