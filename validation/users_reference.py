"""``cayley-heyoka reference`` as a user runs it: the row of issue 16's table, and the projectile.

Run:  python validation/users_reference.py [--quick]

Rows (validation/users_common.py's ``Row``):

1. The issue's case: a torque-free body (examples/free_body.toml, its invariable-plane
   crossings included) at 30 digits over 10⁴ periods (the period from the closed form) with
   2 000 output times, timed as the command a user runs (a new process). Its floor is an
   absolute target, 60 s on this 2-core machine, so the ratio is wall ÷ 60 s. The note gives
   the wall and CPU seconds (the command and its worker processes): on a shared machine the
   wall time carries the other processes' load, the CPU time does not.
2. Hamilton's projectile (examples/projectile.toml) at 30 digits: the closed form ÷ the
   integration it replaces (``--certificate integrate``), timed interleaved.
3. (full run only) The free body over 10 periods, 100 outputs, at 30 digits: the closed form ÷
   the integration it replaces, interleaved.
4. The reference's unit of work, ``FreeRigidBody.at`` at the 41 digits a 30-digit file needs
   (128 bits), at times spread over 10⁴ periods: CPU seconds per call with mpmath on gmpy2 ÷
   pure-Python mpmath (``MPMATH_NOGMPY=1``), each in its own process, alternately.

``--quick`` (the smoke run): 10 periods and 100 outputs in row 1, two repeats, no row 3.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import mpmath
from users_common import Row, interleaved, table

from cayley_heyoka.reference import FreeRigidBody

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

EXAMPLES = ROOT / "examples"
#: The issue's target for the torque-free body's reference, on this 2-core machine.
TARGET_SECONDS = 60.0
DIGITS = 30


def free_body_scene(periods: int, outputs: int, where: Path) -> Path:
    """examples/free_body.toml over ``periods`` periods of its rates, ``outputs`` times."""
    text = (EXAMPLES / "free_body.toml").read_text()
    body = FreeRigidBody(("1.0", "1.5", "2.5"), ("0.125", "0.25", "1.0"), dps=30)
    stop = mpmath.nstr(periods * body.period, 20)
    times = f"times = {{ start = 0.0, stop = {stop}, count = {outputs} }}"
    text, n = re.subn(r"times = \{[^}]*\}", times, text)
    assert n == 1 and "inertia = [1.0, 1.5, 2.5]" in text and "rates = [0.125, 0.25, 1.0]" in text
    path = where / f"free_body_{periods}.toml"
    path.write_text(text)
    return path


def command(scene: Path, out: Path, *extra: str) -> list[str]:
    """The command line a user types, run by this interpreter on this source tree."""
    return [
        *(sys.executable, "-m", "cayley_heyoka.cli", "reference", str(scene)),
        *("--digits", str(DIGITS), "--out", str(out), "--no-progress", "--overwrite", *extra),
    ]


def timed(argv: list[str]) -> tuple[float, float, str]:
    """Wall and CPU seconds (the process and the workers it waited for) of one command."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(argv, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed:\n{done.stdout}\n{done.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, done.stdout


def free_body_row(quick: bool, where: Path) -> Row:
    periods, outputs, repeats = (10, 100, 2) if quick else (10**4, 2000, 5)
    scene = free_body_scene(periods, outputs, where)
    walls, cpus, out = [], [], ""
    load = os.getloadavg()[0]  # the other processes' share of the cores, for the reader
    for _ in range(repeats):
        wall, cpu, out = timed(command(scene, where / "ref.h5"))
        walls.append(wall)
        cpus.append(cpu)
    digits = re.search(r"certified: ([\d.]+) digits", out)
    return Row(
        what=(
            f"`cayley-heyoka reference` of a torque-free body, {DIGITS} digits, "
            f"{periods:g} periods, {outputs} outputs (crossings included)"
        ),
        ratios=[w / TARGET_SECONDS for w in walls],
        target=1.0,
        floor=f"an absolute {TARGET_SECONDS:g} s",
        note=(
            f"wall {statistics.median(walls):.1f} s ({min(walls):.1f}–{max(walls):.1f}), "
            f"CPU {statistics.median(cpus):.1f} s on {os.cpu_count()} cores (load average "
            f"{load:.1f} before, {os.getloadavg()[0]:.1f} after); closed form, "
            f"{digits.group(1) if digits else '?'} digits certified; {repeats} repeats"
        ),
        seconds={"wall": statistics.median(walls), "cpu": statistics.median(cpus)},
    )


