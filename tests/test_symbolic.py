"""The exact symbolic algebra that forms equations from a scene's text (core/symbolic.py).

Its derivatives are checked against heyoka's own (``heyoka.diff``) at sample points, for every
function and operator of the grammar; its normal form against the text it came from; and the
sharing it exists for: a pair's terms written once for both bodies, and the canonical
equations of a Newtonian N-body H no larger than ``heyoka.model.nbody``.
"""

from __future__ import annotations

from fractions import Fraction

import heyoka as hy
import numpy as np
import pytest

from cayley_heyoka.core.expressions import FUNCTIONS, parse_expression, rebuild
from cayley_heyoka.core.model import ParTable
from cayley_heyoka.core.precision import Precision
from cayley_heyoka.core.symbolic import Algebra, Unsupported
from cayley_heyoka.hamilton.canonical import canonical_equations, shared_canonical_equations

X, Y = hy.make_vars("x", "y")
#: Sample points inside every text's domain (x, y > 0, |x| < 3, |y| < 4), and times at none
#: of its poles (t = 0, or a literal: 1/(t - 0.5)).
POINTS = np.array([[0.3, 0.7, 1.9, 2.6], [0.45, 1.6, 0.2, 3.1]])
TIMES = np.array([0.21, 0.37, 1.75, 4.1])

TEXTS = [
    "x**3*y - 2*x/y + 7",
    "sin(x*y) + cos(x)**2 - tan(y/3)",
    "exp(-x**2/2)*log(y + 3)",
    "sqrt(x**2 + y**2 + 1)**3 - 1/sqrt(x**2 + 1)",
    "asin(x/3) + acos(y/4) + atan(x*y)",
    "atan2(y, x + 3) + sinh(x) - cosh(y)/2 + tanh(x*y)",
    "erf(x - y)",
    "x**y + (x + 2)**(1/3) + 4**(1/2)*x + 2**(1/2)*y",
    "(2*x - 2*y)**2 + 4*(x - y) - (x - y)/(y - x)",
    "0.25*x**2*t + pi*y - x**(1/2)*x**(1/2)",
    "(x*y**2)**(1/2) - (x**(1/2)*y)**(2/3) + 3/(x*y)**2",
    "-(x + y)/(x*y) + (1 - x)*(1 + y)*x**-2",
]


def _parsed(text: str, precision: str = "double") -> tuple[Algebra, ParTable, object, object]:
    pars = ParTable(Precision.from_spec(precision))
    symbols = {"x": X, "y": Y}
    expr = parse_expression(text, symbols, pars, "test.f")
    algebra = Algebra(pars.constant, FUNCTIONS)
    return algebra, pars, expr, rebuild(text, symbols, pars, "test.f", algebra)


def _values(exprs: list, pars: ParTable) -> np.ndarray:
    f = hy.cfunc(exprs, [X, Y], compact_mode=True)
    values = np.ascontiguousarray(
        np.array([[float(Fraction(v)) for v in pars.values]] * POINTS.shape[1]).T
    )
    kw = {"pars": np.ascontiguousarray(values[: f.nparams])} if f.nparams else {}
    return f(POINTS, time=TIMES, **kw)


@pytest.mark.parametrize("text", TEXTS)
def test_the_normal_form_and_its_derivatives_are_heyokas(text):
    """The expression and both partial derivatives equal heyoka's at the sample points."""
    algebra, pars, expr, node = _parsed(text)
    ours = [algebra.emit(node)] + [
        algebra.emit(algebra.diff(node, algebra.leaf(v))) for v in (X, Y)
    ]
    theirs = [expr, hy.diff(expr, X), hy.diff(expr, Y)]
    a, b = _values(ours, pars), _values(theirs, pars)
    assert np.all(np.isfinite(b))
    np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13)


def test_a_fractional_power_of_a_power_keeps_its_sign():
    """(x²)^(1/2) = |x|, not x: exponents merge only where both sides agree."""
    algebra, pars, _, node = _parsed("(x**2)**(1/2)")
    f = hy.cfunc([algebra.emit(node)], [X, Y], compact_mode=True)
    assert f(np.array([-2.0, 1.0]))[0] == 2.0
    algebra, pars, _, node = _parsed("(x**(1/2))**(1/2)")
    assert str(algebra.emit(node)) == str(X ** hy.expression(0.25))


