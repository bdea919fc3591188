"""Hostile files: what ``info`` is given to read, and where the writing commands are told to write.

Every case ends as the runner requires (tests/hostile/conftest.py): refused with an
``error: FILE: ...`` line, or done — and a file that is read without complaint holds exactly
what was written. Nothing given as ``--out`` is replaced unless it is ours of the same kind or
``--overwrite`` is given. The policy: cayley_heyoka/core/files.py, docs/scenes.md ("Files").
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest

from cayley_heyoka import Result, Scene, run
from cayley_heyoka.core.consistency import CheckReport
from cayley_heyoka.core.files import DIGEST, seal
from cayley_heyoka.workflows.reference import WORK_MARKER
from cayley_heyoka.workflows.sweep_result import load_sweep

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "files"
SCENE = {
    "title": "hostile files",
    "body": {"inertia": ["1", "1.5", "2.5"]},
    "initial": {"rates": ["1", "0.1875", "0.25"], "quaternion": [1, 0, 0, 0]},
    "attitude": {"formulation": "quaternion"},
    "output": {"times": {"start": 0, "stop": 5, "count": 150}, "events": ["invariable_plane"]},
}


@pytest.fixture(scope="module")
def pristine(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One file of each kind of ours, written by this version (and the older versions')."""
    d = tmp_path_factory.mktemp("pristine")
    files = {}
    res = run(Scene.from_dict(SCENE))
    res.save(files.setdefault("result", d / "result.h5"))
    quad = run(Scene.from_dict({**SCENE, "integrator": {"precision": "quad"}}))
    quad.save(files.setdefault("quad", d / "quad.h5"))
    Result.load(DATA / "reference_v1.h5").save(files.setdefault("reference", d / "ref.h5"))
    load_sweep(DATA / "sweep_v1.h5").save(files.setdefault("sweep", d / "sweep.h5"))
    CheckReport.load(DATA / "check_v1.h5").save(files.setdefault("check", d / "check.h5"))
    for old in DATA.glob("*_v[12]*.h5"):
        files[old.stem] = old
    return files


def _copy(pristine: dict[str, Path], kind: str, tmp_path: Path) -> Path:
    path = tmp_path / f"{kind}.h5"
    shutil.copyfile(pristine[kind], path)
    return path


def _same_as(path: Path, original: Path) -> bool:
    a, b = Result.load(path), Result.load(original)
    p = a.precision
    arrays = [(a.t, b.t), *((a.variables[k], b.variables[k]) for k in a.variables)]
    arrays += [(a.monitors[k], b.monitors[k]) for k in a.monitors]
    return a.metadata == b.metadata and all(
        np.array_equal(p.to_text(x).astype(str), p.to_text(y).astype(str)) for x, y in arrays
    )


# ---------------------------------------------------------------------- reading damaged files
TRUNCATIONS = [0.0, 0.001, 0.01, 0.03, 0.1, 0.25, 0.4, 0.5, 0.6, 0.75, 0.9, 0.99, 0.999]


@pytest.mark.covers("verb:info", "option:info result")
@pytest.mark.parametrize("fraction", TRUNCATIONS)
@pytest.mark.parametrize("kind", ["result", "quad"])
def test_truncated_file(hostile, pristine, tmp_path, kind, fraction):
    path = _copy(pristine, kind, tmp_path)
    size = path.stat().st_size
    with open(path, "r+b") as f:
        f.truncate(int(size * fraction))
    hostile.run(["info", str(path)], expect="refused", field=str(path))


GARBAGE = [0.02, 0.15, 0.3, 0.45, 0.6, 0.75, 0.9, 0.98]


@pytest.mark.covers("verb:info", "option:info result")
@pytest.mark.parametrize("fraction", GARBAGE)
@pytest.mark.parametrize("kind", ["result", "quad"])
def test_garbage_block(hostile, pristine, tmp_path, kind, fraction):
    path = _copy(pristine, kind, tmp_path)
    size = path.stat().st_size
    at = min(int(size * fraction), size - 4096)
    with open(path, "r+b") as f:
        f.seek(at)
        f.write(np.random.default_rng(int(fraction * 100)).bytes(4096))
    o = hostile.run(["info", str(path)], expect={"refused", "done"}, field=str(path))
    if o.kind == "done":  # the block fell where nothing is stored: the contents are intact
        assert _same_as(path, pristine[kind])


def _foreign_hdf5(path: Path) -> None:
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3.0)


def _other_format(path: Path) -> None:
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "someone.elses"
        f["t"] = np.arange(3.0)


