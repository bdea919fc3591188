"""Model families: the protocol each implements, and the registry that finds them.

A family owns some of a scene's tables and turns them into a :class:`~.model.Model`; the core
(scene, engine) and the workflows (checks, references, sweeps, plots, the command line) reach
it only through its :class:`Family` record, never by its name. Ours are registered here by
module path; another package adds one through the entry-point group
``cayley_heyoka.families`` (``name = "package.module:FAMILY"``), without touching ours. A
family's module is imported the first time the registry is asked for it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from importlib import import_module
from typing import Any

from .errors import SceneError

#: The entry-point group through which another package registers a family.
ENTRY_POINTS = "cayley_heyoka.families"
_OURS = {
    "rotation": "cayley_heyoka.rotation.family:FAMILY",
    "orbit": "cayley_heyoka.orbit.family:FAMILY",
    "hamiltonian": "cayley_heyoka.hamilton.family:FAMILY",
}


@dataclass(frozen=True)
class Family:
    """What a model family provides.

    Attributes
    ----------
    name
        The family's name (``scene.family``).
    key_table
        The scene table that identifies the family.
    tables
        Every table the family owns.
    parse
        The family's tables (a mapping) → its parsed, validated model description.
    build
        A scene → its :class:`~.model.Model`.
    validate
        Validation that needs the whole scene (the start time, the outputs), or None; raises
        :class:`~.errors.SceneError`. (Not a consistency check: that is ``consistency_check``.)
    output_keys
        Output-table keys the family adds to the generic ones.
    consistency_check
        ``(scene, options) -> CheckReport`` (:mod:`.consistency`; ``cayley-heyoka check``),
        or None.
    closed_form
        ``scene -> ClosedForm | None`` (:mod:`.closed_form`): the motion in closed form where
        the scene has one (``cayley-heyoka reference``), or None for a family without any.
    plot_kinds
        The kinds of plot the family draws beside the drift (``cayley-heyoka plot --kind``).
    plots
        ``() -> {kind: Plot}`` (:mod:`.figures`), loaded when a plot is drawn; None without.
    variables
        ``(scene, name) -> str | None``: what an output or monitor of the family's results is
        (``cayley-heyoka info --variables``); a light module, loaded without heyoka.
    references
        The family's closed forms for users, public name → module
        (:mod:`cayley_heyoka.reference` serves them).
    memoirs
        Keys of :data:`.citation.MEMOIRS`: the memoirs the family's equations implement
        (:func:`cayley_heyoka.cite`).
    formulations
        ``("table.key", (value, ...))``: the scene key that picks the family's formulation and
        the values a planner may try (:mod:`cayley_heyoka.workflows.planner`), or None. The
        parsed model's ``formulation`` attribute, where it has one, names the scene's own.
    with_formulation
        ``(scene, value) -> dict``: the scene's dictionary in another of its formulations (see
        :meth:`in_formulation`), or None where setting the key is all it takes.
    """

    name: str
    key_table: str
    tables: tuple[str, ...]
    parse: Callable[[Mapping[str, Any]], Any]
    build: Callable[[Any], Any]
    validate: Callable[[Any], None] | None = None
    output_keys: tuple[str, ...] = ()
    consistency_check: Callable[[Any, Any], Any] | None = None
    closed_form: Callable[[Any], Any] | None = None
    plot_kinds: tuple[str, ...] = ()
    plots: Callable[[], Mapping[str, Any]] | None = None
    variables: Callable[[Mapping[str, Any], str], str | None] | None = None
    references: Mapping[str, str] = field(default_factory=dict)
    memoirs: tuple[str, ...] = ()
    formulations: tuple[str, tuple[str, ...]] | None = None
    with_formulation: Callable[[Any, str], dict[str, Any]] | None = None

    def formulation_of(self, scene: Any) -> str | None:
        """The formulation ``scene`` is written in (None: the family offers no other)."""
        if self.formulations is None:
            return None
        own = getattr(scene.model, "formulation", None)
        if isinstance(own, str):
            return own
        table, key = self.formulations[0].split(".")
        value = scene.source.get(table, {}).get(key)
        return value if isinstance(value, str) else None

    def in_formulation(self, scene: Any, value: str) -> dict[str, Any]:
        """The scene's dictionary with the same motion in formulation ``value``.

        The one way every verb (the planner's pilots, the checks' twins) changes a scene's
        formulation: every option the target takes is kept (outputs, monitors, events, units,
        the integrator's options), and keys that only another formulation takes are converted
        or dropped by the family's ``with_formulation``.

        Raises
        ------
        SceneError
            The family has no formulations, or ``value`` cannot express the scene (naming the
            key and why).
        """
        if self.formulations is None:
            raise SceneError("scene", f"the {self.name} family has no other formulation")
        if self.with_formulation is not None:
            return self.with_formulation(scene, value)
        data = scene.to_dict()
        table, key = self.formulations[0].split(".")
        data.setdefault(table, {})[key] = value
        return data


def later(module: str, name: str) -> Callable[..., Any]:
    """``module.name`` (``name`` may be dotted: ``"Class.method"``) called with the same
    arguments, imported at the first call: a family's record imports nothing of the family,
    so finding a scene's family, or describing a result's variables, loads no heyoka."""

    def call(*args: Any) -> Any:
        target: Any = import_module(module)
        for part in name.split("."):
            target = getattr(target, part)
        return target(*args)

    call.__qualname__ = f"later({module}.{name})"
    return call


def _with_user_monitors(build: Callable[[Any], Any]) -> Callable[[Any], Any]:
    """A family's ``build`` that adds the scene's ``[monitors]`` (:mod:`.user_monitors`) to
    the model, so that every family offers them without knowing of them."""

    def call(scene: Any) -> Any:
        from .user_monitors import add_monitors, family_view

        return add_monitors(build(family_view(scene)), scene)

    call.__qualname__ = f"with_user_monitors({getattr(build, '__qualname__', build)})"
    return call


def _with_user_variables(
    variables: Callable[[Mapping[str, Any], str], str | None] | None,
) -> Callable[[Mapping[str, Any], str], str | None]:
    """A family's ``variables`` that also describes the scene's ``[monitors]``."""

    def call(scene: Mapping[str, Any], name: str) -> str | None:
        table = scene.get("monitors") if isinstance(scene, Mapping) else None
        spec = table.get(name) if isinstance(table, Mapping) else None
        if isinstance(spec, Mapping) and isinstance(spec.get("expression"), str):
            judged = "conserved" if spec.get("conserved", True) is True else "not conserved"
            return f"user monitor ({judged}): {spec['expression']}"
        return variables(scene, name) if variables is not None else None

    return call


class _Registry(Mapping[str, Family]):
    """Family name → :class:`Family`, each imported when first asked for."""

    def __init__(self) -> None:
        self._paths: dict[str, str] | None = None
        self._loaded: dict[str, Family] = {}

    def _known(self) -> dict[str, str]:
        if self._paths is None:
            from importlib import metadata

            paths = dict(_OURS)
            for ep in metadata.entry_points(group=ENTRY_POINTS):
                if ep.name in _OURS:
                    raise SceneError(
                        "families",
                        f"the entry point {ep.value!r} registers a family named {ep.name!r}, "
                        "which is one of cayley_heyoka's own",
                    )
                paths[ep.name] = ep.value
            self._paths = paths
        return self._paths

    def __getitem__(self, name: str) -> Family:
        family = self._loaded.get(name)
        if family is None:
            path = self._known()[name]
            module, _, attr = path.partition(":")
            try:
                family = getattr(import_module(module), attr or "FAMILY")
            except Exception as exc:  # another package's family failing to load: say which
                raise SceneError(
                    "families",
                    f"the family {name!r} ({path}) cannot be loaded: {type(exc).__name__}: {exc}",
                ) from exc
            if not isinstance(family, Family) or family.name != name:
                raise SceneError("families", f"{path!r} is not the Family {name!r}")
            family = replace(
                family,
                build=_with_user_monitors(family.build),
                variables=_with_user_variables(family.variables),
            )
            self._loaded[name] = family
        return family

    def __iter__(self) -> Iterator[str]:
        return iter(self._known())

    def __len__(self) -> int:
        return len(self._known())


FAMILIES: Mapping[str, Family] = _Registry()


def family_of(data: Mapping[str, Any]) -> str:
    """The family whose identifying table the scene has.

    A family of another package that fails to load does not stop scenes of the others; it is
    named in the error when no loaded family claims the scene.
    """
    families, broken = [], []
    for name in FAMILIES:
        try:
            families.append(FAMILIES[name])
        except SceneError as exc:
            broken.append(exc.constraint)
    found = [f.name for f in families if f.key_table in data]
    if len(found) == 1:
        return found[0]
    expected = ", ".join(f"[{f.key_table}] ({f.name})" for f in families)
    if not found and "sweep" in data:
        raise SceneError(
            "scene",
            "is a study (it has a [sweep] table), not a scene: run it with `cayley-heyoka sweep` "
            "(in Python, `run_sweep`)",
        )
    if not found:
        also = "".join(f"; {b}" for b in broken)
        raise SceneError(
            "scene", f"names no model family; expected one of the tables {expected}{also}"
        )
    raise SceneError("scene", f"names several model families {found}; use one of {expected}")