def test_sums_share_their_content():
    """2x − 2y is 2·(x − y): ∂/∂x of (2x − 2y)³ is 24 (x − y)², a power of the same x − y."""
    algebra, pars, _, node = _parsed("(2*x - 2*y)**3")
    d = algebra.diff(node, algebra.leaf(X))
    assert d.kind == "scaled" and d.value == 24
    assert str(algebra.emit(d)) == str(hy.expression(24.0) * (X - Y) ** hy.expression(2.0))


def test_a_pairs_partial_derivatives_are_one_expression():
    """∂/∂x₁ of 6/|r₁ − r₂| is −∂/∂x₂: the same heyoka expression, negated, with the pair's
    coefficient and (r²)^(−3/2) once (heyoka's own is twice as long and shares nothing)."""
    x1, y1, x2, y2 = hy.make_vars("x1", "y1", "x2", "y2")
    pars = ParTable(Precision.from_spec("double"))
    symbols = {"x1": x1, "y1": y1, "x2": x2, "y2": y2}
    text = "6/sqrt((x1 - x2)**2 + (y1 - y2)**2)"
    parse_expression(text, symbols, pars, "test.H")
    algebra = Algebra(pars.constant, FUNCTIONS)
    node = rebuild(text, symbols, pars, "test.H", algebra)
    a = algebra.emit(algebra.diff(node, algebra.leaf(x1)))
    b = algebra.emit(algebra.neg(algebra.diff(node, algebra.leaf(x2))))
    assert a == b
    r2 = (x1 - x2) ** hy.expression(2.0) + (y1 - y2) ** hy.expression(2.0)
    assert str(a) == str(-(hy.expression(6.0) * r2 ** hy.expression(-1.5) * (x1 - x2)))


def _nbody(n: int) -> tuple[str, list, list]:
    masses = [1, 3, 7, 2][:n]
    kinetic = " + ".join(
        f"(varpi{3 * i + 1}**2 + varpi{3 * i + 2}**2 + varpi{3 * i + 3}**2)/{2 * m}"
        for i, m in enumerate(masses)
    )
    potential = " - ".join(
        f"{masses[i] * masses[j]}/sqrt("
        + " + ".join(f"(eta{3 * i + k} - eta{3 * j + k})**2" for k in (1, 2, 3))
        + ")"
        for i in range(n)
        for j in range(i + 1, n)
    )
    eta = [hy.make_vars(f"eta{k + 1}") for k in range(3 * n)]
    varpi = [hy.make_vars(f"varpi{k + 1}") for k in range(3 * n)]
    return f"{kinetic} - {potential}", eta, varpi


@pytest.mark.parametrize("precision", ["double", "quad"])
def test_the_canonical_equations_are_heyokas_up_to_round_off(precision):
    """(A.) of a Newtonian 3-body H with a time-dependent term, a literal and a parameter-free
    part: heyoka.hamiltonian's to round-off at a sample state, in double and in quad."""
    text, eta, varpi = _nbody(3)
    text += " + 0.125*sin(t/3)*eta1*varpi2"
    pars = ParTable(Precision.from_spec(precision))
    symbols = {str(v): v for v in (*eta, *varpi)}
    H = parse_expression(text, symbols, pars, "hamiltonian.H")
    ours, counted = shared_canonical_equations(
        H, [(text, "hamiltonian.H")], symbols, pars, eta, varpi
    )
    theirs = canonical_equations(H, eta, varpi)
    assert [v for v, _ in ours] == [v for v, _ in theirs]
    assert counted is not None
    state = np.array([1.0, 0.2, -0.1, -1.1, 0.5, 0.3, 0.1, -0.9, 0.4] + [0.3, -0.2, 0.1] * 3)
    prec = Precision.from_spec(precision)
    kw = prec.heyoka_kwargs
    args = [*eta, *varpi]
    values = [
        hy.cfunc([rhs for _, rhs in system], args, compact_mode=True, **kw)(
            prec.array(state), pars=prec.array(pars.values), time=prec.array([0.7])[0]
        )
        for system in (ours, theirs)
    ]
    scale = max(abs(float(v)) for v in values[1])
    for a, b in zip(*values, strict=True):
        assert abs(float(a - b)) <= 64 * prec.epsilon * scale, (a, b)


