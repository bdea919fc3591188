"""Regenerate the figures of docs/tutorials/plots.md from the bundled scenes.

Run from anywhere: ``python docs/tutorials/make_figures.py`` (needs ``pip install -e
".[plots]"``; about 10 s, most of it compiling the two scenes the first time). Writes
``docs/tutorials/figures/{drift,polhode,crossings,orbit,sweep_drift}.png``: the figures the
tutorial draws, from the same scenes and study, by :func:`cayley_heyoka.workflows.plots.plot_file`.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import cayley_heyoka as ch
from cayley_heyoka.workflows.plots import plot_file
from cayley_heyoka.workflows.sweep import load_study, run_sweep

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent.parent / "examples"
FIGURES = HERE / "figures"
#: Scene file -> the kinds of plot drawn from its result.
DRAWN = {
    "free_body.toml": ("drift", "polhode", "crossings"),
    "orbit_j2_third_body.toml": ("orbit",),
}
#: The study whose sweep file is drawn as sweep_drift.png.
STUDY = EXAMPLES / "studies" / "free_body_random.toml"


def main() -> None:
    FIGURES.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as scratch:
        for scene, kinds in DRAWN.items():
            path = Path(scratch) / f"{Path(scene).stem}.h5"
            ch.run(ch.load_scene(EXAMPLES / scene)).save(path)
            for kind in kinds:
                _show(plot_file(path, kind, FIGURES / f"{kind}.png"))
        sweep = Path(scratch) / "sweep.h5"
        run_sweep(load_study(STUDY), out=sweep)
        _show(plot_file(sweep, "drift", FIGURES / "sweep_drift.png"))


def _show(path: Path) -> None:
    print(path.relative_to(HERE.parent.parent))


if __name__ == "__main__":
    main()
