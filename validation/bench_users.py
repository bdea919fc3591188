"""Section "users" of BENCHMARKS.md: every path a user runs, against raw heyoka's floor.

Each ``users_<topic>.py`` beside this file measures its rows (validation/users_common.py: ours
÷ the floor, timed interleaved in one process, median and spread over the repeats); this
section gathers them into one table. Run alone: ``python validation/benchmarks.py --only users``.
"""

from __future__ import annotations

import importlib
import time
from pathlib import Path

import users_common
from users_common import Row, table

HERE = Path(__file__).resolve().parent

TOPICS = ("engine", "orbit", "rotation", "hamilton", "reference", "cli")


def run(quick: bool, figures: Path) -> str:
    rows: list[Row] = []
    missing = []
    for topic in TOPICS:
        path = HERE / f"users_{topic}.py"
        if not path.exists():
            missing.append(topic)
            continue
        t0 = time.perf_counter()
        rows += importlib.import_module(f"users_{topic}").rows(quick)
        print(f"users_{topic}: {time.perf_counter() - t0:.0f} s", flush=True)
    judged = [r for r in rows if r.met is not None]
    met = sum(bool(r.met) for r in judged)
    lines = [
        "## What users run, against raw heyoka",
        "",
        "Each row times one path a user runs — a whole `run()`, a sweep, a reference, the "
        "command line's start — against its floor: the same work written directly against "
        "heyoka (or, for references, an absolute budget), interleaved in one process; the "
        "ratio is the median over the repeats, with its least and greatest. "
        f"{met} of {len(judged)} rows meet their target. Each row's script: "
        "`validation/users_<topic>.py` (alone: `python validation/users_<topic>.py`).",
        "",
        table(rows),
    ]
    if missing:
        lines += ["", f"Not measured (no script): {', '.join(missing)}."]
    if users_common.SKIPPED:
        lines += ["", f"Not measured here: {'; '.join(users_common.SKIPPED)}."]
    return "\n".join(lines)
