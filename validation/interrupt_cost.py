"""What watching for Ctrl-C costs a run: the same scenes run watched and unwatched, side by side.

In the main thread the engine watches for SIGINT and SIGTERM so that a signal stops the run at
a step's end with its results (``cayley_heyoka.core.engine``, "signals"): in double precision heyoka
steps in the engine's watch thread while the main thread waits, and a signal poisons the
parameters; otherwise a Python callback runs after each step. In any other thread nothing is
watched. This script runs each bundled scene both ways, interleaved (validation/users_common.py),
and prints the median ratio and its spread. It judges nothing: it measures.

    python validation/interrupt_cost.py [--repeat 7] [--stop 2000]
"""

from __future__ import annotations

import argparse
import copy
import statistics
import threading
import time
from pathlib import Path

from users_common import interleaved

import cayley_heyoka as ch

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"

SCENES = {
    "free body, quaternion (double)": (
        "free_body.toml",
        {"attitude": {"formulation": "quaternion"}},
    ),
    "free body, Rodrigues (double)": ("free_body.toml", {}),
    "heavy top (double)": ("heavy_top.toml", {}),
    "free body (quad)": ("free_body_quad.toml", {}),
    "J2 + third body orbit (double)": ("orbit_j2_third_body.toml", {}),
}


def scene_for(name: str, stop: float, extra: dict) -> ch.Scene:
    data = ch.load_scene(EXAMPLES / name).to_dict()
    for table, values in extra.items():
        data.setdefault(table, {}).update(values)
    data["output"] = {"times": {"start": 0, "stop": stop, "count": 11}}
    data.pop("events", None)
    return ch.Scene.from_dict(data)


def timed(scene: ch.Scene) -> float:
    t0 = time.perf_counter()
    ch.run(scene)
    return time.perf_counter() - t0


def in_thread(scene: ch.Scene) -> float:
    box: list[float] = []
    worker = threading.Thread(target=lambda: box.append(timed(scene)))
    worker.start()
    worker.join()
    return box[0]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--stop", type=float, default=2000.0, help="end time of the double runs")
    args = parser.parse_args()
    print("| scene | steps | unwatched (s) | watched (s) | watched ÷ unwatched: median (min–max) |")
    print("|---|---|---|---|---|")
    for label, (name, extra) in SCENES.items():
        stop = args.stop / 20 if "quad" in label else args.stop
        scene = scene_for(name, stop, copy.deepcopy(extra))
        steps = ch.run(scene).counters["steps"]  # compiles once; both ways share the code
        ratios, watched, unwatched = interleaved(
            lambda scene=scene: timed(scene), lambda scene=scene: in_thread(scene), args.repeat
        )
        print(
            f"| {label} | {steps} | {unwatched:.3f} | {watched:.3f} | "
            f"{statistics.median(ratios):.3f} ({min(ratios):.3f}–{max(ratios):.3f}) |"
        )


if __name__ == "__main__":
    main()
