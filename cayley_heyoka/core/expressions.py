"""Expressions written as text in a scene (force functions, user events), turned into heyoka.

The grammar is Python's arithmetic: numbers, names, ``+ - * / **``, parentheses and the
functions in :data:`FUNCTIONS`. Nothing is evaluated by Python: the text is parsed to a syntax
tree and only these nodes are accepted. ``lambda`` may be used as a name (it is the memoir's
symbol), although it is a Python keyword.

Integer literals become exact constants in the run's floating type (so ``3/5`` is folded to
the quad 0.6 in a quad run, not to the double 0.6); other literals become runtime parameters
holding the literal's decimal text, so ``0.1`` is ``0.1`` in the run's precision, not the
nearest double.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import heyoka as hy

from .errors import SceneError
from .model import ParTable
from .precision import exact_fraction

FUNCTIONS = {
    "sin": hy.sin,
    "cos": hy.cos,
    "tan": hy.tan,
    "asin": hy.asin,
    "acos": hy.acos,
    "atan": hy.atan,
    "atan2": hy.atan2,
    "sinh": hy.sinh,
    "cosh": hy.cosh,
    "tanh": hy.tanh,
    "exp": hy.exp,
    "log": hy.log,
    "sqrt": hy.sqrt,
    "erf": hy.erf,
}

_KEYWORD_NAMES = {"lambda": "lambda_"}
_KEYWORD_NAMES_BACK = {v: k for k, v in _KEYWORD_NAMES.items()}
_EXACT_INT_LIMIT = 2**53

#: Limits of an expression text (docs/scenes.md, "Limits"), checked on its tokens before
#: Python's parser runs: a chain of ~3000 operators overflows its recursion during AST
#: construction (``x**x**...`` exhausts memory), and nothing physical needs that many.
MAX_EXPRESSION_CHARS = 100_000
MAX_EXPRESSION_OPERATORS = 2_000
#: Nesting of parentheses, calls, powers and unary signs (a sum or product of many terms is
#: one level): deeper trees would exhaust the recursion that builds and compiles them.
MAX_EXPRESSION_DEPTH = 100


def parse_expression(
    text: str, symbols: Mapping[str, hy.expression], pars: ParTable, field: str
) -> hy.expression:
    """Parse ``text`` into a heyoka expression over ``symbols`` (plus ``t`` and ``pi``).

    The expression is recorded in ``pars`` as the scene's ``field`` (:meth:`ParTable.source`),
    so that a run that cannot start can name it and say why (:func:`trace`).

    Parameters
    ----------
    text
        The expression, e.g. ``"-0.3 * R33 + 0.01 * sin(t)"``.
    symbols
        The names it may use and the expressions they stand for.
    pars
        Where non-integer literals are allocated as runtime parameters; integer literals are
        built in its precision.
    field
        The scene field, for error messages.
    """
    counter = [0]

    def literal(digits: str) -> hy.expression:
        counter[0] += 1
        return pars.add(f"{field}#{counter[0]}", digits)

    expr = _build(text, symbols, pars, field, literal, None)
    pars.source(field, expr, text, symbols)
    return expr


class Algebra(Protocol):
    """What a text is built into: heyoka expressions (:func:`parse_expression`), or another
    representation of the same operations (:func:`rebuild`, e.g. :mod:`.symbolic`)."""

    def leaf(self, expr: hy.expression) -> Any: ...
    def integer(self, value: int) -> Any: ...
    def binary(self, symbol: str, a: Any, b: Any) -> Any: ...
    def neg(self, a: Any) -> Any: ...
    def call(self, name: str, args: Sequence[Any]) -> Any: ...


class _Heyoka:
    """The grammar's operations on heyoka expressions."""

    def __init__(self, pars: ParTable) -> None:
        self.pars = pars

    def leaf(self, expr: hy.expression) -> hy.expression:
        return expr

    def integer(self, value: int) -> hy.expression:
        # In the run's type: heyoka folds 3/5 in the type of its operands.
        return self.pars.constant(value)

    def binary(self, symbol: str, a: hy.expression, b: hy.expression) -> hy.expression:
        return _OPERATORS[symbol](a, b)

    def neg(self, a: hy.expression) -> hy.expression:
        return -a

    def call(self, name: str, args: Sequence[hy.expression]) -> hy.expression:
        return FUNCTIONS[name](*args)


