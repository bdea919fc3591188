"""pytest plugin: the ``drift_golden`` fixture and the ``--update-golden`` option.

Installed with cayley_heyoka (entry point ``pytest11``), so any test suite can write::

    def test_my_scene_drift(drift_golden):
        drift_golden(ch.run(ch.load_scene("my_scene.toml")))

The first run with ``pytest --update-golden`` writes ``golden/test_my_scene_drift.h5`` beside
the test module; later runs fail when a window of the drift envelope exceeds the golden one by
more than :func:`cayley_heyoka.workflows.testing.assert_drift_within` allows.

Loading the plugin imports pytest only: the library (and heyoka) load when a test first calls
the fixture, so test suites that do not use it pay nothing.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import pytest

if TYPE_CHECKING:
    from ..core.result import Result
    from .testing import DriftEnvelope

_WRITTEN = pytest.StashKey[list[Path]]()


def pytest_addoption(parser: pytest.Parser) -> None:
    """Add ``--update-golden``."""
    group = parser.getgroup("cayley_heyoka")
    group.addoption(
        "--update-golden",
        action="store_true",
        default=False,
        help="write the golden drift files compared by the drift_golden fixture from this run",
    )


def pytest_configure(config: pytest.Config) -> None:
    """Start the session's list of golden files written."""
    config.stash[_WRITTEN] = []


def pytest_terminal_summary(
    terminalreporter: pytest.TerminalReporter, exitstatus: int, config: pytest.Config
) -> None:
    """List the golden files written, so that an update is never silent."""
    written = config.stash.get(_WRITTEN, [])
    if written:
        terminalreporter.write_sep("-", f"golden drift files written: {len(written)}")
        for path in written:
            terminalreporter.write_line(str(path))


class DriftGolden:
    """Compare a run's drift with a golden file, or write the file under ``--update-golden``.

    Parameters
    ----------
    directory
        The test module's directory: named files are in its ``golden/``, relative paths start
        there.
    default_name
        The file name (without ``.h5``) when a call gives neither ``name`` nor ``path``.
    update
        Whether to write the files instead of comparing.
    written
        Collects the paths written (reported at the end of the session).
    root
        Paths in messages are shown relative to it (pytest's root directory).
    """

    def __init__(
        self, directory: Path, default_name: str, update: bool, written: list[Path], root: Path
    ):
        self.directory = directory
        self.default_name = default_name
        self.update = update
        self._written = written
        self._root = root

    def _shown(self, path: Path) -> Path:
        """``path`` relative to the session's root directory when it lies inside it."""
        return path.relative_to(self._root) if path.is_relative_to(self._root) else path

    def path(self, name: str | None = None) -> Path:
        """The golden file for ``name`` (default: the test's name): ``directory/golden/NAME.h5``."""
        return self.directory / "golden" / f"{name or self.default_name}.h5"

    def __call__(
        self,
        result: Result,
        name: str | None = None,
        *,
        path: str | Path | None = None,
        windows: int = 8,
        factor: float | None = None,
        floor: float | None = None,
    ) -> DriftEnvelope:
        """Check ``result``'s drift against its golden file; return the measured envelope.

        Parameters
        ----------
        result
            The run, with at least one conserved monitor.
        name
            The golden file's name in ``golden/`` beside the test module (default: the test's
            name, parameters included).
        path
            The golden file instead (relative paths start at the test module's directory).
        windows
            Number of log-spaced windows when the file is written; a comparison uses the
            golden file's windows.
        factor, floor
            Passed to :func:`~cayley_heyoka.workflows.testing.assert_drift_within` (default:
            its own).
        """
        __tracebackhide__ = True
        import numpy as np

        from .testing import DriftEnvelope, assert_drift_within, drift_envelope

        if name is not None and path is not None:
            raise TypeError("drift_golden: give name or path, not both")
        target = self.path(name) if path is None else self.directory / Path(path)
        shown = self._shown(target)
        if self.update:
            envelope = drift_envelope(result, windows)
            bad = [k for k, v in envelope.peaks.items() if not np.isfinite(v).all()]
            if bad:
                pytest.fail(f"not writing {shown}: non-finite drift of {', '.join(bad)}")
            target.parent.mkdir(parents=True, exist_ok=True)
            envelope.save(target)
            self._written.append(shown)
            return envelope
        if not target.exists():
            pytest.fail(
                f"golden drift file {shown} does not exist: run pytest with --update-golden "
                "to write it from this run",
                pytrace=False,
            )
        golden = DriftEnvelope.load(target)
        options = {k: v for k, v in (("factor", factor), ("floor", floor)) if v is not None}
        try:
            assert_drift_within(result, golden, **options)
        except AssertionError as exc:
            raise AssertionError(
                f"{exc}\n(golden file {shown}; if the change is intended, rewrite it with "
                "pytest --update-golden)"
            ) from None
        return drift_envelope(result, golden.windows)


@pytest.fixture
def drift_golden(request: pytest.FixtureRequest) -> DriftGolden:
    """Compare a run's drift envelope with ``golden/<test name>.h5`` beside the test module.

    Call it with a :class:`~cayley_heyoka.core.result.Result`; see :class:`DriftGolden`. With
    ``--update-golden`` the file is written from the run instead.
    """
    name = re.sub(r"\W+", "_", request.node.name).strip("_")
    return DriftGolden(
        request.path.parent,
        name,
        request.config.getoption("update_golden"),
        request.config.stash[_WRITTEN],
        request.config.rootpath,
    )
