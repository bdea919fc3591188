"""Hostile Dask sweeps: a scheduler that cannot serve is refused before anything is written.

A scheduler address that distributed cannot parse is refused when the study is read; one that
does not answer (nothing listening, or a port that accepts and never answers) or has no worker
is refused within ``sweep_dask.CONNECT_TIMEOUT`` (shortened here), naming ``run.scheduler``
or ``--scheduler``; and a sweep that stops before any member ends leaves a file already at
``--out`` as it was. Each case runs in this process (conftest.py's ``hostile.run``).
"""

from __future__ import annotations

import shutil
import socket
from collections.abc import Iterator
from pathlib import Path

import pytest
from helpers import SMALL_BODY

from cayley_heyoka.workflows import sweep as sweep_module
from cayley_heyoka.workflows import sweep_dask

pytest.importorskip("distributed")


def _study(tmp_path: Path, run: str = "") -> Path:
    (tmp_path / "free.toml").write_text(SMALL_BODY)
    study = tmp_path / "study.toml"
    study.write_text(
        'scene = "free.toml"\n[sweep]\nkind = "grid"\n[sweep.parameters]\n'
        '"initial.rates[0]" = [0.1, 0.2, 0.3]\n' + run
    )
    return study


@pytest.fixture(scope="module")
def completed(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A completed sweep file of the study (3 members)."""
    from cayley_heyoka.workflows.study import load_study

    where = tmp_path_factory.mktemp("completed")
    out = where / "sweep.h5"
    result = sweep_module.run_sweep(load_study(_study(where)), out=out, backend="local")
    assert result.completed.all()
    return out


@pytest.fixture
def good(completed: Path, tmp_path: Path) -> Path:
    """A copy of the completed sweep at this test's ``--out``."""
    return Path(shutil.copy(completed, tmp_path / "sweep.h5"))


@pytest.fixture
def silent() -> Iterator[str]:
    """A TCP port that accepts connections (the kernel's backlog) and never answers."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen(8)
        yield f"tcp://127.0.0.1:{s.getsockname()[1]}"


@pytest.fixture
def closed() -> str:
    """A TCP port that nothing listens on (connection refused)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    return f"tcp://127.0.0.1:{port}"


@pytest.fixture
def short(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sweep_dask, "CONNECT_TIMEOUT", 1)


def _untouched(path: Path, before: bytes) -> None:
    assert path.read_bytes() == before, f"{path.name} was replaced"
    left = {p.name for p in path.parent.iterdir()}
    assert left == {"free.toml", path.name, "study.toml"}, "a temporary was left"


@pytest.mark.covers("class:9", "option:sweep --scheduler", "verb:sweep")
@pytest.mark.parametrize("scheduler", ["silent", "closed"])
def test_a_scheduler_that_does_not_answer_is_refused_and_the_file_kept(
    hostile, request, tmp_path, good, short, scheduler
):
    """A listener that never answers held distributed's Client for ever (its timeout does not
    cover the handshake); nothing listening was retried for the timeout and then replaced a
    completed sweep with '0 completed, 0 failed, 3 not run'."""
    address = request.getfixturevalue(scheduler)
    before = good.read_bytes()
    argv = ["sweep", str(_study(tmp_path)), "--scheduler", address, "--out", str(good)]
    o = hostile.run([*argv, "--no-progress"], expect="refused", field="--scheduler", seconds=30)
    assert f"cannot reach the Dask scheduler at {address}: " in o.error_line
    _untouched(good, before)


@pytest.mark.covers("class:9", "study-key:run.scheduler")
def test_a_silent_scheduler_in_the_study_is_refused_naming_its_field(
    hostile, tmp_path, good, short, silent
):
    before = good.read_bytes()
    study = _study(tmp_path, f'[run]\nscheduler = "{silent}"\n')
    o = hostile.run(
        ["sweep", str(study), "--out", str(good), "--no-progress"],
        expect="refused",
        field="run.scheduler",
        seconds=30,
    )
    assert f"cannot reach the Dask scheduler at {silent}: no answer within 1 s" in o.error_line
    _untouched(good, before)


@pytest.mark.covers("class:9", "option:sweep --scheduler")
def test_a_scheduler_without_workers_is_refused_and_the_file_kept(hostile, tmp_path, good, short):
    import distributed

    before = good.read_bytes()
    with distributed.LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cl:
        argv = ["sweep", str(_study(tmp_path)), "--scheduler", cl.scheduler_address]
        o = hostile.run(
            [*argv, "--out", str(good), "--no-progress"],
            expect="refused",
            field="--scheduler",
            seconds=30,
        )
    assert "has no workers after 1 s" in o.error_line
    _untouched(good, before)


BAD_ADDRESSES = ["not an address", "tcp://127.0.0.1:99999", "tcp://:8786", "gopher://h:1"]


@pytest.mark.covers("class:9", "option:sweep --scheduler")
@pytest.mark.parametrize("address", BAD_ADDRESSES)
def test_a_malformed_scheduler_option_is_refused_before_any_work(hostile, tmp_path, address):
    argv = ["sweep", str(_study(tmp_path)), "--scheduler", address, "--no-progress"]
    o = hostile.run(argv, expect="refused", field="--scheduler")
    assert "must be an address like 'tcp://host:8786'" in o.error_line


@pytest.mark.covers("class:9", "study-key:run.scheduler")
@pytest.mark.parametrize("address", BAD_ADDRESSES[:2])
def test_a_malformed_scheduler_in_the_study_is_refused_before_any_work(hostile, tmp_path, address):
    study = _study(tmp_path, f'[run]\nscheduler = "{address}"\n')
    hostile.run(["sweep", str(study), "--no-progress"], expect="refused", field="run.scheduler")


@pytest.mark.covers("class:9", "verb:sweep")
@pytest.mark.parametrize("how", ["interrupted", "stopped"])
def test_a_sweep_that_ends_no_member_keeps_the_file_there(
    hostile, tmp_path, good, monkeypatch, how
):
    """Ctrl-C, or a backend lost, before the first chunk is back: nothing to keep, so the
    completed sweep already at --out is not replaced by one of members not run."""

    def lost(*args: object, **kwargs: object) -> None:
        raise KeyboardInterrupt if how == "interrupted" else RuntimeError("the cluster is gone")

    monkeypatch.setattr(sweep_module, "integrate_members", lost)
    before = good.read_bytes()
    argv = ["sweep", str(_study(tmp_path)), "--out", str(good), "--no-progress"]
    hostile.run(argv, expect=how, out=good)
    _untouched(good, before)
