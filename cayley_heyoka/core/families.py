"""Model families: the protocol each implements, and the registry that finds them.

A family owns some of a scene's tables and turns them into a :class:`~.model.Model`; the core
(scene, engine) and the workflows (checks, references, sweeps, plots, the command line) reach
it only through its :class:`Family` record, never by its name. Ours are registered here by
module path; another package adds one through the entry-point group
``cayley_heyoka.families`` (``name = "package.module:FAMILY"``), without touching ours. A
family's module is imported the first time the registry is asked for it.

A family of another package cannot take what is ours or another's: a family named like one
of ours, one that claims one of our families' tables or a table every scene has
(:data:`.names.SCENE_TABLES`), two that claim one table or one name, and one that fails to
load are not used (they are left out of the registry, and named when a scene finds no
family). Their hooks run guarded: an exception other than :class:`~.errors.SceneError` or
:class:`~.errors.IntegrationError` escaping one becomes a :class:`~.errors.SceneError`
naming the family and the hook.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from importlib import import_module
from typing import Any

from .errors import IntegrationError, SceneError
from .names import SCENE_TABLES, check_model

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
    events
        The names of the events the family offers (``output.events``): no user event
        (``[events.NAME]``) may take one (:func:`.names.check_scene`).
    with_formulation
        ``(scene, value) -> dict``: the scene's dictionary in another of its formulations (see
        :meth:`in_formulation`), or None where setting the key is all it takes.
    structure, numbers
        Structure once, numbers many (:mod:`.structures`): ``structure(scene) -> str | None``
        names what ``build`` compiles for the scene, from the scene alone (equal texts: equal
        expressions, events and handlers; None: not offered for this scene), and
        ``numbers(scene) -> Numbers`` (:class:`~.model.Numbers`) the values ``build`` gives
        its state and parameters, without building an expression. Both or neither.
    table
        ``(scene, model, fields, values, exact, low) -> Table | None``
        (:func:`.structures.table_for`): the numbers of many scenes that are ``scene`` (whose
        model is ``model``) with other double ``values`` (``(scenes, fields)``; ``exact``: each
        is its scene's number exactly; ``low``: the number minus the double, to a double) at
        the scene paths ``fields``, as arrays rounded as ``numbers`` rounds; rows it cannot
        vouch for marked suspect; None where it offers none for these fields. Optional.
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
    events: tuple[str, ...] = ()
    with_formulation: Callable[[Any, str], dict[str, Any]] | None = None
    structure: Callable[[Any], str | None] | None = None
    numbers: Callable[[Any], Any] | None = None
    table: Callable[..., Any] | None = None

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


def named(choices: Mapping[str, Any], field: str, name: Any) -> Any:
    """The entry of ``choices`` (a family's formulations by name) that scene key ``field``
    names; the refusal lists the names.

    Raises
    ------
    SceneError
        ``field``: ``name`` (of any type: a list, a dictionary) is none of ``choices``.

    Examples
    --------
    >>> named({"a": 1}, "model.formulation", "a")
    1
    """
    found = choices.get(name) if isinstance(name, str) else None
    if found is None:
        raise SceneError(field, f"must be one of {tuple(choices)}, got {name!r}")
    return found


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


def _with_user_monitors(family: Family) -> Callable[[Any], Any]:
    """A family's ``build`` that checks the model's names (:func:`.names.check_model`) and adds
    the scene's ``[monitors]`` (:mod:`.user_monitors`), so that every family offers them
    without knowing of them."""
    build = family.build

    def call(scene: Any) -> Any:
        from .user_monitors import add_monitors, family_view

        model = build(family_view(scene))
        check_model(model, scene.monitors, family.key_table)
        return add_monitors(model, scene)

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


#: The fields of a family's record that call its package's code.
_HOOKS = (
    "parse",
    "build",
    "validate",
    "consistency_check",
    "closed_form",
    "plots",
    "variables",
    "structure",
    "numbers",
    "table",
)


def _guarded(family: Family, path: str) -> Family:
    """``family`` (of another package) with each hook's unexpected exception turned into a
    :class:`SceneError` that names the family and the hook: a fault in that package is one
    line, not a traceback."""

    def guard(hook: str, fn: Callable[..., Any]) -> Callable[..., Any]:
        def call(*args: Any) -> Any:
            try:
                return fn(*args)
            except (SceneError, IntegrationError):
                raise
            except Exception as exc:
                raise SceneError(
                    "families",
                    f"the family {family.name!r} ({path}) failed in its {hook}: "
                    f"{type(exc).__name__}: {exc} (a fault in that package, not in the scene)",
                ) from exc

        call.__qualname__ = f"guarded({getattr(fn, '__qualname__', fn)})"
        return call

    hooks: dict[str, Any] = {
        h: guard(h, fn) for h in _HOOKS if (fn := getattr(family, h)) is not None
    }
    return replace(family, **hooks)


@dataclass
class _Entries:
    """What the registry found: the path of every family it may use, why it refuses the
    others, and the records loaded so far."""

    paths: dict[str, str]
    refused: dict[str, str]
    loaded: dict[str, Family] = field(default_factory=dict)
    checked: bool = False


class _Registry(Mapping[str, Family]):
    """Family name → :class:`Family`: ours, and the usable families of other packages.

    Ours are imported when first asked for; the others all together, the first time one of
    them is asked for or the registry is listed, since a family of another package is used
    only if no other claims its tables.
    """

    def __init__(self) -> None:
        self._entries: _Entries | None = None

    def _found(self) -> _Entries:
        if self._entries is None:
            from importlib import metadata

            values: dict[str, list[str]] = {}
            for ep in metadata.entry_points(group=ENTRY_POINTS):
                values.setdefault(ep.name, [])
                if ep.value not in values[ep.name]:
                    values[ep.name].append(ep.value)
            paths, refused = dict(_OURS), {}
            for name, found in values.items():
                if name in _OURS:
                    refused[name] = (
                        f"the entry point {found[0]!r} registers a family named {name!r}, which "
                        "is one of cayley_heyoka's own: it is not used"
                    )
                elif len(found) > 1:
                    refused[name] = (
                        f"the entry points {', '.join(map(repr, found))} all register a family "
                        f"named {name!r}: none is used (uninstall all but one)"
                    )
                else:
                    paths[name] = found[0]
            self._entries = _Entries(paths, refused)
        return self._entries

    def _load(self, name: str, path: str) -> Family:
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
        if family.key_table not in family.tables:
            raise SceneError(
                "families",
                f"the family {name!r} ({path}) has the key table [{family.key_table}] outside "
                f"its tables {list(family.tables)}",
            )
        if name not in _OURS:
            family = _guarded(family, path)
        return replace(
            family,
            build=_with_user_monitors(family),
            variables=_with_user_variables(family.variables),
        )

    def _check_others(self) -> None:
        """Load every family of another package, once, and refuse those that fail to load or
        would take a table from another family.

        A scene's family is the one whose key table it has, so a key table is one family's
        alone: no other family may have it among its tables, and it is none of the tables
        every scene has (:data:`.names.SCENE_TABLES`), which no family may have at all. The
        other tables are read by their family only, and may share a name (our rotation and
        Hamiltonian families both have ``[initial]``).
        """
        entries = self._found()
        if entries.checked:
            return
        entries.checked = True
        others: dict[str, Family] = {}
        refused: dict[str, str] = {}
        for name, path in entries.paths.items():
            if name not in _OURS:
                try:
                    others[name] = self._load(name, path)
                except SceneError as exc:
                    refused[name] = exc.constraint
        ours = {name: self[name] for name in _OURS}
        for name, family in others.items():
            path = entries.paths[name]
            if common := [t for t in family.tables if t in SCENE_TABLES]:
                refused[name] = (
                    f"the family {name!r} ({path}) claims the table [{common[0]}] that every "
                    "scene may have: it is not used"
                )
                continue
            for rival, theirs in [*ours.items(), *others.items()]:
                if rival == name:
                    continue
                if family.key_table in theirs.tables:
                    table = family.key_table
                elif theirs.key_table in family.tables:
                    table = theirs.key_table
                else:
                    continue
                whose = "cayley_heyoka's" if rival in _OURS else "the"
                refused[name] = (
                    f"the family {name!r} ({path}) claims the table [{table}], which {whose} "
                    f"family {rival!r} also has, and a scene names its family by that table: "
                    f"{name!r} is not used"
                )
                break
            else:
                entries.loaded[name] = family
        for name in refused:
            del entries.paths[name]
        entries.refused.update(refused)

    def __getitem__(self, name: str) -> Family:
        entries = self._found()
        family = entries.loaded.get(name)
        if family is not None:
            return family
        if name in _OURS:
            family = self._load(name, _OURS[name])
            entries.loaded[name] = family
            return family
        self._check_others()
        if name in entries.loaded:
            return entries.loaded[name]
        if name in entries.refused:
            raise SceneError("families", entries.refused[name])
        raise KeyError(name)

    def __contains__(self, name: object) -> bool:
        return name in self._usable()

    def _usable(self) -> list[str]:
        self._check_others()
        entries = self._found()
        return [n for n in entries.paths if n in _OURS or n in entries.loaded]

    def __iter__(self) -> Iterator[str]:
        return iter(self._usable())

    def __len__(self) -> int:
        return len(self._usable())

    def refused(self) -> list[str]:
        """Why each family of another package that is not used is not (one line each)."""
        self._check_others()
        return list(self._found().refused.values())


_REGISTRY = _Registry()
FAMILIES: Mapping[str, Family] = _REGISTRY


def refused_families() -> list[str]:
    """Why each installed family of another package is not used, one line each (none when
    every one is)."""
    return _REGISTRY.refused()


def family_of(data: Mapping[str, Any]) -> str:
    """The family whose identifying table the scene has.

    A family of another package that is not used (it fails to load, or claims a table that is
    not its own: :class:`_Registry`) does not stop scenes of the others; it is named in the
    error when no family claims the scene.
    """
    families = [FAMILIES[name] for name in FAMILIES]
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
        also = "".join(f"; {b}" for b in refused_families())
        raise SceneError(
            "scene", f"names no model family; expected one of the tables {expected}{also}"
        )
    raise SceneError("scene", f"names several model families {found}; use one of {expected}")
