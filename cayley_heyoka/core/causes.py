"""Why a run cannot start: the first of a model's inputs, in causal order, that is not finite
at the start, named by its scene field.

A run is refused when an output or monitor is not finite at the first output time (the
engine's check, which needs nothing beyond the evaluation of the first row). Only then, on
this slow path, is the model's provenance (:class:`.model.ParTable`: the scene fields of its
numbers, the expressions parsed from the scene's text and the terms built from its tables)
evaluated in the run's precision at the start, in the order in which each feeds the next:

1. the scene's expressions and terms (V, H, Ω, the flow, user events and monitors, a
   family's force terms): the first that is not finite is named, with the operation of its
   text that first is not (``1/eta1 divides by zero``) and the values of the names it uses;
2. the right-hand sides of the equations — one that is not finite is first traced to the
   derivative of a scene expression that is not (the equations take the slopes of V, H, Ω:
   ``H = "… + sqrt(eta1)"`` at η₁ = 0);
3. the outputs and monitors.

The same search runs when the first step of a run is not finite (:func:`explain_start`): a
cause found at the start refuses the run, which kept nothing.

A quantity of finite inputs that is not finite (a right-hand side, a built-in output, a term
with no text) is evaluated again in MPFR, whose exponent range has no practical bound: finite
there, the numbers of its inputs overflow the run's precision ("scale the units"); not finite
there either, the inputs are at a singularity of it. Either way the inputs' scene fields are
named (``body.inertia, initial.rates``), never the derived quantity alone.

The expressions of the scene's text are evaluated at the start of every run that has any
(:func:`check_sources`, with a compiled function kept per model structure): no output need
show them.
"""

from __future__ import annotations

import functools
import re
from collections.abc import Iterable, Sequence
from typing import Any

import heyoka as hy
import mpmath
import numpy as np

from .errors import SceneError
from .expressions import Node, trace
from .model import Expr, Model, Source
from .precision import Precision

#: heyoka's name of the time in an expression's text (no state variable is named t).
_TIME = re.compile(r"\bt\b")
#: Extra significand bits of the wide evaluation (the exponent range is what matters).
_WIDE_BITS = 64
#: Outputs of one compiled evaluation above which it is compiled in compact mode.
_COMPACT_OUTPUTS = 50
#: Nodes of a text beyond which its operations are not evaluated one by one (each is an
#: output of one compiled function, and each slope a derivative): the text is named alone.
_MAX_TRACE = 1_000
#: What heyoka raises for an expression it cannot compile or evaluate in a type.
_NOT_EVALUATED = (ValueError, TypeError, RuntimeError, OverflowError)


def start_failure(
    model: Model,
    precision: Precision,
    state: np.ndarray,
    pars: np.ndarray,
    t0: Any,
    first: dict[str, np.ndarray],
) -> SceneError:
    """The refusal of a run whose outputs and monitors ``first`` (at ``t0``) are not all finite.

    Parameters
    ----------
    model
        The model being started.
    precision
        The run's precision (of ``state``, ``pars`` and ``t0``).
    state, pars
        The initial state and the whole parameter vector (both finite).
    t0
        The start time.
    first
        The outputs and monitors at the start, by name (:func:`.recording.evaluate_outputs`).
    """
    at = _Start(model, precision, state, pars, t0)
    found = at.cause(first)
    if found is not None:
        return found
    for name, value in first.items():
        flat = np.ravel(value)
        bad = np.flatnonzero(~np.isfinite(flat))
        if name not in model.unbounded and len(bad):
            kind = "monitor" if name in model.monitors else "output"
            return SceneError(
                f"{kind}s.{name}",
                f"the {kind} is {flat[bad[0]]} at the start: it must be finite to integrate",
            )
    raise ValueError("start_failure() of a start whose outputs are finite")


def explain_start(
    model: Model, precision: Precision, state: np.ndarray, pars: np.ndarray, t0: Any
) -> SceneError | None:
    """The first of the model's expressions, terms and right-hand sides that is not finite at
    the start ``t0`` (steps 1 and 2 of the module docstring), as the refusal naming it; None
    if all are finite."""
    return _Start(model, precision, state, pars, t0).cause(None)