def rebuild(
    text: str, symbols: Mapping[str, hy.expression], pars: ParTable, field: str, algebra: Algebra
) -> Any:
    """``text``, which :func:`parse_expression` parsed into ``pars`` as ``field``, built again
    into ``algebra``: its literals are the parameters that parse allocated."""
    counter = [0]

    def literal(digits: str) -> hy.expression:
        counter[0] += 1
        return hy.par[pars.index(f"{field}#{counter[0]}")]

    return _build(text, symbols, pars, field, literal, None, algebra)


@dataclass(frozen=True)
class Node:
    """One operation, name or number of a parsed text (:func:`trace`)."""

    #: The node's own text, as Python writes it back (``1 / (R33 - R33)``).
    text: str
    #: ``"+"``, ``"-"``, ``"*"``, ``"/"``, ``"**"``, ``"neg"``, a function's name, ``"name"``
    #: or ``"number"``.
    kind: str
    expression: hy.expression
    #: Positions of the operands in the trace (before this node).
    operands: tuple[int, ...]
    #: The names the node's text uses.
    names: frozenset[str]


def trace(
    text: str, symbols: Mapping[str, hy.expression], pars: ParTable, field: str
) -> list[Node]:
    """Every node of the expression that :func:`parse_expression` built from ``text`` into
    ``pars``, operands before the operations on them: its literals are the parameters it
    allocated there."""
    counter = [0]

    def literal(digits: str) -> hy.expression:
        counter[0] += 1
        return hy.par[pars.index(f"{field}#{counter[0]}")]

    nodes: list[Node] = []
    _build(text, symbols, pars, field, literal, nodes)
    return nodes


def _build(
    text: str,
    symbols: Mapping[str, hy.expression],
    pars: ParTable,
    field: str,
    literal: Callable[[str], hy.expression],
    nodes: list[Node] | None,
    algebra: Algebra | None = None,
) -> Any:
    if not isinstance(text, str) or not text.strip():
        raise SceneError(field, f"must be a non-empty expression string, got {text!r}")
    source = _rename_keywords(text, field)
    tree = _parse(source, text, field)
    table = {_KEYWORD_NAMES.get(k, k): v for k, v in symbols.items()}
    table.setdefault("t", hy.time)
    table.setdefault("pi", hy.pi)
    ops: Algebra = algebra if algebra is not None else _Heyoka(pars)
    # Nodes (when traced) as positions in ``nodes``, beside their values.
    Built = tuple[Any, int]

    def node(ast_node: ast.AST, kind: str, value: Any, *operands: Built) -> Built:
        if nodes is None:
            return value, -1
        segment = ast.unparse(ast_node)
        inside = list(ast.walk(ast_node))
        functions = {c.func for c in inside if isinstance(c, ast.Call)}
        names = frozenset(
            _KEYWORD_NAMES_BACK.get(n.id, n.id)
            for n in inside
            if isinstance(n, ast.Name) and n not in functions
        )
        for k, v in _KEYWORD_NAMES.items():
            segment = re.sub(rf"\b{v}\b", k, segment)
        nodes.append(Node(segment, kind, value, tuple(o[1] for o in operands), names))
        return value, len(nodes) - 1

    def build(n: ast.AST) -> Built:
        if isinstance(n, ast.Expression):
            return build(n.body)
        if isinstance(n, ast.BinOp):
            # A left-leaning chain (a + b - c + ...) is folded in a loop, left to right as
            # Python would, so that a sum of many terms costs no recursion.
            chain = [n]
            while isinstance(chain[-1].left, ast.BinOp) and type(chain[-1].op) in _CHAINED:
                chain.append(chain[-1].left)
            value = build(chain[-1].left)
            for link in reversed(chain):
                right = build(link.right)
                result = ops.binary(_symbol(link.op, field), value[0], right[0])
                value = node(link, _SYMBOLS[type(link.op)], result, value, right)
            return value
        if isinstance(n, ast.UnaryOp) and isinstance(n.op, ast.USub | ast.UAdd):
            v = build(n.operand)
            return node(n, "neg", ops.neg(v[0]), v) if isinstance(n.op, ast.USub) else v
        if isinstance(n, ast.Name):
            if n.id not in table:
                known = ", ".join(sorted(k.replace("lambda_", "lambda") for k in table))
                raise SceneError(field, f"unknown name {n.id!r}; known names: {known}")
            return node(n, "name", ops.leaf(table[n.id]))
        if isinstance(n, ast.Constant) and isinstance(n.value, int | float):
            if isinstance(n.value, bool):
                raise SceneError(field, "booleans are not numbers here")
            if isinstance(n.value, int) and abs(n.value) < _EXACT_INT_LIMIT:
                return node(n, "number", ops.integer(n.value))
            text_of = ast.get_source_segment(source.strip(), n) or repr(n.value)
            try:
                exact_fraction(text_of)
            except ValueError as exc:
                raise SceneError(field, f"literal {exc}") from None
            return node(n, "number", ops.leaf(literal(text_of)))
        if isinstance(n, ast.Call) and isinstance(n.func, ast.Name):
            fn = FUNCTIONS.get(n.func.id)
            if fn is None or n.keywords:
                known = ", ".join(sorted(FUNCTIONS))
                raise SceneError(field, f"unknown function {n.func.id!r}; known: {known}")
            args = [build(a) for a in n.args]
            return node(n, n.func.id, ops.call(n.func.id, [a[0] for a in args]), *args)
        raise SceneError(field, f"unsupported syntax {ast.dump(n)[:60]!r} in {text!r}")

    return build(tree)[0]


