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
    "clear_cache": "core.compiler",
    "compile_model": "core.compiler",
    "run": "core.engine",
    "EnsembleError": "workflows.ensemble",
    "EnsembleResult": "workflows.ensemble",
    "propagate_ensemble": "workflows.ensemble",
    "IntegrationError": "core.errors",
    "Interrupted": "core.errors",
    "SceneError": "core.errors",
    "OutputError": "core.files",
    "ResultFileError": "core.files",
    "Precision": "core.precision",
    "EventLog": "core.result",
    "Result": "core.result",
    "Scene": "core.scene",
    "load_scene": "core.scene",
    "check_scene": "workflows.checks",
    "cite": "core.citation",
    "ensemble_state": "workflows.ensemble",
    "generate_reference": "workflows.reference",
    "read_certificate": "workflows.reference",
    "run_sweep": "workflows.sweep",
    "load_study": "workflows.study",
    "Study": "workflows.study",
    "plan": "workflows.planner",
    "Plan": "workflows.planner",
    "load_sweep": "workflows.sweep_result",
}
#: Public submodules, loaded on first use (``from cayley_heyoka import plots``).
_MODULES = {"plots": "plots"}

if TYPE_CHECKING:
    from . import plots
    from .core.citation import cite
    from .core.compiler import clear_cache, compile_model
    from .core.engine import run
    from .core.errors import IntegrationError, Interrupted, SceneError
    from .core.files import OutputError, ResultFileError
    from .core.precision import Precision
    from .core.result import EventLog, Result
    from .core.scene import Scene, load_scene
    from .workflows.checks import check_scene
    from .workflows.ensemble import (
        EnsembleError,
        EnsembleResult,
        ensemble_state,
        propagate_ensemble,
    )
    from .workflows.reference import generate_reference, read_certificate
    from .workflows.study import Study, load_study
    from .workflows.sweep import run_sweep
    from .workflows.sweep_result import load_sweep


def __getattr__(name: str) -> Any:
    if name == "__version__":
        # Looked up when asked for: importing importlib.metadata costs ~15 ms, a tenth of the
        # command line's start (validation/users_cli.py).
        globals()[name] = value = _version()
        return value
    if name in _MODULES:
        value = import_module(f".{_MODULES[name]}", __name__)
        globals()[name] = value
        return value
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS, *_MODULES, "__version__"})


def _version() -> str:
    from importlib import metadata

    try:
        return metadata.version("cayley_heyoka")
    except metadata.PackageNotFoundError:  # pragma: no cover - source tree without install
        return "0.0.0+unknown"


def load_result(path: str) -> Result:
    """Read a result file written by :meth:`Result.save`."""
    from .core.result import Result

    return Result.load(path)


__all__ = [
    "EnsembleError",
    "EnsembleResult",
    "EventLog",
    "IntegrationError",
    "Interrupted",
    "OutputError",
    "Plan",
    "Precision",
    "Result",
    "ResultFileError",
    "Scene",
    "SceneError",
    "Study",
    "check_scene",
    "cite",
    "clear_cache",
    "compile_model",
    "ensemble_state",
    "generate_reference",
    "load_result",
    "load_scene",
    "load_study",
    "load_sweep",
    "plan",
    "plots",
    "propagate_ensemble",
    "read_certificate",
    "run",
    "run_sweep",
]