def _bare_result(path: Path) -> None:
    with h5py.File(path, "w") as f:
        f.attrs["format"] = "cayley_heyoka.result"
        f.attrs["format_version"] = 1


NOT_OURS: dict[str, Callable[[Path], Any]] = {
    "empty": lambda p: p.write_bytes(b""),
    "text": lambda p: p.write_text("Chapter 1. It was a dark and stormy night.\n"),
    "random": lambda p: p.write_bytes(np.random.default_rng(0).bytes(20000)),
    "hdf5 signature only": lambda p: p.write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100)),
    "png": lambda p: p.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(100)),
    "foreign hdf5": _foreign_hdf5,
    "another format": _other_format,
    "a result header and nothing else": _bare_result,
    "drift golden file": lambda p: shutil.copyfile(ROOT / "tests/data/golden/free_body.h5", p),
    "directory": lambda p: p.mkdir(),
    "missing": lambda p: None,
}


@pytest.mark.covers("verb:info", "option:info result")
@pytest.mark.parametrize("case", list(NOT_OURS))
def test_file_that_is_not_ours(hostile, tmp_path, case):
    path = tmp_path / "file.h5"
    NOT_OURS[case](path)
    hostile.run(["info", str(path)], expect="refused", field=str(path))


OURS = {
    "result": "hostile files",
    "quad": "quad",
    "reference": "reference     certified",
    "sweep": "3 completed",
    "check": "passed",
    "result_v1_double": "completed",
    "result_v1_quad": "quad",
    "reference_v1": "certified",
    "sweep_v1": "3 completed",
    "result_v2_double": "completed",
    "result_v2_quad": "quad",
    "reference_v2": "certified",
    "sweep_v2": "3 completed",
    "check_v1": "passed",
}


@pytest.mark.covers("verb:info", "option:info result")
@pytest.mark.parametrize("kind", list(OURS))
def test_each_kind_of_our_files_is_summarised(hostile, pristine, kind):
    o = hostile.run(["info", str(pristine[kind])], expect="done")
    assert OURS[kind] in o.stdout


def _drop(name: str) -> Callable[[Any], None]:
    return lambda f: f.__delitem__(name)


def _attr(name: str, value: Any) -> Callable[[Any], None]:
    return lambda f: f.attrs.__setitem__(name, value)


DAMAGE: dict[str, Callable[[Any], None]] = {
    # Moved, not deleted: HDF5 itself fails to close a file whose dimension scale was
    # deleted while attached (in the damaging, not in our reading).
    "no time": lambda f: f.move("time", "times"),
    "no variable p": _drop("p"),
    "no monitor energy": _drop("energy"),
    "order without monitors": _attr("order", '{"variables": ["p"], "events": []}'),
    "order not JSON": _attr("order", "{"),
    "no events": _drop("events"),
    "no event labels": _drop("events/invariable_plane/label"),
    "metadata not JSON": _attr("metadata", "{not json"),
    "scene not JSON": _attr("scene", "[[["),
    "precision unknown": _attr("precision", '"octuple"'),
    "precision not JSON": _attr("precision", "quad"),
    "status missing": lambda f: f.attrs.__delitem__("status"),
    "order names a missing variable": _attr(
        "order", '{"variables": ["p", "nowhere"], "monitors": [], "events": []}'
    ),
    "format version text": _attr("format_version", "two"),
    "format version 0": _attr("format_version", 0),
    "format version from the future": _attr("format_version", 99),
    "time as text": lambda f: (
        f.__delitem__("time"),
        f.__setitem__("time", np.array([b"x", b"y"])),
    ),
    "a variable as text": lambda f: (f.__delitem__("p"), f.__setitem__("p", np.array([b"x"]))),
}


@pytest.mark.covers("verb:info", "option:info result")
@pytest.mark.parametrize("sealed", [True, False], ids=["resealed", "checksum-stale"])
@pytest.mark.parametrize("case", list(DAMAGE))
def test_damaged_contents(hostile, pristine, tmp_path, case, sealed):
    """Damage under a valid checksum (as a buggy writer would) and under a stale one."""
    path = _copy(pristine, "result", tmp_path)
    with h5py.File(path, "a") as f:
        DAMAGE[case](f)
        if sealed:
            seal(f)
    hostile.run(["info", str(path)], expect="refused", field=str(path))


@pytest.mark.covers("verb:info", "option:info result")
def test_checksum_removed(hostile, pristine, tmp_path):
    path = _copy(pristine, "sweep", tmp_path)
    with h5py.File(path, "a") as f:
        del f.attrs[DIGEST]
    hostile.run(["info", str(path)], expect="refused", field="not completely written")