def check_sources(
    model: Model, precision: Precision, state: np.ndarray, pars: np.ndarray, t0: Any
) -> None:
    """Refuse an expression of the scene's text that is not finite at the start (V, H, Ω, a
    flow, a user event), by the operation of its text that is not: the outputs need not show
    it (an event's expression is in none; V is in the energy only if it is monitored), and a
    run would go on with an infinite force function or an event with no zero to find.

    A text is not refused for a name it uses that is itself not finite there (the Rodrigues
    λ at a half-turn, Θ on the tilted frame): such outputs are values. User monitors are
    outputs, checked with them.
    """
    texts = [
        s for s in model.pars.sources if s.text is not None and not s.field.startswith("monitors.")
    ]
    if not texts:
        return
    key = (precision.name, model.code_key, *[s.field for s in texts])
    at = _Start(model, precision, state, pars, t0)
    function = _SOURCE_FUNCTIONS.get(key)
    try:
        if function is None:
            exprs = [at.at_state(s.expression) for s in texts]
            if any(e is None for e in exprs):
                return
            function = at.compile(exprs)
            if len(_SOURCE_FUNCTIONS) >= _SOURCE_FUNCTIONS_HELD:
                _SOURCE_FUNCTIONS.pop(next(iter(_SOURCE_FUNCTIONS)))
            _SOURCE_FUNCTIONS[key] = function
        values = at.call(function)
    except _NOT_EVALUATED:
        return  # a check that cannot be made does not stop a run: its outputs were checked
    for source, value in zip(texts, values, strict=True):
        if not np.isfinite(value):
            blamed = at.blame_source(source, value)
            if isinstance(blamed, SceneError):
                raise blamed


#: Compiled functions of :func:`check_sources`, by model structure and precision.
_SOURCE_FUNCTIONS: dict[tuple, Any] = {}
_SOURCE_FUNCTIONS_HELD = 64


