"""What the accounting of crossings beside terminal events costs a whole ``run()``.

Run:  python validation/event_parity_cost.py [--repeats N]

The bundled free body (``examples/free_body.toml``: a Rodrigues attitude, whose chart re-bases
by a terminal event every few steps, recording its invariable-plane crossings) over
t = 0 … 2000, run through ``cayley_heyoka.run`` with the accounting
(``cayley_heyoka/core/event_parity.py``) and without it (the compiled sign function withheld,
as for a model without recorded events), interleaved in one process; median and spread of the
repeats, and the events found by each (the accounting may only add what the searches lost).
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import cayley_heyoka as ch
from cayley_heyoka.core import compiler

HERE = Path(__file__).resolve().parent


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args(argv)
    data = ch.load_scene(HERE.parent / "examples" / "free_body.toml").to_dict()
    data["output"]["times"] = {"start": "0", "stop": "2000", "count": 11}
    scene = ch.Scene.from_dict(data)
    with_parity = compiler.event_values

    def without(model, options):
        return None

    def timed(values) -> tuple[float, ch.Result]:
        compiler.event_values = values
        compiler.clear_cache()
        ch.run(scene)  # compiled here, not in the timing
        t0 = time.perf_counter()
        result = ch.run(scene)
        return time.perf_counter() - t0, result

    ratios, on, off = [], [], []
    try:
        for _ in range(args.repeats):
            a, ra = timed(with_parity)
            b, rb = timed(without)
            on.append(a)
            off.append(b)
            ratios.append(a / b)
    finally:
        compiler.event_values = with_parity
    q = statistics.quantiles(ratios, n=4)
    print(
        f"free body, t = 0 … 2000: {ra.counters['steps']} steps, "
        f"{ra.counters['rebasings']} re-basings, "
        f"{len(ra.events['invariable_plane'])} crossings with the accounting, "
        f"{len(rb.events['invariable_plane'])} without"
    )
    print(
        f"run() with ÷ without the accounting: {statistics.median(ratios):.3f}× "
        f"(quartiles {q[0]:.3f}–{q[2]:.3f}); medians {statistics.median(on) * 1e3:.1f} ms "
        f"and {statistics.median(off) * 1e3:.1f} ms"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
