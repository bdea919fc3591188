"""Expressions written as text in a scene (force functions, user events), turned into heyoka.

The grammar is Python's arithmetic: numbers, names, ``+ - * / **``, parentheses and the
functions in :data:`FUNCTIONS`. Nothing is evaluated by Python: the text is parsed to a syntax
tree and only these nodes are accepted. ``lambda`` may be used as a name (it is the memoir's
symbol), although it is a Python keyword.

Integer literals become exact constants; other literals become runtime parameters holding the
literal's decimal text, so ``0.1`` is ``0.1`` in the run's precision, not the nearest double.
"""

from __future__ import annotations

import ast
import io
import tokenize
from collections.abc import Mapping

import heyoka as hy

from .errors import SceneError
from .model import ParTable

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
_EXACT_INT_LIMIT = 2**53


def parse_expression(
    text: str, symbols: Mapping[str, hy.expression], pars: ParTable, field: str
) -> hy.expression:
    """Parse ``text`` into a heyoka expression over ``symbols`` (plus ``t`` and ``pi``).

    Parameters
    ----------
    text
        The expression, e.g. ``"-0.3 * R33 + 0.01 * sin(t)"``.
    symbols
        The names it may use and the expressions they stand for.
    pars
        Where non-integer literals are allocated as runtime parameters.
    field
        The scene field, for error messages.
    """
    if not isinstance(text, str) or not text.strip():
        raise SceneError(field, f"must be a non-empty expression string, got {text!r}")
    source = _rename_keywords(text, field)
    try:
        tree = ast.parse(source.strip(), mode="eval")
    except SyntaxError as exc:
        raise SceneError(field, f"not a valid expression ({exc.msg}): {text!r}") from None
    table = {_KEYWORD_NAMES.get(k, k): v for k, v in symbols.items()}
    table.setdefault("t", hy.time)
    table.setdefault("pi", hy.pi)
    counter = [0]

    def build(node: ast.AST) -> hy.expression:
        if isinstance(node, ast.Expression):
            return build(node.body)
        if isinstance(node, ast.BinOp):
            a, b = build(node.left), build(node.right)
            ops = {
                ast.Add: lambda: a + b,
                ast.Sub: lambda: a - b,
                ast.Mult: lambda: a * b,
                ast.Div: lambda: a / b,
                ast.Pow: lambda: a**b,
            }
            if type(node.op) not in ops:
                raise SceneError(field, f"operator {type(node.op).__name__} is not allowed")
            return ops[type(node.op)]()
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
            v = build(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.Name):
            if node.id not in table:
                known = ", ".join(sorted(k.replace("lambda_", "lambda") for k in table))
                raise SceneError(field, f"unknown name {node.id!r}; known names: {known}")
            return table[node.id]
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            if isinstance(node.value, bool):
                raise SceneError(field, "booleans are not numbers here")
            if isinstance(node.value, int) and abs(node.value) < _EXACT_INT_LIMIT:
                return hy.expression(float(node.value))
            literal = ast.get_source_segment(source.strip(), node) or repr(node.value)
            counter[0] += 1
            return pars.add(f"{field}#{counter[0]}", literal)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            fn = FUNCTIONS.get(node.func.id)
            if fn is None or node.keywords:
                known = ", ".join(sorted(FUNCTIONS))
                raise SceneError(field, f"unknown function {node.func.id!r}; known: {known}")
            return fn(*[build(a) for a in node.args])
        raise SceneError(field, f"unsupported syntax {ast.dump(node)[:60]!r} in {text!r}")

    return build(tree)


def names_used(text: str) -> set[str]:
    """The names an expression text refers to (``lambda`` reported as ``lambda``)."""
    tree = ast.parse(_rename_keywords(text, "expression").strip(), mode="eval")
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


def _rename_keywords(text: str, field: str) -> str:
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, IndentationError) as exc:
        raise SceneError(field, f"not a valid expression ({exc}): {text!r}") from None
    out = [
        (tok.type, _KEYWORD_NAMES.get(tok.string, tok.string))
        if tok.type == tokenize.NAME
        else (tok.type, tok.string)
        for tok in tokens
    ]
    return tokenize.untokenize(out)