def names_used(text: str, field: str = "expression") -> set[str]:
    """The names an expression text refers to (``lambda`` reported as ``lambda``)."""
    tree = _parse(_rename_keywords(text, field), text, field)
    inv = {v: k for k, v in _KEYWORD_NAMES.items()}
    return {inv.get(n.id, n.id) for n in ast.walk(tree) if isinstance(n, ast.Name)}


def uses_time(text: object) -> bool:
    """Whether an expression text names ``t``; a malformed one is reported later, when it is
    parsed with its field's name, so here it counts as not using it."""
    if not isinstance(text, str):
        return False
    try:
        return "t" in names_used(text)
    except (SyntaxError, SceneError):
        return False


_CHAINED = (ast.Add, ast.Sub, ast.Mult, ast.Div)
_SYMBOLS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_OPERATORS: dict[str, Callable[[Any, Any], Any]] = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": lambda a, b: a / b,
    "**": lambda a, b: a**b,
}


def _symbol(op: ast.operator, field: str) -> str:
    if type(op) not in _SYMBOLS:
        hint = " (a power is written **, as in Python)" if isinstance(op, ast.BitXor) else ""
        raise SceneError(
            field, f"operator {type(op).__name__} is not allowed; use + - * / **{hint}"
        )
    return _SYMBOLS[type(op)]


def _parse(source: str, text: str, field: str) -> ast.Expression:
    """Python's syntax tree of ``source`` (``text`` renamed), within the limits above."""
    try:
        tree = ast.parse(source.strip(), mode="eval")
    except SyntaxError as exc:
        raise SceneError(field, f"not a valid expression ({exc.msg}): {_short(text)}") from None
    depth = 0
    stack: list[tuple[ast.AST, int]] = [(tree.body, 1)]
    while stack:
        node, level = stack.pop()
        while isinstance(node, ast.BinOp) and isinstance(node.op, _CHAINED):
            stack.append((node.right, level + 1))
            node = node.left
        depth = max(depth, level)
        if depth > MAX_EXPRESSION_DEPTH:
            raise SceneError(
                field,
                f"nested deeper than {MAX_EXPRESSION_DEPTH} levels (parentheses, calls, powers, "
                f"signs): {_short(text)}",
            )
        stack += [(child, level + 1) for child in ast.iter_child_nodes(node)]
    return tree


def _short(text: str) -> str:
    return repr(text) if len(text) <= 200 else f"{text[:120]!r}... ({len(text)} characters)"


def _rename_keywords(text: str, field: str) -> str:
    if len(text) > MAX_EXPRESSION_CHARS:
        raise SceneError(
            field, f"longer than {MAX_EXPRESSION_CHARS} characters ({len(text)}): {_short(text)}"
        )
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, IndentationError, SyntaxError) as exc:
        raise SceneError(field, f"not a valid expression ({exc}): {_short(text)}") from None
    operators = sum(tok.type == tokenize.OP and tok.string not in "()," for tok in tokens)
    if operators > MAX_EXPRESSION_OPERATORS:
        raise SceneError(
            field,
            f"has {operators} operators, more than {MAX_EXPRESSION_OPERATORS}: {_short(text)}",
        )
    out = [
        (tok.type, _KEYWORD_NAMES.get(tok.string, tok.string))
        if tok.type == tokenize.NAME
        else (tok.type, tok.string)
        for tok in tokens
    ]
    return tokenize.untokenize(out)
