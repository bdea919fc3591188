"""What a multiprecision run costs as the bits grow: the figure behind the ``{bits}`` limit.

One time unit of the bundled free body with its Rodrigues attitude, a whole ``run()`` with
every cache off (ours and heyoka's memory and disk caches: the LLVM compilation included, as a
user's first run of a new structure pays it), at each
precision; the limit itself (1024 bits) is lifted here by building the precision directly.

    python validation/precision_cost.py [--bits 256 512 1024 2048]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import heyoka as hy

import cayley_heyoka as ch
from cayley_heyoka.core import compiler
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.core.scene import IntegratorOptions

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "free_body.toml"


def scene_at(bits: int) -> ch.Scene:
    data = ch.load_scene(EXAMPLE).to_dict()
    data.pop("events", None)
    data["output"] = {"times": [0, 1]}
    scene = ch.Scene.from_dict(data)
    # Past the scene limit on purpose: this is the measurement that sets it.
    options = IntegratorOptions(precision=Precision("real", bits))
    return ch.Scene(scene.family, scene.model, options, scene.output, {}, scene.title, scene.source)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bits", type=int, nargs="+", default=[256, 512, 1024, 2048])
    args = parser.parse_args()
    hy.llvm_state.set_diskcache_enabled(False)
    print("| bits | run() incl. compile (s) | steps |")
    print("|---|---|---|")
    for bits in args.bits:
        compiler.clear_cache()
        hy.llvm_state.clear_memcache()
        t0 = time.perf_counter()
        result = ch.run(scene_at(bits))
        print(f"| {bits} | {time.perf_counter() - t0:.2f} | {result.counters['steps']} |")


if __name__ == "__main__":
    main()
