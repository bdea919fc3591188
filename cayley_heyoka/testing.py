"""Test helpers for your suites and ours (public path; the code is
:mod:`cayley_heyoka.workflows.testing`): compare a run with a reference trajectory, or its
drift with a golden envelope."""

from __future__ import annotations

from .workflows.testing import (
    DRIFT_FACTOR,
    DRIFT_FLOOR,
    DRIFT_FORMAT,
    DRIFT_FORMAT_VERSION,
    MAX_WINDOWS,
    DriftEnvelope,
    assert_drift_within,
    assert_trajectory_close,
    drift_envelope,
)

__all__ = [
    "DRIFT_FACTOR",
    "DRIFT_FLOOR",
    "DRIFT_FORMAT",
    "DRIFT_FORMAT_VERSION",
    "MAX_WINDOWS",
    "DriftEnvelope",
    "assert_drift_within",
    "assert_trajectory_close",
    "drift_envelope",
]
