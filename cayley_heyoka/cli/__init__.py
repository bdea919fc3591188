"""The ``cayley-heyoka`` command: run scenes, check them, summarise result files.

One module per verb (``run``, ``info``, ``check``, ``reference``, ``plot``, ``sweep``,
``plan``), each
defining its subcommand with the standard library only and importing its workflow (the engine,
hence heyoka; h5py; matplotlib; tqdm) when the command runs: ``--help``, ``--version`` and the
parsing of every command start without them, and no command pays for another's imports.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator
from importlib import import_module

#: The verb modules of this package, in the order ``--help`` lists them; each has
#: ``add_parser(subparsers)``, which sets ``handler`` to the function running the command.
VERBS: tuple[str, ...] = ("run", "info", "check", "reference", "plot", "sweep", "plan")


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``cayley-heyoka`` console script.

    What it prints goes through :class:`~cayley_heyoka.cli.terminal.SafeStream` (text from files
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
    """SIGTERM ends a command as Ctrl-C does (results kept, exit 130). The commands that
    compile also end the process at once on either while LLVM compiles (:func:`compiling`)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    old = signal.signal(signal.SIGTERM, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


@contextlib.contextmanager
def compiling() -> Iterator[None]:
    """:func:`~cayley_heyoka.core.signals.signals_end_compilation` for a command that integrates.

    Entered by the command, not by :func:`main`: the engine imports heyoka, which the commands
    that do not integrate (and ``--help``) never load.
    """
    if threading.current_thread() is not threading.main_thread():
        yield  # the signals are the main thread's (and the engine's switch is process-wide)
        return
    from ..core.signals import signals_end_compilation

    with signals_end_compilation():
        yield


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


class _Version(argparse._VersionAction):
    """``--version``, its text looked up only when asked for: argparse's own action takes it
    when the parser is built, and importing and reading package metadata costs ~15 ms."""

    def __call__(self, parser: argparse.ArgumentParser, *args: object, **kwargs: object) -> None:
        self.version = _version()
        super().__call__(parser, *args, **kwargs)


def _main(argv: list[str] | None) -> int:
    parser = argparse.ArgumentParser(
        prog="cayley-heyoka", description="High-accuracy Taylor integration of classical dynamics."
    )
    parser.add_argument("--version", action=_Version)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in VERBS:
        import_module(f".{name}", __package__).add_parser(sub)
    args = parser.parse_args(argv)
    return args.handler(args)


#: Help of every writing command's ``--overwrite``.
OVERWRITE_HELP = "replace --out even if it is not a file of ours of the same kind"


def destination(args: argparse.Namespace, kind: str) -> bool:
    """Refuse ``--out`` up front (printing why) if it cannot or may not be written."""
    if not args.out:
        return True
    from ..core.files import OutputError, check_destination

    try:
        check_destination(args.out, kind, overwrite=args.overwrite)
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
