"""What the command line prints: text from scene and result files, made safe for a terminal.

A scene's title, an event name or a label comes from a file, and a file can hold escape
sequences that recolour, retitle or rewrite a terminal. Everything the ``cayley-heyoka``
command prints goes through :class:`SafeStream`, which writes control characters as visible
escapes (``\\x1b``), as :func:`repr` would.
"""

from __future__ import annotations

import contextlib
import re
from typing import TextIO

# C0 controls but tab and newline, DEL, C1 controls, and the bidirectional overrides and
# isolates that reorder what a terminal shows.
_UNSAFE = re.compile("[\x00-\x08\x0b-\x1f\x7f-\x9f\u200e\u200f\u202a-\u202e\u2066-\u2069]")


def printable(text: str) -> str:
    """``text`` with every control character written as an escape (``"\\x1b"``)."""
    return _UNSAFE.sub(_escape, text)


def _escape(match: re.Match[str]) -> str:
    c = match.group()
    return f"\\x{ord(c):02x}" if ord(c) < 0x100 else f"\\u{ord(c):04x}"


class SafeStream:
    """A text stream that passes what is written through :func:`printable`.

    A carriage return is let through at the start of a write to a stream that ``allow_cr``:
    that is how progress bars (tqdm) redraw their line on stderr.

    What cannot be written (a stream that is None because its descriptor was closed at start,
    a pipe whose reader has gone, a full disk, ``/dev/full``) is dropped, and so is everything
    after it: a report that cannot be shown changes nothing of what the command computes,
    writes to its files or returns. The first failure other than a closed pipe (which
    ``| head`` closes on purpose) is said once on ``warn``, naming the stream as ``label``.
    """

    def __init__(
        self,
        stream: TextIO | None,
        allow_cr: bool = False,
        *,
        label: str = "the output",
        warn: TextIO | None = None,
    ) -> None:
        self.stream = stream
        self.allow_cr = allow_cr
        self.label = label
        self.warn = warn
        self.failed: BaseException | None = None

    def write(self, text: str) -> int:
        if self.allow_cr and text.startswith("\r"):
            self._do("write", "\r" + printable(text[1:]))
        else:
            self._do("write", printable(text))
        return len(text)

    def flush(self) -> None:
        self._do("flush")

    def flush_or_drop(self) -> bool:
        """Flush; whether everything written so far has reached the stream."""
        self.flush()
        return self.failed is None

    def isatty(self) -> bool:
        return self.stream is not None and self.failed is None and self.stream.isatty()

    def _do(self, method: str, *args: str) -> None:
        if self.failed is not None or self.stream is None:
            return
        try:
            getattr(self.stream, method)(*args)
        except (OSError, ValueError) as exc:  # ValueError: a stream closed in Python
            self.failed = exc
            if self.warn is not None and not isinstance(exc, BrokenPipeError):
                with contextlib.suppress(OSError, ValueError):
                    self.warn.write(f"warning: {self.label} could not be written: {exc}\n")

    def __getattr__(self, name: str) -> object:
        # fileno, encoding ...: those of the stream underneath.
        return getattr(self.stream, name)
