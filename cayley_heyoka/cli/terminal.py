"""What the command line prints: text from scene and result files, made safe for a terminal.

A scene's title, an event name or a label comes from a file, and a file can hold escape
sequences that recolour, retitle or rewrite a terminal. Everything the ``cayley-heyoka``
command prints goes through :class:`SafeStream`, which writes control characters as visible
escapes (``\\x1b``), as :func:`repr` would.
"""

from __future__ import annotations

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
    """

    def __init__(self, stream: TextIO, allow_cr: bool = False) -> None:
        self.stream = stream
        self.allow_cr = allow_cr

    def write(self, text: str) -> int:
        if self.allow_cr and text.startswith("\r"):
            self.stream.write("\r" + printable(text[1:]))
        else:
            self.stream.write(printable(text))
        return len(text)

    def __getattr__(self, name: str) -> object:
        # flush, fileno, isatty, encoding ...: those of the stream underneath.
        return getattr(self.stream, name)