# ---------------------------------------------------------------------- where files are written
@pytest.fixture
def scene(hostile) -> Path:
    small = {**SCENE, "output": {"times": {"start": 0, "stop": 1, "count": 3}}}
    return hostile.scene(small)


def _thesis(path: Path) -> Path:
    path.write_text("Chapter 1\n")
    return path


DESTINATIONS: dict[str, Callable[[Path], Path]] = {
    "missing directory": lambda d: d / "nowhere" / "r.h5",
    "a directory": lambda d: d,
    "parent is a file": lambda d: _thesis(d / "thesis.txt") / "r.h5",
    "foreign file": lambda d: _thesis(d / "thesis.txt"),
    "symlink to a foreign file": lambda d: _link(d / "r.h5", _thesis(d / "thesis.txt")),
    "dangling symlink into nowhere": lambda d: _link(d / "r.h5", d / "nowhere" / "x.h5"),
    "symlink to a directory": lambda d: _link(d / "r.h5", d),
    "fifo": lambda d: _fifo(d / "r.h5"),
    "name too long": lambda d: d / ("n" * 250 + ".h5"),
}


def _link(path: Path, target: Path) -> Path:
    path.symlink_to(target)
    return path


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _snapshot(d: Path) -> dict[str, bytes | str]:
    """Every entry under ``d``: file contents, link targets, directories."""
    out: dict[str, bytes | str] = {}
    for p in sorted(d.rglob("*")):
        key = str(p.relative_to(d))
        if p.is_symlink():
            out[key] = f"-> {os.readlink(p)}"
        elif p.is_file():
            out[key] = p.read_bytes()
        else:
            out[key] = "dir" if p.is_dir() else "special"
    return out


@pytest.mark.covers(
    "option:run --out",
    "option:check --out",
    "option:sweep --out",
    "option:reference --out",
    "option:plot --out",
)
@pytest.mark.parametrize("case", list(DESTINATIONS))
@pytest.mark.parametrize("verb", ["run", "check", "sweep", "reference", "plot"])
def test_destination_refused_before_any_work(hostile, pristine, scene, tmp_path, verb, case):
    place = tmp_path / "place"
    place.mkdir()
    out = DESTINATIONS[case](place)
    before = _snapshot(place)
    argv = {
        "run": ["run", str(scene)],
        "check": ["check", str(ROOT / "examples" / "projectile.toml")],
        "sweep": ["sweep", str(ROOT / "examples" / "studies" / "free_body_grid.toml")],
        "reference": ["reference", str(scene), "--digits", "8"],
        "plot": ["plot", str(pristine["result"]), "--kind", "drift"],
    }[verb]
    o = hostile.run([*argv, "--out", str(out)], expect="refused", field="error: ")
    assert o.seconds < 10  # nothing was integrated: a sweep would take far longer
    assert _snapshot(place) == before


@pytest.mark.covers(
    "option:run --out",
    "option:check --out",
    "option:sweep --out",
    "option:reference --out",
    "option:plot --out",
)
@pytest.mark.parametrize(
    "verb, other", [("run", "sweep"), ("check", "result"), ("sweep", "check"), ("plot", "result")]
)
def test_another_kind_of_our_files_is_not_replaced(hostile, pristine, scene, tmp_path, verb, other):
    out = _copy(pristine, other, tmp_path)
    before = out.read_bytes()
    argv = {
        "run": ["run", str(scene)],
        "check": ["check", str(ROOT / "examples" / "projectile.toml")],
        "sweep": ["sweep", str(ROOT / "examples" / "studies" / "free_body_grid.toml")],
        "plot": ["plot", str(pristine["result"]), "--kind", "drift"],
    }[verb]
    hostile.run([*argv, "--out", str(out)], expect="refused", field="--overwrite")
    assert out.read_bytes() == before


@pytest.mark.covers("option:run --out", "option:run --overwrite")
def test_our_result_file_is_replaced_and_a_foreign_one_only_when_told(hostile, scene, tmp_path):
    ours = tmp_path / "r.h5"
    hostile.run(["run", str(scene), "--out", str(ours), "--no-progress"], expect="done", out=ours)
    hostile.run(["run", str(scene), "--out", str(ours), "--no-progress"], expect="done", out=ours)
    thesis = _thesis(tmp_path / "thesis.txt")
    argv = ["run", str(scene), "--out", str(thesis), "--no-progress", "--overwrite"]
    hostile.run(argv, expect="done", out=thesis)
    assert Result.load(thesis).success
    assert sorted(p.name for p in tmp_path.iterdir() if p.suffix != ".toml") == [
        "r.h5",
        "thesis.txt",
    ]


