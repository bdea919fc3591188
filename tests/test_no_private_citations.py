"""No tracked file cites the maintainers' private notes, a folder users do not have.

Docs, docstrings, examples, tests and validation scripts cite the memoirs (Cayley 1843, 1846,
1860; Euler 1758; Hamilton 1835) and our own docs; reference values live in the test files and
``validation/orbit_cases.py``.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: The folder, and the names of the notes in it (a citation by name is one too).
PRIVATE = (
    "shared/notes",
    "../shared",
    "hamilton1835.md",
    "cayley1843.md",
    "cayley1846.md",
    "cayley1860.md",
    "euler1758.md",
    "_reference_values.md",
)


def _tracked() -> list[Path]:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    out = subprocess.run(
        ["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True
    ).stdout
    return [ROOT / name for name in out.decode().split("\0") if name]


def test_no_tracked_file_cites_the_private_notes():
    here = Path(__file__).resolve()
    found = []
    for path in _tracked():
        if path == here or not path.is_file():
            continue
        data = path.read_bytes()
        if b"\0" in data[:8192]:  # binary (HDF5, PNG)
            continue
        for number, line in enumerate(data.decode("utf-8", "replace").splitlines(), 1):
            hits = [p for p in PRIVATE if p in line]
            if hits:
                found.append(f"{path.relative_to(ROOT)}:{number}: {hits}")
    assert not found, "private citations:\n" + "\n".join(found)
