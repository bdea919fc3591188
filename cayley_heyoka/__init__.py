"""cayley_heyoka: high-accuracy Taylor integration of classical dynamics with heyoka.

Quick use::

    import cayley_heyoka as ch
    scene = ch.load_scene("examples/free_body.toml")
    result = ch.run(scene)
    result["p"], result.drift("energy"), result.events["invariable_plane"]
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

# Public names are imported on first use (PEP 562): the pytest plugin, loaded in every test
# session of an environment that has cayley_heyoka installed, imports this package, and
# importing heyoka costs ~0.4 s.
_EXPORTS = {
    "clear_cache": "engine",
    "compile_model": "engine",
    "run": "engine",
    "EnsembleError": "ensemble",
    "EnsembleResult": "ensemble",
    "propagate_ensemble": "ensemble",
    "IntegrationError": "errors",
    "Interrupted": "errors",
    "SceneError": "errors",
    "OutputError": "files",
    "ResultFileError": "files",
    "Precision": "precision",
    "EventLog": "result",
    "Result": "result",
    "Scene": "scene",
    "load_scene": "scene",
}

if TYPE_CHECKING:
    from .engine import clear_cache, compile_model, run
    from .ensemble import EnsembleError, EnsembleResult, propagate_ensemble
    from .errors import IntegrationError, Interrupted, SceneError
    from .files import OutputError, ResultFileError
    from .precision import Precision
    from .result import EventLog, Result
    from .scene import Scene, load_scene


def __getattr__(name: str) -> Any:
    if name == "__version__":
        # Looked up when asked for: importing importlib.metadata costs ~15 ms, a tenth of the
        # command line's start (validation/users_cli.py).
        globals()[name] = value = _version()
        return value
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS, "__version__"})


def _version() -> str:
    from importlib import metadata

    try:
        return metadata.version("cayley_heyoka")
    except metadata.PackageNotFoundError:  # pragma: no cover - source tree without install
        return "0.0.0+unknown"


def load_result(path: str) -> Result:
    """Read a result file written by :meth:`Result.save`."""
    from .result import Result

    return Result.load(path)


__all__ = [
    "EnsembleError",
    "EnsembleResult",
    "EventLog",
    "IntegrationError",
    "Interrupted",
    "OutputError",
    "Precision",
    "Result",
    "ResultFileError",
    "Scene",
    "SceneError",
    "clear_cache",
    "compile_model",
    "load_result",
    "load_scene",
    "propagate_ensemble",
    "run",
]