@pytest.mark.covers("option:run --out")
def test_symlink_to_our_file_writes_through(hostile, pristine, scene, tmp_path):
    target = _copy(pristine, "result", tmp_path)
    link = _link(tmp_path / "latest.h5", target)
    # --overwrite: the target holds another scene's result.
    argv = ["run", str(scene), "--out", str(link), "--no-progress", "--overwrite"]
    hostile.run(argv, expect="done")
    assert link.is_symlink() and len(Result.load(target).t) == 3


@pytest.mark.covers("option:run --out", "option:run --overwrite")
def test_a_result_of_another_scene_is_not_replaced(hostile, pristine, scene, tmp_path):
    """The same scene's file is replaced (a re-run); another scene's only with --overwrite,
    the message naming both scenes' titles or the table that differs."""
    out = _copy(pristine, "result", tmp_path)
    before = out.read_bytes()
    hostile.run(["run", str(scene), "--out", str(out)], expect="refused", field="another [output]")
    assert out.read_bytes() == before
    retitled = hostile.scene({**SCENE, "title": "another body"})
    o = hostile.run(
        ["run", str(retitled), "--out", str(out)], expect="refused", field="--overwrite"
    )
    assert "'hostile files', not 'another body'" in o.stderr
    assert out.read_bytes() == before
    hostile.run(["run", str(scene), "--out", str(out), "--overwrite"], expect="done", out=out)
    assert len(Result.load(out).t) == 3


@pytest.mark.covers("option:run --out")
def test_a_result_whose_scene_cannot_be_read_is_not_replaced(hostile, pristine, scene, tmp_path):
    """A file of ours whose stored scene is not JSON (edited by hand) is refused, not replaced."""
    out = _copy(pristine, "result", tmp_path)
    with h5py.File(out, "r+") as f:
        f.attrs["scene"] = "{not json"
    before = out.read_bytes()
    o = hostile.run(["run", str(scene), "--out", str(out)], expect="refused", field="--overwrite")
    assert "its scene cannot be read" in o.stderr
    assert out.read_bytes() == before


@pytest.mark.covers("option:reference --out", "option:reference --overwrite")
def test_a_reference_does_not_replace_another_scenes_result(hostile, pristine, scene, tmp_path):
    """A reference replaces a result of its own scene (whatever precision it was run at), not
    another's."""
    out = _copy(pristine, "result", tmp_path)
    before = out.read_bytes()
    argv = ["reference", str(scene), "--digits", "8", "--out", str(out)]
    hostile.run(argv, expect="refused", field="--overwrite")
    assert out.read_bytes() == before
    own = tmp_path / "own.h5"
    hostile.run(["run", str(scene), "--out", str(own), "--no-progress"], expect="done", out=own)
    hostile.run(["reference", str(scene), "--digits", "8", "--out", str(own)], expect="done")
    assert Result.load(own).metadata.get("reference")


@pytest.mark.covers("option:sweep --out", "option:sweep --overwrite")
def test_a_sweep_of_another_study_is_not_replaced(hostile, pristine, tmp_path):
    out = _copy(pristine, "sweep", tmp_path)
    before = out.read_bytes()
    study = ROOT / "examples" / "studies" / "free_body_grid.toml"
    o = hostile.run(["sweep", str(study), "--out", str(out)], expect="refused", field="--overwrite")
    assert "holds the sweep of another study" in o.stderr and o.seconds < 10
    assert out.read_bytes() == before


@pytest.mark.covers("option:run --out")
def test_a_loop_of_links_is_refused_and_left_alone(hostile, scene, tmp_path):
    a, b = tmp_path / "a.h5", tmp_path / "b.h5"
    a.symlink_to(b)
    b.symlink_to(a)
    hostile.run(
        ["run", str(scene), "--out", str(a), "--no-progress"], expect="refused", field="loop"
    )
    assert a.is_symlink() and b.is_symlink()


@pytest.mark.covers("option:run --out")
@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_directory(hostile, scene, tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    try:
        hostile.run(
            ["run", str(scene), "--out", str(locked / "r.h5")], expect="refused", field="writable"
        )
    finally:
        locked.chmod(0o755)


@pytest.mark.covers("verb:reference", "option:reference --out")
def test_reference_leaves_a_work_directory_it_did_not_make(hostile, scene, tmp_path):
    work = tmp_path / "ref.h5.work"
    work.mkdir()
    (work / "thesis.tex").write_text("\\chapter{}\n")
    argv = ["reference", str(scene), "--digits", "8", "--out", str(tmp_path / "ref.h5")]
    hostile.run(argv, expect="refused", field=WORK_MARKER)
    assert [p.name for p in work.iterdir()] == ["thesis.tex"]