class _Start:
    """A model's inputs at its start, evaluated on demand in the run's precision."""

    def __init__(
        self, model: Model, precision: Precision, state: np.ndarray, pars: np.ndarray, t0: Any
    ) -> None:
        self.model, self.precision = model, precision
        self.state, self.pars, self.t0 = state, pars, t0

    # Worded or compiled only when needed: a run whose texts are finite at the start (the
    # compiled check cached) uses none of them.
    @functools.cached_property
    def variables(self) -> list[Expr]:
        return [v for v, _ in self.model.system]

    @functools.cached_property
    def names(self) -> set[str]:
        return set(self.model.state_names)

    @functools.cached_property
    def t0_text(self) -> str:
        return _show(self.t0)

    # ------------------------------------------------------------------ evaluation
    def compile(self, exprs: Sequence[Expr], wide: bool = False) -> Any:
        """A compiled function of ``exprs`` over the state (MPFR, if ``wide``)."""
        if wide:
            kwargs: dict[str, Any] = {"fp_type": hy.real, "prec": self.wide_bits}
        else:
            kwargs = self.precision.heyoka_kwargs
        compact = len(exprs) > _COMPACT_OUTPUTS
        return hy.cfunc(list(exprs), self.variables, compact_mode=compact, **kwargs)

    @property
    def wide_bits(self) -> int:
        return max(self.precision.bits, 113) + _WIDE_BITS

    def call(self, function: Any, wide: bool = False) -> np.ndarray:
        """``function`` (from :meth:`compile`) at the start: one value per expression."""
        state, pars, t0 = self.state, self.pars, self.t0
        if wide:
            bits = self.wide_bits
            state = np.array([hy.real(v, bits) for v in state], dtype=hy.real)
            pars = np.array([hy.real(v, bits) for v in pars], dtype=hy.real)
            t0 = hy.real(t0, bits)
        kwargs: dict[str, Any] = {"time": np.array([t0], dtype=state.dtype)}
        if function.nparams:
            kwargs["pars"] = np.ascontiguousarray(pars[: function.nparams, None])
        return function(np.ascontiguousarray(state[:, None]), **kwargs)[:, 0]

    def values(self, exprs: Sequence[Expr | None], wide: bool = False) -> list[Any]:
        """Each expression's value at the start (None for one that cannot be evaluated)."""
        known = [e for e in exprs if e is not None]
        if not known:
            return [None] * len(exprs)
        try:
            got = iter(self.call(self.compile(known, wide), wide))
        except _NOT_EVALUATED:
            return [None] * len(exprs)
        return [None if e is None else next(got) for e in exprs]

    def at_state(self, expr: Expr) -> Expr | None:
        """``expr`` over the state variables: placeholders (:meth:`ParTable.bind`) and names
        of outputs replaced by their values; None if it uses another variable."""
        extra = [v for v in hy.get_variables(expr) if v not in self.names]
        if not extra:
            return expr
        values = {}
        for name in extra:
            value = self.model.pars.placeholders.get(name, self.model.outputs.get(name))
            if not isinstance(value, hy.expression):  # a vector monitor, or nothing
                return None
            values[name] = value
        return hy.subs(expr, values)

    # ------------------------------------------------------------------ causes
    def cause(self, first: dict[str, np.ndarray] | None) -> SceneError | None:
        """The first cause in the order of the module docstring (outputs only if ``first``
        is given)."""
        sources = self.model.pars.sources
        deferred: list[SceneError] = []
        for source, value in zip(
            sources, self.values([self.at_state(s.expression) for s in sources]), strict=True
        ):
            if value is None or np.isfinite(value):
                continue
            blamed = self.blame_source(source, value)
            if isinstance(blamed, _Deferred):
                deferred.append(blamed.error)
            elif blamed is not None:
                return blamed
            else:
                return self.derived(source.field, source.expression, value, "its term is")
        rhs = [r for _, r in self.model.system]
        for (variable, expr), value in zip(self.model.system, self.values(rhs), strict=True):
            if value is not None and not np.isfinite(value):
                # The equations take the slopes of V, H, Ω: one of them may be the cause.
                slope = self.slopes(sources)
                if slope is not None:
                    return slope
                what = f"the rate of {variable} in the equations is"
                return self.derived(None, expr, value, what)
        users = {s.field for s in sources}
        for name, value in (first or {}).items():
            if name in self.model.unbounded or f"monitors.{name}.expression" in users:
                continue
            flat = np.ravel(value)
            bad = np.flatnonzero(~np.isfinite(flat))
            if not len(bad):
                continue
            kind = "monitor" if name in self.model.monitors else "output"
            expr = self.model.monitors.get(name, self.model.outputs.get(name))
            label = f"the {kind} {name}"
            if isinstance(expr, list):
                expr, label = expr[int(bad[0])], f"{label}[{int(bad[0])}]"
            return self.derived(None, expr, flat[bad[0]], f"{label} is", f"{kind}s.{name}")
        return deferred[0] if deferred else None

    def blame_source(self, source: Source, value: Any) -> SceneError | _Deferred | None:
        """Why the scene's ``source`` is ``value`` (not finite) at the start: its text's
        operation that first is not finite; a :class:`_Deferred` when that is a name standing
        for a quantity that is itself not finite; None for a term without text."""
        if source.text is None or source.symbols is None:
            return None
        plain = SceneError(source.field, f"is {value} at the start (t = {self.t0_text})")
        nodes = trace(source.text, source.symbols, self.model.pars, source.field)
        if not nodes or len(nodes) > _MAX_TRACE:
            return plain
        values = self.values([self.at_state(n.expression) for n in nodes])
        if any(v is None for v in values):
            return plain
        i = len(nodes) - 1
        while True:
            bad = [j for j in nodes[i].operands if not np.isfinite(values[j])]
            if not bad:
                break
            i = bad[0]
        culprit = nodes[i]
        head = f"is {value} at the start (t = {self.t0_text}): "
        if culprit.kind == "name":
            return _Deferred(
                SceneError(
                    source.field,
                    f"{head}it uses {culprit.text}, which is {values[i]} there"
                    f"{self._from(culprit.expression)}",
                )
            )
        why = self._why(culprit, [(nodes[j], values[j]) for j in culprit.operands], values[i])
        return SceneError(source.field, head + why)

    def slopes(self, sources: Sequence[Source]) -> SceneError | None:
        """The first of ``sources`` (finite at the start) whose derivative by a variable it is
        written on is not finite there, named with why."""
        wanted = []
        for source in sources:
            for variable in sorted(hy.get_variables(source.expression)):
                slope = self.at_state(hy.diff(source.expression, hy.expression(variable)))
                wanted.append((source, variable, slope))
        values = self.values([w[2] for w in wanted])
        for (source, variable, _), value in zip(wanted, values, strict=True):
            if value is None or np.isfinite(value):
                continue
            name = self._name_of(source, variable)
            head = (
                f"its derivative by {name} is {value} at the start (t = {self.t0_text}), and "
                "the equations of motion need it finite"
            )
            if source.text is None or source.symbols is None:
                inputs = ", ".join(self.inputs(source.expression))
                return SceneError(source.field, f"{head}: at these values of {inputs}")
            nodes = trace(source.text, source.symbols, self.model.pars, source.field)
            if len(nodes) > _MAX_TRACE:
                return SceneError(source.field, head)
            exprs = [self.at_state(n.expression) for n in nodes]
            exprs += [self.at_state(hy.diff(n.expression, hy.expression(variable))) for n in nodes]
            got = self.values(exprs)
            if any(v is None for v in got):
                return SceneError(source.field, head)
            vals, slopes = got[: len(nodes)], got[len(nodes) :]
            i = len(nodes) - 1
            while True:
                bad = [
                    j
                    for j in nodes[i].operands
                    if not (np.isfinite(slopes[j]) and np.isfinite(vals[j]))
                ]
                if not bad:
                    break
                i = bad[0]
            culprit = nodes[i]
            told = "; ".join(
                self._is((nodes[j], vals[j])) for j in culprit.operands if nodes[j].kind != "number"
            )
            return SceneError(
                source.field,
                f"{head}: the derivative of {culprit.text} is {slopes[i]}"
                + (f" where {told}" if told else ""),
            )
        return None

    def _name_of(self, source: Source, variable: str) -> str:
        """The name a text calls ``variable`` by (``R33`` for the placeholder ``R33__``)."""
        for name, expr in (source.symbols or {}).items():
            if str(expr) == variable:
                return name
        return variable

    def _why(self, node: Node, operands: list[tuple[Node, Any]], value: Any) -> str:
        """What the operation ``node`` on finite ``operands`` does to be ``value``."""
        prec = self.precision.name
        vals = [v for _, v in operands]
        if node.kind == "/" and vals[1] == 0:
            if operands[1][0].kind == "number":
                return f"{node.text} divides by zero"
            return f"{node.text} divides by zero: {self._is(operands[1])}"
        if node.kind == "**" and vals[0] == 0 and vals[1] < 0:
            return f"{node.text} divides by zero: {self._is(operands[0])}, to a negative power"
        if node.kind == "**" and vals[0] < 0:
            return (
                f"{node.text} raises a negative number to a non-integer power: "
                f"{self._is(operands[0])}"
            )
        if node.kind == "log" and vals[0] <= 0:
            what = "0" if vals[0] == 0 else "a negative number"
            return f"{node.text} is the logarithm of {what}: {self._is(operands[0])}"
        if node.kind == "sqrt" and vals[0] < 0:
            return f"{node.text} is the square root of a negative number: {self._is(operands[0])}"
        if node.kind in ("asin", "acos") and abs(vals[0]) > 1:
            return f"{node.text} is outside [-1, 1]: {self._is(operands[0])}"
        if not np.isnan(value) and all(np.isfinite(v) for v in vals):
            told = "; ".join(self._is(o) for o in operands if o[0].kind != "number")
            return f"{node.text} overflows {prec}" + (f": {told}" if told else "")
        told = "; ".join(self._is(o) for o in operands)
        return f"{node.text} is {value}" + (f" where {told}" if told else "")

    def _is(self, operand: tuple[Node, Any]) -> str:
        """``text = value`` of an operand, with where its names come from."""
        node, value = operand
        said = f"{node.text} = {_show(value)}"
        if node.kind == "number":
            return said
        if node.kind == "name":
            return said + self._from(node.expression)
        return said + self._names(node)

    def _names(self, node: Node) -> str:
        """`` at NAME = value (field), ...`` of the names ``node`` uses (not t, pi)."""
        names = sorted(node.names - {"t", "pi"})
        if not names:
            return ""
        symbols: dict[str, Expr] = {}
        for name in names:
            expr = self._symbol(name)
            if expr is not None:
                symbols[name] = expr
        values = self.values([self.at_state(e) for e in symbols.values()])
        parts = [
            f"{name} = {_show(v)}{self._from(expr)}"
            for (name, expr), v in zip(symbols.items(), values, strict=True)
            if v is not None
        ]
        return f" at {', '.join(parts)}" if parts else ""

    def _symbol(self, name: str) -> Expr | None:
        for source in self.model.pars.sources:
            if source.symbols is not None and name in source.symbols:
                return source.symbols[name]
        return None

    def _from(self, expr: Expr) -> str:
        """`` (fields)``: the scene fields ``expr``'s value comes from."""
        if str(expr) in self.names:  # a state variable: its own entry (initial.eta[0])
            return f" ({self.model.initial_field(str(expr))})"
        fields = self.inputs(expr)
        return f" ({', '.join(fields)})" if fields else ""

    def inputs(self, expr: Expr) -> list[str]:
        """The scene fields of the state variables and parameters ``expr`` depends on, each
        field once (``body.inertia`` for ``body.inertia[0]`` … ``[2]``)."""
        expr = self.at_state(expr) or expr
        pars = self.model.pars
        fields = [
            pars.fields[i] or f"parameters.{pars.names[i]}"
            for i in sorted(int(str(p)[1:]) for p in hy.get_params(expr))
        ]
        fields += [self.model.initial_field(v) for v in sorted(hy.get_variables(expr))]
        if _TIME.search(str(expr)):
            fields.append("output.times")
        return _collapse(fields)

    def derived(
        self, field: str | None, expr: Expr, value: Any, what: str, otherwise: str = ""
    ) -> SceneError:
        """The refusal of ``expr`` (of finite inputs), ``value`` at the start: an overflow of
        the precision or a singularity, named by its inputs' fields."""
        inputs = self.inputs(expr)
        named = field or ", ".join(inputs) or otherwise or "initial"
        wide = self.values([self.at_state(expr)], wide=True)[0]
        head = f"{what} {value} at the start (t = {self.t0_text})"
        if wide is not None and np.isfinite(wide):
            prec = self.precision.name
            return SceneError(
                named,
                f"{head} in {prec} ({_show(wide)} computed with a wider exponent range): "
                f"these numbers overflow {prec} there; scale the units (or choose a wider "
                "precision)",
            )
        where = f" of {', '.join(inputs)}" if field is not None and inputs else ""
        if wide is None:  # not evaluated in MPFR: overflow or singularity cannot be told
            return SceneError(named, f"{head}, from these values{where}")
        return SceneError(
            named, f"{head}, at any precision: these values{where} are a singularity of it"
        )


class _Deferred:
    """A text that is not finite only because a name it uses is not (reported last)."""

    def __init__(self, error: SceneError) -> None:
        self.error = error


def _collapse(fields: Iterable[str]) -> list[str]:
    """Each field once, in order, without its index (``a[0], a[1]`` → ``a``); a field listing
    several (``"a, b"``) counts as each."""
    out: list[str] = []
    for text in fields:
        for one in text.split(", "):
            base = re.sub(r"\[\d+\]$", "", one)
            if base not in out:
                out.append(base)
    return out


def _show(value: Any) -> str:
    """``value`` (of any precision) to 6 significant digits."""
    with mpmath.workdps(20):
        return mpmath.nstr(mpmath.mpf(str(value)), 6)
