"""What a model family hands to the engine: equations, events, outputs and monitors.

A family (rotation, orbit, ...) turns its part of a scene into a :class:`Model`. Everything
downstream (compiling, propagating, recording, saving) works on this description only and
knows nothing about rigid bodies or orbits.

Numerical values that a scene may change (moments of inertia, force strengths, chart bases)
enter the equations as heyoka runtime parameters ``par[i]``, never as literals. Two scenes
that differ only in their numbers therefore share one compiled integrator, and every value is
built in the target precision from its decimal text.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import pickle
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any, TypeAlias

import heyoka as hy

from .precision import Number, Precision

Expr: TypeAlias = hy.expression


class ParTable:
    """The numbers of a model: runtime parameters, and constants built in its precision.

    ``add`` returns ``par[i]`` and remembers the value; ``constant`` returns a number node in
    the run's floating type (:meth:`Precision.constant`), so that nothing a family writes in
    its equations (½, 15/8, a literal of a force function) is a double in a quad system.

    It also keeps where the model's numbers and terms come from in the scene, so that a run
    that cannot start names its cause (:mod:`.causes`): the scene field of each parameter
    (``field``), the expressions parsed from the scene's text and the terms built from its
    tables (:meth:`source`), and the values of placeholder variables such terms were written
    on (:meth:`bind`).

    Parameters
    ----------
    precision
        The run's precision (double when not given: tests of double systems).
    """

    def __init__(self, precision: Precision | None = None) -> None:
        self.precision = precision if precision is not None else Precision()
        self.names: list[str] = []
        self.values: list[Any] = []
        self.fields: list[str | None] = []
        self.sources: list[Source] = []
        self.placeholders: dict[str, Expr] = {}

    def constant(self, value: int | Fraction | str) -> Expr:
        """A number node exactly ``value``, or ``value`` correctly rounded in the precision."""
        return self.precision.constant(value)

    def add(self, name: str, value: Number, field: str | None = None) -> Expr:
        """Allocate a parameter named ``name`` holding ``value``; returns ``par[i]``.

        ``field`` is the scene field (or fields, ``", "``-separated) the value comes from;
        by default a name of the form ``FIELD#k`` (a literal of an expression text) comes
        from ``FIELD``, and another from no field the scene spells.
        """
        if name in self.names:
            raise ValueError(f"parameter {name!r} allocated twice")
        self.names.append(name)
        self.values.append(value)
        self.fields.append(field if field is not None or "#" not in name else name.split("#")[0])
        return hy.par[len(self.names) - 1]

    def index(self, name: str) -> int:
        """Position of a parameter in the heyoka ``pars`` array."""
        return self.names.index(name)

    def source(
        self,
        field: str,
        expression: Expr,
        text: str | None = None,
        symbols: Mapping[str, Expr] | None = None,
    ) -> None:
        """Record that ``expression`` is the scene's ``field``: parsed from ``text`` over
        ``symbols`` (:func:`.expressions.parse_expression` records every text it parses), or
        a term the family built from that table. The first record of a field is kept."""
        if all(s.field != field for s in self.sources):
            self.sources.append(Source(field, expression, text, symbols))

    def bind(self, values: Mapping[str, Expr]) -> None:
        """The values of placeholder variables that recorded sources were written on, as
        expressions of the state (``R11__`` of a force function on the attitude matrix)."""
        self.placeholders.update(values)

    def __len__(self) -> int:
        return len(self.names)


@dataclass(frozen=True)
class Source:
    """A scene expression or term as a model holds it (:meth:`ParTable.source`)."""

    field: str
    expression: Expr
    text: str | None = None
    symbols: Mapping[str, Expr] | None = None


@dataclass
class EventSpec:
    """A non-terminal event: record each zero of ``expression``.

    ``direction`` is 0 (any), +1 (upwards only) or -1 (downwards only); ``label`` says what
    fired (e.g. the body axis), several specs may share one ``name``; ``labels`` replaces it
    by direction of crossing (e.g. ``{1: "ascending", -1: "descending"}``).
    """

    name: str
    label: str
    expression: Expr
    direction: int = 0
    labels: dict[int, str] | None = None

    def label_for(self, direction: int) -> str:
        """The label of an occurrence crossing zero in ``direction``."""
        return self.labels.get(direction, self.label) if self.labels else self.label


@dataclass
class TerminalSpec:
    """A terminal event that lets the family act on the integrator.

    ``handle(integrator, pars)`` is called with the integrator stopped at the event and the
    model's whole parameter vector ``pars`` (the integrator holds only the leading ones its
    equations use; the engine copies them back after the call). It may change the state and
    ``pars`` (e.g. re-base an attitude chart), and the run goes on; or it returns a message,
    and the run ends there with that message (results kept); or it returns a
    :class:`Handover`, and the run goes on from there with another variant of the model.
    ``counter`` names the tally of
    its occurrences in :attr:`Result.counters`. ``records``, if given, is the recorded event
    this stop stands for: the stop is logged as its occurrence (the same zero found twice, by
    two root searches, could otherwise land either side of the stop).

    A handler that keeps state of its own between calls (not in ``pars``) exposes it as
    ``checkpoint() -> JSON value`` and ``resume(value)``, so that an interrupted run continues
    exactly (:meth:`cayley_heyoka.core.engine.Propagation.snapshot`).
    """

    expression: Expr
    direction: int
    handle: Callable[[Any, Any], str | Handover | None]
    counter: str
    records: EventSpec | None = None


@dataclass(frozen=True)
class Handover:
    """A terminal handler's request: go on with ``variant`` of the model (:attr:`Model.variants`).

    The handler has already put the state and the parameters in the variant's terms. The
    variants of one scene share their state variables, parameter table, outputs, monitors and
    recorded events; they differ in their equations and terminal events, so that each compiles
    only the terms its stretch of the motion needs.
    """

    variant: str


def call_handler(spec: TerminalSpec, integrator: Any, pars: Any, t: Any) -> str | Handover | None:
    """``spec.handle(integrator, pars)`` at the event time ``t``: the one way the engine and
    the batch lanes call a terminal handler.

    A handler that cannot act on the state reached — an arithmetic error, or a value it
    cannot take (an orbit no longer an ellipse, a NaN) — stops the run there as if it had
    returned that as its message: the rows up to the event are kept, and nothing escapes
    the engine. Any other exception is a fault of the handler and is raised.
    """
    try:
        return spec.handle(integrator, pars)
    except (ArithmeticError, ValueError) as exc:
        return (
            f"the terminal event {spec.counter!r} could not be handled at t = {t}: {exc}; "
            "results kept up to there"
        )


def own_terminal(specs: Sequence[TerminalSpec]) -> list[TerminalSpec]:
    """``specs`` for one run: a handler that keeps state of its own between calls
    (``checkpoint``) is copied, so that runs of one model never share that state."""
    return [
        TerminalSpec(s.expression, s.direction, copy.deepcopy(s.handle), s.counter, s.records)
        if hasattr(s.handle, "checkpoint")
        else s
        for s in specs
    ]


@dataclass(frozen=True)
class Numbers:
    """What a scene's numbers decide in its model (:meth:`Model.with_numbers`).

    A family that offers ``numbers`` (:class:`~.families.Family`) computes these without
    building any expression: the initial state, in the order of the system, and the value of
    every parameter of the model by name, except the literals of the scene's texts (names
    ``FIELD#k``), which its structure holds.
    """

    initial_state: Sequence[Any]
    values: Mapping[str, Any]


@dataclass
class Model:
    """A model family's description of one scene, ready to compile.

    Attributes
    ----------
    family
        Name of the model family.
    system
        ``(variable, right-hand side)`` pairs, as accepted by ``heyoka.taylor_adaptive``.
    initial_state
        Values of the state variables at the start time, in the order of ``system``.
    pars
        Runtime parameters and their values.
    outputs
        Result variables: name -> expression of the state, the parameters and time. They are
        evaluated on the output grid in the run's precision.
    monitors
        Monitored quantities: name -> expression or list of expressions (a vector).
    conserved
        Monitors that the exact flow conserves for this scene.
    events, terminal
        Recorded and acting events.
    compact
        Compile in compact mode unless the scene says otherwise: the family knows that this
        system's code is large for what it computes (heyoka's non-compact code grows with the
        expression's size, and its compile time faster), where :meth:`size` would not tell.
    decomposition
        The length of heyoka's Taylor decomposition of the system as the family counts it
        (variables, distinct operations, right-hand sides), or None: a measure of the code
        to compile for right-hand sides that share subexpressions, which :meth:`size` counts
        at every use (:func:`.compiler.use_compact_mode`).
    unbounded
        Outputs whose infinite value is a value, not a failure (the Cayley–Rodrigues λ, μ, ν
        at a half-turn): a run never stops for them, nor is refused when they start infinite.
    variant
        This model's name among its scene's variants ("" when it has none).
    variants
        ``name -> Model``: the scene's other variants, built (and kept) on first use; a
        terminal handler moves a run to one by returning :class:`Handover`. None: no others.
    initial_fields
        The scene field each state variable's initial value comes from (``p`` from
        ``initial.rates[0]``), for the refusals of a run that cannot start; a variable not
        listed is named ``initial.NAME``.
    """

    family: str
    system: list[tuple[Expr, Expr]]
    initial_state: Sequence[Any]
    pars: ParTable
    outputs: dict[str, Expr]
    monitors: dict[str, Expr | list[Expr]] = field(default_factory=dict)
    conserved: tuple[str, ...] = ()
    events: list[EventSpec] = field(default_factory=list)
    terminal: list[TerminalSpec] = field(default_factory=list)
    compact: bool = False
    decomposition: int | None = None
    unbounded: tuple[str, ...] = ()
    variant: str = ""
    variants: Callable[[str], Model] | None = None
    initial_fields: dict[str, str] = field(default_factory=dict)

    def initial_field(self, name: str) -> str:
        """The scene field the initial value of state variable ``name`` comes from."""
        return self.initial_fields.get(name, f"initial.{name}")

    @property
    def state_names(self) -> list[str]:
        """Names of the integrated variables."""
        return list(self._state_names)

    @functools.cached_property
    def _state_names(self) -> tuple[str, ...]:
        # Printed once per model (~1 µs a variable, read several times by each run).
        return tuple(str(v) for v, _ in self.system)

    def structure_key(self) -> str:
        """Text that identifies the compiled code: equations and events, not the numbers."""
        parts = [self.family]
        parts += [f"{v}'={_fingerprint(rhs)}" for v, rhs in self.system]
        parts += [
            f"event {e.name}/{e.label}/{e.direction}: {_fingerprint(e.expression)}"
            for e in self.events
        ]
        parts += [
            f"terminal {e.counter}/{e.direction}: {_fingerprint(e.expression)}"
            for e in self.terminal
        ]
        return "\n".join(parts)

    @functools.cached_property
    def code_key(self) -> str:
        """:meth:`structure_key` and :meth:`output_key` together, computed once per model (a
        model is not changed once its family has built it)."""
        return self.structure_key() + "\n" + self.output_key()

    def output_key(self) -> str:
        """Text that identifies the compiled evaluator of outputs and monitors."""
        parts = [self.family, ",".join(self.state_names)]
        parts += [f"{k}={_fingerprint(v)}" for k, v in self.outputs.items()]
        parts += [f"{k}={_fingerprint(v)}" for k, v in self.monitors.items()]
        return "\n".join(parts)

    def integrator_parameters(self) -> int:
        """How many leading parameters the equations and events use (heyoka's ``pars`` size).

        Parameters used only by outputs or monitors may follow them; heyoka refuses a
        parameter vector longer than its equations need.
        """
        return self._held

    @functools.cached_property
    def _held(self) -> int:
        exprs = [rhs for _, rhs in self.system]
        exprs += [e.expression for e in self.events] + [e.expression for e in self.terminal]
        used = [int(str(p)[1:]) for p in hy.get_params(exprs)]
        return max(used) + 1 if used else 0

    def with_numbers(self, numbers: Numbers) -> Model:
        """This model's structure with another scene's numbers: the same expressions, events,
        handlers and compiled code (its keys are not computed again), ``numbers``' initial
        state and parameter values.

        Raises
        ------
        ValueError
            ``numbers`` does not fit the structure: another state size, a parameter it does not
            have, or one it leaves without a value (a fault of the family's ``numbers``).
        """
        if len(numbers.initial_state) != len(self.system):
            raise ValueError(
                f"{len(numbers.initial_state)} initial values for {len(self.system)} variables"
            )
        table = copy.copy(self.pars)
        table.values = values = list(self.pars.values)
        names = self.pars.names
        given = 0
        for i, name in enumerate(names):
            if name in numbers.values:
                values[i] = numbers.values[name]
                given += 1
            elif "#" not in name:
                raise ValueError(f"no value for the parameter {name!r}")
        if given != len(numbers.values):
            unknown = sorted(set(numbers.values) - set(names))
            raise ValueError(f"values for parameters the model does not have: {unknown}")
        model = dataclasses.replace(
            self,
            initial_state=list(numbers.initial_state),
            pars=table,
            outputs=dict(self.outputs),
            monitors=dict(self.monitors),
            events=list(self.events),
            terminal=list(self.terminal),
        )
        for key in ("code_key", "_held", "_state_names"):  # the structure's, computed once
            if key in self.__dict__:
                model.__dict__[key] = self.__dict__[key]
        return model

    def size(self) -> int:
        """Bytes of the serialised right-hand sides: a measure of the code to compile."""
        return sum(len(pickle.dumps(rhs)) for _, rhs in self.system)


def _fingerprint(expr: Expr | list[Expr]) -> str:
    """heyoka's structural hash of the whole expression tree (of each, for a list).

    Not ``str(expr)``: heyoka elides the middle of long expressions when printing them, so two
    systems differing only there would print alike (and share a compiled integrator). Not a
    pickle either: serialising every expression cost more than a short run (1.5 ms of a 3.5 ms
    run of the free body). heyoka's hash walks the tree in C++ (every node, numbers by value,
    parameters by index, microseconds) and differs for ``x - y`` and ``y - x``, ``p0*x + p1*y``
    and ``p1*x + p0*y``, real128's 0.1 and double's 0.1; two different right-hand sides would
    need a 64-bit collision to share code.
    """
    exprs = expr if isinstance(expr, list) else [expr]
    return ":".join(format(hash(e) & (2**64 - 1), "016x") for e in exprs)
