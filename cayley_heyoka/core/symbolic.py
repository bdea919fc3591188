"""Exact symbolic algebra for equations formed from a scene's text: normal forms, derivatives
with shared subexpressions, and heyoka expressions built from them.

heyoka's differentiation (``heyoka.diff``, ``heyoka.hamiltonian``) follows the chain rule
node by node and keeps what it produces: ∂/∂x of ``c/sqrt(r²)`` is
``(−c · −(√r²)⁻² · (0.5/√r²)) · (2 · (x − y))``, so a Newtonian N-body H gives a system
two thirds larger than the hand-written one (``heyoka.model.nbody``). Here an expression is
kept in a normal form as it is built:

* a sum is a linear combination of terms with exact rational coefficients, its content (the
  rational gcd of the coefficients, with the sign of the first term) taken out, so that
  ``2x − 2y`` is ``2·(x − y)`` and shares ``x − y`` with every other multiple of it;
* a product is a coefficient times powers of bases with exact rational exponents
  (``sqrt(u)`` is ``u^(1/2)``, ``a/b`` is ``a·b⁻¹``), equal bases merged, so that
  ∂/∂x of ``c·(r²)^(−1/2)`` is ``−c·(r²)^(−3/2)·(x − y)`` — the same product, up to its
  coefficient, for both bodies of the pair and all three components but the last factor;
* equal expressions are one object (interned), so the heyoka expression built from a node
  is built once and every use of it is the same expression: heyoka's decomposition then
  computes it once.

Every coefficient and exponent is a :class:`fractions.Fraction` until heyoka's expressions are
built, where each becomes one number node in the run's precision
(:meth:`~cayley_heyoka.core.precision.Precision.constant`: exact, or rounded once). A power's
exponent is merged with another only where both sides are equal wherever the original is
defined: ``(u^k)^e = u^(ke)`` for an integer e, or when k is not an integer (then u ≥ 0).

:class:`Algebra` builds nodes (the operations of :mod:`.expressions`' grammar: it parses a text
into it with :func:`.expressions.rebuild`), :meth:`Algebra.diff` differentiates them, and
:meth:`Algebra.emit` turns them into heyoka expressions.
"""

from __future__ import annotations

import functools
import math
import operator
from collections.abc import Callable, Iterable, Sequence
from fractions import Fraction
from typing import Any, TypeAlias

import heyoka as hy

Expr: TypeAlias = hy.expression

#: The largest integer power of an exact constant folded (beyond it the power stays a node,
#: as heyoka would evaluate it).
_MAX_FOLDED_BITS = 4096


class Node:
    """An interned expression: one object for each distinct expression of an :class:`Algebra`.

    Attributes
    ----------
    kind
        ``"const"``, ``"leaf"``, ``"sum"``, ``"product"``, ``"scaled"`` or ``"func"``.
    ident
        Creation order within the algebra: the canonical order of terms and factors.
    free
        The leaves (by ``ident``) the expression depends on.
    weight
        Nodes of the expression written as a tree: heavier factors of a product come first, so
        that products sharing them share their first partial products.
    """

    __slots__ = ("args", "free", "ident", "kind", "value", "weight")

    def __init__(
        self,
        kind: str,
        ident: int,
        value: Any,
        args: tuple[Any, ...],
        free: frozenset[int],
        weight: int,
    ) -> None:
        self.kind = kind
        self.ident = ident
        #: const: its Fraction; leaf: its heyoka expression; scaled: the coefficient; sum: the
        #: constant term; func: the function's name; product: None.
        self.value = value
        #: sum: ((term, integer coefficient), …); product: ((base, exponent), …); scaled:
        #: (core,); func: its arguments.
        self.args = args
        self.free = free
        self.weight = weight

    def __repr__(self) -> str:
        return f"Node({self.kind}#{self.ident})"


class Unsupported(ValueError):
    """An operation this algebra does not represent exactly (the caller falls back to heyoka's
    own differentiation)."""


Terms = dict[Node, Fraction]


