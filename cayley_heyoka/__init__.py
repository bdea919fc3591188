"""cayley_heyoka: high-accuracy Taylor integration of classical dynamics with heyoka.

Quick use::

    import cayley_heyoka as ch
    scene = ch.load_scene("examples/free_body.toml")
    result = ch.run(scene)
    result["p"], result.drift("energy"), result.events["invariable_plane"]
"""

from __future__ import annotations

from importlib import metadata as _metadata

from .engine import clear_cache, compile_model, run
from .ensemble import EnsembleError, EnsembleResult, propagate_ensemble
from .errors import IntegrationError, SceneError
from .precision import Precision
from .result import EventLog, Result
from .scene import Scene, load_scene

try:
    __version__ = _metadata.version("cayley_heyoka")
except _metadata.PackageNotFoundError:  # pragma: no cover - source tree without install
    __version__ = "0.0.0+unknown"


def load_result(path: str) -> Result:
    """Read a result file written by :meth:`Result.save`."""
    return Result.load(path)


__all__ = [
    "EnsembleError",
    "EnsembleResult",
    "EventLog",
    "IntegrationError",
    "Precision",
    "Result",
    "Scene",
    "SceneError",
    "clear_cache",
    "compile_model",
    "load_result",
    "load_scene",
    "propagate_ensemble",
    "run",
]
