"""The Python a sweep spends on each member before integrating it, phase by phase.

Run:  python validation/sweep_member_cost.py [--members N]

A study of free bodies (quaternion attitude, t = 0 … 100) whose members differ in two initial
rates: per member, the median time of its scene (``Study.member_scene``: the base scene with
the member's values, validated by ``Scene.from_dict``), its model (``model_for``: the study's
structure filled with the member's numbers; and, for comparison, the family's full build) and
its group key (the compiled code's cache key), and of ``prepare_members`` for all of them, as a
sweep runs it (the family's table: every member's numbers computed at once,
``cayley_heyoka.core.structures.table_for``) and member by member (each validated scene's
``model_for``, the path of a family without a table) — against the integration of one member
by heyoka (the same scene's compiled integrator, ``propagate_until`` from its initial state),
the floor this Python is paid on top of.
"""

from __future__ import annotations

import argparse
import statistics
import time

from cayley_heyoka.core import compiler
from cayley_heyoka.core.engine import model_of
from cayley_heyoka.core.families import FAMILIES
from cayley_heyoka.core.structures import model_for
from cayley_heyoka.workflows.members import _group_key, prepare_members
from cayley_heyoka.workflows.study import Study
from cayley_heyoka.workflows.sweep import layout_of

BODY = {
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["0.3", "1", "0.5"], "quaternion": ["1", "0", "0", "0"]},
    "attitude": {"formulation": "quaternion"},
    "output": {"times": {"start": "0", "stop": "100", "count": "11"}},
}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--members", type=int, default=500)
    args = parser.parse_args(argv)
    parameters = {
        "initial.rates[0]": {"uniform": ["0.2", "0.4"]},
        "initial.rates[1]": {"uniform": ["0.9", "1.1"]},
    }
    study = Study.from_dict(
        {
            "scene": BODY,
            "sweep": {"kind": "random", "count": args.members, "seed": 1, "parameters": parameters},
        }
    )
    members = list(enumerate(study.members()))
    layout = layout_of(study)
    prepare_members(study, members[:10], layout)  # imports and caches warm
    phases: dict[str, list[float]] = {"scene": [], "model": [], "group key": [], "full build": []}
    for index, values in members:
        t0 = time.perf_counter()
        scene = study.member_scene(index, values)
        t1 = time.perf_counter()
        model = model_for(scene)
        t2 = time.perf_counter()
        _group_key(model, scene)
        t3 = time.perf_counter()
        FAMILIES[scene.family].build(scene).code_key  # noqa: B018 -- what a member once cost
        phases["full build"].append(time.perf_counter() - t3)
        phases["scene"].append(t1 - t0)
        phases["model"].append(t2 - t1)
        phases["group key"].append(t3 - t2)
    t0 = time.perf_counter()
    prepare_members(study, members, layout)
    whole = (time.perf_counter() - t0) / len(members)
    scenes = [study.member_scene(*m) for m in members]
    t0 = time.perf_counter()
    prepare_members(study, members, layout, scenes)
    alone = (time.perf_counter() - t0) / len(members)

    scene = study.member_scene(*members[0])
    compiled, _ = compiler.compile_model(model_of(scene), scene.integrator)
    ta = compiled.integrator
    initial = model_of(scene).initial_state
    steps, runs = 0, []
    for _ in range(20):
        ta.time, ta.state[:] = 0.0, initial
        t0 = time.perf_counter()
        steps = ta.propagate_until(100.0)[3]
        runs.append(time.perf_counter() - t0)
    floor = statistics.median(runs)

    print(f"{len(members)} members of a free-body study, t = 0 … 100 ({steps} steps each)")
    for name, times in phases.items():
        print(f"  {name:<10} {statistics.median(times) * 1e3:.3f} ms a member (median)")
    print(f"  prepare_members, the family's table: {whole * 1e3:.4f} ms a member")
    print(f"  prepare_members, member by member (scenes given): {alone * 1e3:.3f} ms a member")
    print(
        f"  heyoka's propagate_until of one member: {floor * 1e3:.3f} ms "
        f"(the Python a member: {whole / floor:.1%} of it with the table, "
        f"{(alone + statistics.median(phases['scene'])) / floor:.0%} member by member)"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
