"""REPORT.md is shared by several validation scripts: each owns one marked section.

A section is the text between ``<!-- section:NAME -->`` and ``<!-- /section:NAME -->``;
:func:`write_section` replaces it in place, or appends it when the file or the section is absent,
leaving every other section untouched.
"""

from __future__ import annotations

from pathlib import Path


def markers(name: str) -> tuple[str, str]:
    return f"<!-- section:{name} -->", f"<!-- /section:{name} -->"


def replace_section(document: str, name: str, body: str) -> str:
    """``document`` with section ``name`` set to ``body`` (appended if absent)."""
    start, end = markers(name)
    block = f"{start}\n{body.strip(chr(10))}\n{end}"
    i = document.find(start)
    j = document.find(end, i + len(start)) if i >= 0 else -1
    if i >= 0 and j >= 0:
        return document[:i] + block + document[j + len(end) :]
    if i >= 0 or document.find(end) >= 0:
        raise ValueError(f"section {name!r}: unbalanced markers in the document")
    prefix = document.rstrip("\n")
    return f"{prefix}\n\n{block}\n" if prefix else f"{block}\n"


def write_section(path: Path, name: str, body: str) -> Path:
    """Replace (or append) section ``name`` of the file at ``path`` with ``body``."""
    path = Path(path)
    old = path.read_text() if path.exists() else ""
    path.write_text(replace_section(old, name, body))
    return path


def machine_lines(total_seconds: float, workers: int, mode: str) -> list[str]:
    """The report's machine and run lines: platform, cores, worker processes, versions; mode,
    total wall time and when it was generated."""
    import os
    import platform
    import time

    import heyoka
    import mpmath
    import numpy as np

    return [
        f"* Machine: {platform.platform()}, {os.cpu_count()} cores, {workers} worker processes; "
        f"Python {platform.python_version()}, heyoka {heyoka.__version__}, "
        f"numpy {np.__version__}, mpmath {mpmath.__version__}.",
        f"* Mode: {mode}; total wall time {total_seconds / 60:.1f} min; generated "
        f"{time.strftime('%Y-%m-%d %H:%M %Z')}.",
    ]