def test_a_newtonian_n_body_system_is_no_larger_than_heyokas_nbody():
    """The decomposition of (A.) for four bodies against heyoka.model.nbody's (the same
    masses): no larger, and counted exactly by the algebra (Model.decomposition)."""
    text, eta, varpi = _nbody(4)
    pars = ParTable(Precision.from_spec("double"))
    symbols = {str(v): v for v in (*eta, *varpi)}
    H = parse_expression(text, symbols, pars, "hamiltonian.H")
    system, counted = shared_canonical_equations(
        H, [(text, "hamiltonian.H")], symbols, pars, eta, varpi
    )
    ours = hy.taylor_adaptive(system, [0.1 * k + 1 for k in range(24)], compact_mode=True)
    nbody = hy.model.nbody(4, masses=[1.0, 3.0, 7.0, 2.0], Gconst=1.0)
    floor = hy.taylor_adaptive(nbody, [0.1 * k + 1 for k in range(24)], compact_mode=True)
    heyokas = hy.taylor_adaptive(
        canonical_equations(H, eta, varpi), [0.1 * k + 1 for k in range(24)], compact_mode=True
    )
    assert len(ours.decomposition) <= len(floor.decomposition) < len(heyokas.decomposition)
    assert counted == len(ours.decomposition)


def test_an_operation_the_algebra_refuses_falls_back_to_heyoka():
    """A division by an exact zero (x − x) is left to heyoka's differentiation."""
    eta, varpi = [hy.make_vars("eta1")], [hy.make_vars("varpi1")]
    text = "varpi1**2/2 + 1/(eta1 - eta1)"
    pars = ParTable(Precision.from_spec("double"))
    symbols = {"eta1": eta[0], "varpi1": varpi[0]}
    H = parse_expression(text, symbols, pars, "hamiltonian.H")
    system, counted = shared_canonical_equations(
        H, [(text, "hamiltonian.H")], symbols, pars, eta, varpi
    )
    assert counted is None
    assert system == canonical_equations(H, eta, varpi)


def _random_text(rng: np.random.Generator, depth: int) -> str:
    if depth == 0 or rng.random() < 0.2:
        return str(rng.choice(["x", "y", "2", "3", "(1/3)", "0.5", "t", "(x - y)", "(2*x - 2*y)"]))
    a, b = _random_text(rng, depth - 1), _random_text(rng, depth - 1)
    kind = rng.integers(8)
    if kind < 4:
        return f"({a} {'+-*/'[kind]} {b})"
    if kind == 4:
        return f"{a}**{rng.choice(['2', '3', '-1', '-2', '(1/2)', '(-3/2)', '(2/3)'])}"
    if kind == 5:
        return f"{rng.choice(['sin', 'cos', 'atan', 'tanh', 'erf'])}({a})"
    if kind == 6:
        return f"exp({a}/10)"
    return f"sqrt(1 + ({a})**2)*{b}"


def test_random_expressions_in_one_algebra_match_heyoka():
    """200 random texts built into one algebra (their shared nodes and emitted expressions
    memoised together): each value and derivative equal to heyoka's wherever heyoka's is
    finite (a text the algebra refuses, dividing by an exact zero, is left out)."""
    rng = np.random.default_rng(20240)
    pars = ParTable(Precision.from_spec("double"))
    symbols = {"x": X, "y": Y}
    algebra = Algebra(pars.constant, FUNCTIONS)
    ours, theirs, refused = [], [], 0
    for k in range(200):
        text = _random_text(rng, 4)
        expr = parse_expression(text, symbols, pars, f"test.f{k}")
        try:
            node = rebuild(text, symbols, pars, f"test.f{k}", algebra)
            emitted = [algebra.emit(algebra.diff(node, algebra.leaf(v))) for v in (X, Y)]
        except Unsupported:
            refused += 1
            continue
        ours += [*emitted, algebra.emit(node)]
        theirs += [hy.diff(expr, X), hy.diff(expr, Y), expr]
    assert refused < 20
    a, b = _values(ours, pars), _values(theirs, pars)
    finite = np.isfinite(b) & (np.abs(b) < 1e12)
    assert finite.mean() > 0.8
    np.testing.assert_allclose(a[finite], b[finite], rtol=1e-9, atol=1e-9)
