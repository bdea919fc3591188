"""The benchmark harness runs: a smoke run of every section of validation/BENCHMARKS.md.

Benchmarks are measurements, not tests: nothing here judges a time. This only checks that
``python validation/benchmarks.py --quick`` writes every section with its tables and plots, so
that the one command that regenerates the document keeps working. Peers that are not
installed (scipy, REBOUND) are reported by the harness as such.

The command runs as users run it, in a process of its own: in the test session's process,
after its thousand integrators, the whole quick run took 110 s with heyoka's compile cache
partly filled; alone, 73 s with it empty. Its "users" section, most of that, is smoke-run with
the slow validation (``python -m pytest -m slow``).
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import benchmarks
import pytest
from report_sections import markers

VALIDATION = Path(__file__).resolve().parents[2] / "validation"
SLOW = ("users",)


def quick_run(tmp_path: Path, sections: list[str]) -> None:
    out = tmp_path / "BENCHMARKS.md"
    command = [sys.executable, str(VALIDATION / "benchmarks.py"), "--quick", "--out", str(out)]
    done = subprocess.run([*command, "--only", *sections], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-4000:]
    text = out.read_text()
    for name in ("header", *sections):
        start, end = markers(name)
        assert start in text and end in text, name
        body = text[text.index(start) : text.index(end)]
        if name != "header":
            assert re.search(r"^\|.*\d.*\|$", body, re.M), f"{name}: no table with numbers"
    for link in re.findall(r"\]\((figures/[^)]+\.png)\)", text):
        assert (tmp_path / link).is_file(), link


def test_quick_run_writes_every_section(tmp_path):
    quick_run(tmp_path, [name for name in benchmarks.SECTIONS if name not in SLOW])


@pytest.mark.slow
@pytest.mark.parametrize("section", SLOW)
def test_quick_run_of_the_slow_sections(tmp_path, section):
    quick_run(tmp_path, [section])