class Algebra:
    """Builds, differentiates and emits :class:`Node` expressions.

    Parameters
    ----------
    constant
        Builds a heyoka number node of a Fraction in the run's precision
        (:meth:`.model.ParTable.constant`).
    functions
        The functions of the grammar by name (:data:`.expressions.FUNCTIONS`).
    """

    def __init__(
        self, constant: Callable[[Fraction], Expr], functions: dict[str, Callable[..., Expr]]
    ) -> None:
        self._constant = constant
        self._functions = functions
        self._interned: dict[tuple[Any, ...], Node] = {}
        self._derivatives: dict[tuple[int, int], Node] = {}
        self._emitted: dict[tuple[int, Fraction], Expr] = {}
        #: heyoka operations built by :meth:`emit` so far, each once however often it is used.
        self.operations = 0
        self.zero = self.const(Fraction(0))
        self.one = self.const(Fraction(1))

    # ------------------------------------------------------------------ interning
    def _intern(
        self, key: tuple[Any, ...], kind: str, value: Any, args: tuple[Any, ...], children: Any
    ) -> Node:
        node = self._interned.get(key)
        if node is None:
            kids = list(children)
            free = frozenset().union(*(c.free for c in kids)) if kids else frozenset()
            weight = 1 + sum(c.weight for c in kids)
            node = Node(kind, len(self._interned), value, args, free, weight)
            if kind == "leaf":
                node.free = frozenset((node.ident,))
            self._interned[key] = node
        return node

    def const(self, value: Fraction) -> Node:
        """The exact number ``value``."""
        value = Fraction(value)
        return self._intern(("const", value), "const", value, (), ())

    def leaf(self, expr: Expr) -> Node:
        """A heyoka variable, parameter, ``t`` or ``pi``, kept as it is."""
        return self._intern(("leaf", expr), "leaf", expr, (), ())

    def integer(self, value: int) -> Node:
        return self.const(Fraction(value))

    def _scaled(self, c: Fraction, core: Node | None) -> Node:
        if core is None or c == 0:
            return self.const(c if core is None else Fraction(0))
        if c == 1:
            return core
        return self._intern(("scaled", c, core.ident), "scaled", c, (core,), (core,))

    @staticmethod
    def _split(node: Node) -> tuple[Fraction, Node | None]:
        """(coefficient, the rest): the rest None for a constant."""
        if node.kind == "const":
            return node.value, None
        if node.kind == "scaled":
            return node.value, node.args[0]
        return Fraction(1), node

    # ------------------------------------------------------------------ sums
    def _terms(self, node: Node, scale: Fraction, terms: Terms) -> Fraction:
        """Add ``scale·node`` to ``terms``; returns its constant part."""
        c, core = self._split(node)
        c *= scale
        if core is None:
            return c
        if core.kind == "sum":
            for term, k in core.args:
                terms[term] = terms.get(term, Fraction(0)) + c * k
            return c * core.value
        terms[core] = terms.get(core, Fraction(0)) + c
        return Fraction(0)

    def linear(self, parts: Iterable[tuple[Fraction, Node]]) -> Node:
        """Σ cᵢ·nodeᵢ, in normal form."""
        terms: Terms = {}
        constant = Fraction(0)
        for c, node in parts:
            if c != 0:
                constant += self._terms(node, Fraction(c), terms)
        return self._sum(terms, constant)

    def _sum(self, terms: Terms, constant: Fraction) -> Node:
        items = sorted(((t, k) for t, k in terms.items() if k != 0), key=lambda p: p[0].ident)
        if not items:
            return self.const(constant)
        if len(items) == 1 and constant == 0:
            return self._scaled(items[0][1], items[0][0])
        # The content: integer coefficients with gcd 1, the first one positive.
        numbers = [k for _, k in items] + ([constant] if constant else [])
        numerator = math.gcd(*(k.numerator for k in numbers))
        denominator = math.lcm(*(k.denominator for k in numbers))
        content = Fraction(numerator, denominator) * (1 if items[0][1] > 0 else -1)
        args = tuple((t, k / content) for t, k in items)
        rest = constant / content
        key = ("sum", rest, tuple((t.ident, k) for t, k in args))
        core = self._intern(key, "sum", rest, args, (t for t, _ in args))
        return self._scaled(content, core)

    def add(self, a: Node, b: Node) -> Node:
        return self.linear(((Fraction(1), a), (Fraction(1), b)))

    def sub(self, a: Node, b: Node) -> Node:
        return self.linear(((Fraction(1), a), (Fraction(-1), b)))

    def neg(self, a: Node) -> Node:
        return self.linear(((Fraction(-1), a),))

    # ------------------------------------------------------------------ products
    @staticmethod
    def _factors(core: Node | None, exponent: Fraction, into: dict[Node, Fraction]) -> None:
        if core is None:
            return
        pairs = core.args if core.kind == "product" else ((core, Fraction(1)),)
        for base, k in pairs:
            into[base] = into.get(base, Fraction(0)) + k * exponent

    def _product(self, c: Fraction, factors: dict[Node, Fraction]) -> Node:
        kept = []
        for base, k in factors.items():
            if k == 0:
                continue
            if base.kind == "const" and k.denominator == 1:
                c *= _power(base.value, int(k))
                continue
            kept.append((base, k))
        if c == 0:
            return self.zero
        kept.sort(key=lambda p: p[0].ident)
        if not kept:
            return self.const(c)
        if len(kept) == 1 and kept[0][1] == 1:
            return self._scaled(c, kept[0][0])
        key = ("product", tuple((b.ident, k) for b, k in kept))
        core = self._intern(key, "product", None, tuple(kept), (b for b, _ in kept))
        return self._scaled(c, core)

    def mul(self, a: Node, b: Node) -> Node:
        ca, core_a = self._split(a)
        cb, core_b = self._split(b)
        factors: dict[Node, Fraction] = {}
        self._factors(core_a, Fraction(1), factors)
        self._factors(core_b, Fraction(1), factors)
        return self._product(ca * cb, factors)

    def div(self, a: Node, b: Node) -> Node:
        return self.mul(a, self.pow_rational(b, Fraction(-1)))

    def pow(self, a: Node, b: Node) -> Node:
        if b.kind == "const":
            return self.pow_rational(a, b.value)
        return self.func("pow", (a, b))

    def pow_rational(self, a: Node, e: Fraction) -> Node:
        """``a`` to the exact power ``e``."""
        if e == 0:
            return self.one
        if e == 1:
            return a
        c, core = self._split(a)
        factors: dict[Node, Fraction] = {}
        if e.denominator == 1:
            if c == 0 and e < 0:
                raise Unsupported("a negative power of an exact zero")
            self._factors(core, e, factors)
            return self._product(_power(c, int(e)), factors)
        # A fractional power: merged into the bases' exponents only where both sides agree
        # wherever the original is defined (a base under a fractional power is ≥ 0).
        if core is None:
            exact = _root(c, e) if c > 0 else None
            return self.const(exact) if exact is not None else self._product(Fraction(1), {a: e})
        if c < 0:
            return self._product(Fraction(1), {a: e})
        coefficient = Fraction(1)
        if c != 1:
            exact = _root(c, e)
            if exact is None:
                factors[self.const(c)] = e
            else:
                coefficient = exact
        if core.kind == "product" and all(k.denominator != 1 for _, k in core.args):
            self._factors(core, e, factors)
        else:
            factors[core] = e
        return self._product(coefficient, factors)

    # ------------------------------------------------------------------ functions
    def func(self, name: str, args: Sequence[Node]) -> Node:
        if name == "sqrt":
            return self.pow_rational(args[0], Fraction(1, 2))
        key = ("func", name, tuple(a.ident for a in args))
        return self._intern(key, "func", name, tuple(args), args)

    def call(self, name: str, args: Sequence[Node]) -> Node:
        return self.func(name, args)

    def binary(self, symbol: str, a: Node, b: Node) -> Node:
        op = {"+": self.add, "-": self.sub, "*": self.mul, "/": self.div, "**": self.pow}[symbol]
        return op(a, b)

    # ------------------------------------------------------------------ derivatives
    def diff(self, node: Node, variable: Node) -> Node:
        """∂node/∂variable (a leaf), in normal form."""
        if variable.ident not in node.free:
            return self.zero
        key = (node.ident, variable.ident)
        done = self._derivatives.get(key)
        if done is None:
            done = self._diff(node, variable)
            self._derivatives[key] = done
        return done

    def _diff(self, node: Node, v: Node) -> Node:
        if node.kind == "leaf":
            return self.one
        if node.kind == "scaled":
            return self.mul(self.const(node.value), self.diff(node.args[0], v))
        if node.kind == "sum":
            return self.linear((k, self.diff(t, v)) for t, k in node.args)
        if node.kind == "product":
            parts = []
            for i, (base, k) in enumerate(node.args):
                if v.ident not in base.free:
                    continue
                others = {b: e for j, (b, e) in enumerate(node.args) if j != i}
                others[base] = k - 1
                partial = self._product(k, others)
                parts.append((Fraction(1), self.mul(partial, self.diff(base, v))))
            return self.linear(parts)
        parts = []
        for i, arg in enumerate(node.args):
            if v.ident in arg.free:
                parts.append((Fraction(1), self.mul(self._partial(node, i), self.diff(arg, v))))
        return self.linear(parts)

    def _partial(self, node: Node, i: int) -> Node:
        """∂f/∂(its i-th argument) of a function node."""
        name, args = node.value, node.args
        u = args[0]
        half = Fraction(1, 2)

        def square(x: Node) -> Node:
            return self.pow_rational(x, Fraction(2))

        def one_minus_u2() -> Node:
            return self.sub(self.one, square(u))

        rules: dict[str, Callable[[], Node]] = {
            "sin": lambda: self.func("cos", (u,)),
            "cos": lambda: self.neg(self.func("sin", (u,))),
            "tan": lambda: self.add(self.one, square(node)),
            "asin": lambda: self.pow_rational(one_minus_u2(), -half),
            "acos": lambda: self.neg(self.pow_rational(one_minus_u2(), -half)),
            "atan": lambda: self.pow_rational(self.add(self.one, square(u)), Fraction(-1)),
            "sinh": lambda: self.func("cosh", (u,)),
            "cosh": lambda: self.func("sinh", (u,)),
            "tanh": lambda: self.sub(self.one, square(node)),
            "exp": lambda: node,
            "log": lambda: self.pow_rational(u, Fraction(-1)),
            "erf": lambda: self.mul(
                self.mul(self.const(Fraction(2)), self.pow_rational(self.leaf(hy.pi), -half)),
                self.func("exp", (self.neg(square(u)),)),
            ),
        }
        if name in rules:
            return rules[name]()
        if name == "atan2":
            y, x = args
            inverse = self.pow_rational(self.add(square(x), square(y)), Fraction(-1))
            return self.mul(x if i == 0 else self.neg(y), inverse)
        if name == "pow":
            base, exponent = args
            if i == 0:
                return self.mul(exponent, self.func("pow", (base, self.sub(exponent, self.one))))
            return self.mul(node, self.func("log", (base,)))
        raise Unsupported(f"no derivative of {name}")

    # ------------------------------------------------------------------ heyoka expressions
    def emit(self, node: Node) -> Expr:
        """The heyoka expression of ``node``: one object for each node, however often used."""
        return self._emit_term(Fraction(1), node)

    def _op(self, key: tuple[Any, ...], build: Callable[[], Expr], count: int = 1) -> Expr:
        """The expression ``build`` makes, built once per ``key``; ``count`` heyoka operations
        the first time (what :attr:`operations` counts)."""
        done = self._emitted.get(key)
        if done is None:
            done = build()
            self._emitted[key] = done
            self.operations += count
        return done

    def _emit_term(self, c: Fraction, node: Node) -> Expr:
        """c·node as a heyoka expression."""
        if node.kind == "scaled":
            return self._emit_term(c * node.value, node.args[0])
        if node.kind == "const":
            return self._constant(c * node.value)
        if node.kind == "sum":
            return self._emit_sum(c, node)
        if c < 0:
            return self._op(("neg", node.ident, c), lambda: -self._emit_term(-c, node))
        if node.kind == "product":
            return self._emit_product(c, node)
        if node.kind == "leaf":
            core = node.value
        else:
            core = self._op(("core", node.ident), lambda: self._emit_core(node))
        if c == 1:
            return core
        return self._op(("term", node.ident, c), lambda: self._constant(c) * core)

    def _emit_core(self, node: Node) -> Expr:
        args = [self.emit(a) for a in node.args]
        if node.value == "pow":
            return args[0] ** args[1]
        return self._functions[node.value](*args)

    def _emit_sum(self, c: Fraction, node: Node) -> Expr:
        def build() -> Expr:
            plus: list[Expr] = []
            minus: list[Expr] = []
            squares = 0
            for term, k in node.args:
                if c * k == 1 and _is_square(term):
                    # heyoka computes a sum of squares as one operation: counted once below.
                    plus.append(self.emit(term.args[0][0]) ** self._constant(Fraction(2)))
                    squares += 1
                else:
                    (plus if c * k > 0 else minus).append(self._emit_term(abs(c * k), term))
            rest = c * node.value
            if rest:
                (plus if rest > 0 else minus).append(self._constant(abs(rest)))
            self.operations += (len(plus) > 1) + (len(minus) > 1) + (len(minus) > 0)
            if not (squares == len(plus) > 1 and not minus):
                self.operations += squares
            if not minus:
                return hy.sum(plus)
            if not plus:
                return -hy.sum(minus)
            return hy.sum(plus) - hy.sum(minus)

        return self._op(("sum", node.ident, c), build, count=0)

    def _emit_product(self, c: Fraction, node: Node) -> Expr:
        # Heavier factors first, the coefficient on the first: products that share their
        # heaviest factors and coefficient (a pair's c·(r²)^(−3/2)) share their first
        # partial products, built once.
        numerator: list[tuple[Node, Fraction]] = []
        denominator: list[tuple[Node, Fraction]] = []
        for base, k in sorted(node.args, key=lambda p: (-p[0].weight, p[0].ident)):
            if k < 0 and k.denominator == 1:
                denominator.append((base, -k))
            else:
                numerator.append((base, k))
        key: tuple[Any, ...] = ("product", c)
        if not numerator:
            out = self._constant(c)
        else:
            out = self._emit_power(*numerator[0])
            key += (numerator[0],)
            if c != 1:
                out = self._op(key, functools.partial(operator.mul, self._constant(c), out))
            key, out = self._chain(key, out, numerator[1:])
        if denominator:
            low, below = self._chain(
                ("below", denominator[0]), self._emit_power(*denominator[0]), denominator[1:]
            )
            out = self._op(key + low, functools.partial(operator.truediv, out, below))
        return out

    def _chain(
        self, key: tuple[Any, ...], first: Expr, factors: Sequence[tuple[Node, Fraction]]
    ) -> tuple[tuple[Any, ...], Expr]:
        """first · f₁ · f₂ ⋯, each partial product built once: keyed by ``key`` (which names
        ``first``) and the factors so far; returns the whole product's key and expression."""
        out = first
        for factor in factors:
            key += (factor,)
            out = self._op(key, functools.partial(operator.mul, out, self._emit_power(*factor)))
        return key, out

    def _emit_power(self, base: Node, k: Fraction) -> Expr:
        if k == 1:
            return self.emit(base)
        return self._op(("power", base.ident, k), lambda: self.emit(base) ** self._constant(k))


def _is_square(node: Node) -> bool:
    return node.kind == "product" and len(node.args) == 1 and node.args[0][1] == 2


def _power(c: Fraction, n: int) -> Fraction:
    """cⁿ exactly, refused beyond :data:`_MAX_FOLDED_BITS` bits."""
    if c == 0:
        if n < 0:
            raise Unsupported("a negative power of an exact zero")
        return Fraction(0)
    bits = max(abs(c.numerator).bit_length(), c.denominator.bit_length()) * abs(n)
    if bits > _MAX_FOLDED_BITS:
        raise Unsupported("an exact power too large to fold")
    return c**n


def _root(c: Fraction, e: Fraction) -> Fraction | None:
    """c^e exactly when it is rational (c > 0), else None."""
    q = e.denominator
    roots = []
    for n in (c.numerator, c.denominator):
        r = round(n ** (1 / q)) if n.bit_length() < 1000 else None
        if r is None:
            return None
        for guess in (r - 1, r, r + 1):
            if guess >= 0 and guess**q == n:
                roots.append(guess)
                break
        else:
            return None
    return _power(Fraction(roots[0], roots[1]), e.numerator)