def versus_integration(what: str, scene: Path, where: Path, repeats: int) -> Row:
    """The closed form's command ÷ the same command integrating, interleaved."""
    ours = command(scene, where / "closed.h5")
    floor = command(scene, where / "integrated.h5", "--certificate", "integrate")
    ratios, best_ours, best_floor = interleaved(
        lambda: timed(ours), lambda: timed(floor), repeats=repeats
    )
    return Row(
        what=what,
        ratios=ratios,
        target=1.0,
        floor="the same command integrating (`--certificate integrate`)",
        note=f"best {best_ours:.2f} s against {best_floor:.2f} s; {repeats} repeats",
        seconds={"ours": best_ours, "floor": best_floor},
    )


AT_PROBE = """
import sys, time, mpmath
from cayley_heyoka.reference import FreeRigidBody
body = FreeRigidBody(("1.0", "1.5", "2.5"), ("0.125", "0.25", "1.0"),
                     rodrigues=("0.1", "0.2", "-0.3"), dps=41)
n = int(sys.argv[1])
times = [body.period * 10**4 * k / n + 1 for k in range(n)]
body.at(times[0])
t0 = time.process_time()
for t in times:
    body.at(t)
print(mpmath.libmp.BACKEND, (time.process_time() - t0) / n)
"""


def gmpy_row(quick: bool) -> Row:
    """CPU time per FreeRigidBody.at with gmpy2 ÷ without, in alternating processes."""
    calls, repeats = (10, 2) if quick else (60, 5)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    argv = [sys.executable, "-c", AT_PROBE, str(calls)]
    ratios, seconds = [], {"gmpy": [], "python": []}
    for k in range(repeats):
        pair = {}
        for nogmpy in (False, True) if k % 2 == 0 else (True, False):
            e = {**env, "MPMATH_NOGMPY": "1"} if nogmpy else env
            backend, per = subprocess.run(
                argv, env=e, capture_output=True, text=True, check=True
            ).stdout.split()
            pair[backend] = float(per)
        if set(pair) != {"gmpy", "python"}:
            raise RuntimeError(f"gmpy2 is not installed here: backends {sorted(pair)}")
        ratios.append(pair["gmpy"] / pair["python"])
        for name in pair:
            seconds[name].append(pair[name])
    gmpy, python = (statistics.median(seconds[n]) for n in ("gmpy", "python"))
    return Row(
        what="`FreeRigidBody.at` at 41 digits (a 30-digit reference's unit of work), on gmpy2",
        ratios=ratios,
        target=1.0,
        floor="pure-Python mpmath (`MPMATH_NOGMPY=1`)",
        note=(
            f"CPU {gmpy * 1e3:.2f} ms against {python * 1e3:.2f} ms per call "
            f"({python / gmpy:.2f}x); {calls} times over 10⁴ periods, {repeats} repeats"
        ),
        seconds={"gmpy": gmpy, "python": python},
    )


def rows(quick: bool) -> list[Row]:
    """The reference command's rows (see the module docstring)."""
    with tempfile.TemporaryDirectory() as tmp:
        where = Path(tmp)
        out = [free_body_row(quick, where)]
        out.append(
            versus_integration(
                f"`cayley-heyoka reference` of Hamilton's projectile, {DIGITS} digits",
                EXAMPLES / "projectile.toml",
                where,
                2 if quick else 5,
            )
        )
        if not quick:
            out.append(
                versus_integration(
                    f"`cayley-heyoka reference` of a torque-free body, {DIGITS} digits, "
                    "10 periods, 100 outputs",
                    free_body_scene(10, 100, where),
                    where,
                    5,
                )
            )
    out.append(gmpy_row(quick))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the smoke run (< 30 s)")
    args = parser.parse_args()
    print(table(rows(args.quick)))


if __name__ == "__main__":
    main()
