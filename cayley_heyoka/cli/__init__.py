"""The ``cayley-heyoka`` command: run scenes, check them, summarise result files.

One module per verb (``run``, ``info``, ``check``, ``reference``, ``plot``, ``sweep``,
``plan``), each
defining its subcommand with the standard library only and importing its workflow (the engine,
hence heyoka; h5py; matplotlib; tqdm) when the command runs: ``--help``, ``--version`` and the
parsing of every command start without them, and no command pays for another's imports.
"""

from __future__ import annotations

import os
import sys
from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # argparse is imported by main, after the signal policy is in place
    import argparse

#: The verb modules of this package, in the order ``--help`` lists them; each has
#: ``add_parser(subparsers)``, which sets ``handler`` to the function running the command.
VERBS: tuple[str, ...] = ("run", "info", "check", "reference", "plot", "sweep", "plan")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``cayley-heyoka`` console script.

    The signal policy (:mod:`cayley_heyoka.core.signals`) holds from the first line: a
    Ctrl-C or SIGTERM before any work ends the command at once with exit 130, one during the
    work stops it cleanly with its results. What it prints goes through
    :class:`~cayley_heyoka.cli.terminal.SafeStream` (text from files cannot drive the
    terminal, and a report that cannot be written — stdout closed, full or a closed pipe —
    changes nothing of what the command does or returns).
    """
    _standard_descriptors()  # before anything opens a file, the signal policy's pipe included
    from ..core.signals import command_signals

    with command_signals() as policy:
        from .terminal import SafeStream

        out, err = sys.stdout, sys.stderr
        safe_err = SafeStream(err, allow_cr=True, label="stderr")
        safe_out = SafeStream(out, label="stdout", warn=safe_err)
        sys.stdout, sys.stderr = safe_out, safe_err
        try:
            try:
                code = _main(argv)
            except KeyboardInterrupt:  # in a command that keeps nothing, or kept it already
                policy.finish()
                print("interrupted", file=sys.stderr)
                code = 130
            finally:
                policy.finish()  # a second Ctrl-C while the command ends: exit 130 at once
            # Output held in a buffer shows here, not in the interpreter's exit; a stream that
            # cannot take it is pointed at /dev/null, so that the interpreter's final flush
            # does not fail (and change the exit status) either.
            for safe, stream in ((safe_out, out), (safe_err, err)):
                if not safe.flush_or_drop():
                    _silence(stream)
            return code
        finally:
            sys.stdout, sys.stderr = out, err


def _standard_descriptors() -> None:
    """Open /dev/null on a standard descriptor (0, 1, 2) that is closed.

    The next file opened would otherwise take that number, and whatever writes to stdout or
    stderr below Python (heyoka's and HDF5's C++ logs) would write into it: into a result file.
    """
    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            null = os.open(os.devnull, os.O_RDWR)
            if null != fd:  # a lower one was closed too and took it: move it up
                os.dup2(null, fd)
                os.close(null)


def _silence(stream: object) -> None:
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except (OSError, AttributeError, ValueError):  # not a real file (a test's capture), None
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
    import argparse

    class Version(argparse._VersionAction):
        """``--version``, its text looked up only when asked for: argparse's own action takes
        it when the parser is built, and importing and reading package metadata costs ~15 ms."""

        def __call__(self, parser: argparse.ArgumentParser, *args: Any, **kwargs: Any) -> None:
            self.version = _version()
            super().__call__(parser, *args, **kwargs)

    parser = argparse.ArgumentParser(
        prog="cayley-heyoka", description="High-accuracy Taylor integration of classical dynamics."
    )
    parser.add_argument("--version", action=Version)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in VERBS:
        import_module(f".{name}", __package__).add_parser(sub)
    args = parser.parse_args(argv)
    return args.handler(args)


#: Help of every writing command's ``--overwrite``.
OVERWRITE_HELP = "replace --out even if it is not a file of ours of the same kind"


def destination(
    args: argparse.Namespace,
    kind: str,
    holding: tuple[str, Any] | None = None,
    ignoring: tuple[str, ...] = (),
) -> bool:
    """Refuse ``--out`` up front (printing why) if it cannot or may not be written, or with
    ``holding`` if it holds another scene's file (:func:`.core.files.check_destination`)."""
    if not args.out:
        return True
    from ..core.files import OutputError, check_destination

    try:
        check_destination(
            args.out, kind, overwrite=args.overwrite, holding=holding, ignoring=ignoring
        )
    except OutputError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return False
    return True


def add_progress(parser: argparse.ArgumentParser) -> None:
    """``--progress`` / ``--no-progress`` (default: a bar when stderr is a terminal)."""
    bar = parser.add_mutually_exclusive_group()
    bar.add_argument("--progress", action="store_true", default=None, help="show a progress bar")
    bar.add_argument("--no-progress", dest="progress", action="store_false")


def show_progress(args: argparse.Namespace) -> bool:
    """Whether the command draws a progress bar."""
    return sys.stderr.isatty() if args.progress is None else args.progress


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
