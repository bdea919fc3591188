"""Double-double arithmetic on numpy arrays: a number as ``hi + lo``, two doubles.

A family's table (:func:`cayley_heyoka.core.structures.table_for`) computes many members'
numbers at once, and must round each as the family's ``numbers`` does: once, from a value
computed in extended precision (mpmath). Where that value is not a double's sum or product,
double arithmetic cannot give the same bits; double-double can, where it vouches for the
result: it carries about 106 bits, each operation here errs by a few units of 2⁻¹⁰⁴ of its
result (Dekker's and Knuth's error-free transformations, as in Bailey's QD library), and
:func:`gap` says how far a value lies from the nearest rounding boundary of double, so that a
table marks as suspect every value within its error bound of one.

The transcendental functions take the argument reductions of table-driven libraries: to
within 2⁻⁹ of a point j/256 whose sine, cosine or arc tangent is tabulated in double-double
(computed once in mpmath), and a short series there whose terms beyond the first two are
below 2⁻⁴⁵ and summed in double. Their error is a few units of 2⁻¹⁰³ for arguments of
magnitude at most a few units (:func:`reduce` brings an angle there).

Overflow, underflow and NaN are not trapped: a caller keeps its inputs in a range where no
product overflows or leaves the normal range, and treats a non-finite result as unknown.
"""

from __future__ import annotations

import functools

import numpy as np

#: A double-double: (hi, lo) arrays with hi = fl(hi + lo).
Dd = tuple[np.ndarray, np.ndarray]

_SPLIT = 134217729.0  # 2²⁷ + 1: Dekker's splitting constant


def two_sum(a: np.ndarray, b: np.ndarray) -> Dd:
    """s = fl(a + b) and the error of that sum, exactly (Knuth)."""
    s = a + b
    bb = s - a
    return s, (a - (s - bb)) + (b - bb)


def _quick_two_sum(a: np.ndarray, b: np.ndarray) -> Dd:
    """As :func:`two_sum`, for |a| ≥ |b| (Dekker)."""
    s = a + b
    return s, b - (s - a)


def _split(a: np.ndarray) -> Dd:
    t = _SPLIT * a
    hi = t - (t - a)
    return hi, a - hi


def two_prod(a: np.ndarray, b: np.ndarray) -> Dd:
    """p = fl(a b) and the error of that product, exactly (Dekker; |a b| < 2⁹⁹⁶ and no
    underflow)."""
    p = a * b
    ah, al = _split(a)
    bh, bl = _split(b)
    return p, ((ah * bh - p) + ah * bl + al * bh) + al * bl


def of(hi: np.ndarray | float, lo: np.ndarray | float = 0.0) -> Dd:
    """A double-double from a double and a smaller correction (normalised)."""
    return two_sum(np.asarray(hi, dtype=np.float64), np.asarray(lo, dtype=np.float64))


def add(x: Dd, y: Dd) -> Dd:
    s, e = two_sum(x[0], y[0])
    t, f = two_sum(x[1], y[1])
    s, e = _quick_two_sum(s, e + t)
    return _quick_two_sum(s, e + f)


def neg(x: Dd) -> Dd:
    return -x[0], -x[1]


def sub(x: Dd, y: Dd) -> Dd:
    return add(x, neg(y))


def add_d(x: Dd, b: np.ndarray | float) -> Dd:
    """x + b, b a double."""
    s, e = two_sum(x[0], np.asarray(b, dtype=np.float64))
    return _quick_two_sum(s, e + x[1])


def mul(x: Dd, y: Dd) -> Dd:
    p, e = two_prod(x[0], y[0])
    return _quick_two_sum(p, e + (x[0] * y[1] + x[1] * y[0]))


def mul_d(x: Dd, b: np.ndarray | float) -> Dd:
    """x b, b a double."""
    b = np.asarray(b, dtype=np.float64)
    p, e = two_prod(x[0], b)
    return _quick_two_sum(p, e + x[1] * b)


def scale(x: Dd, power_of_two: float) -> Dd:
    """x times a power of two (exact)."""
    return x[0] * power_of_two, x[1] * power_of_two


def div(x: Dd, y: Dd) -> Dd:
    """x / y: three quotient digits (QD's accurate division)."""
    q1 = x[0] / y[0]
    r = sub(x, mul_d(y, q1))
    q2 = r[0] / y[0]
    r = sub(r, mul_d(y, q2))
    q3 = r[0] / y[0]
    return add_d(_quick_two_sum(q1, q2), q3)


def sqrt(x: Dd) -> Dd:
    """√x for x > 0 (one Newton step from the double root)."""
    q = np.sqrt(x[0])
    p, e = two_prod(q, q)
    return _quick_two_sum(q, ((x[0] - p) - e + x[1]) / (2 * q))


def square(x: Dd) -> Dd:
    return mul(x, x)


def dot(a: list[Dd], b: list[Dd]) -> Dd:
    total = mul(a[0], b[0])
    for u, v in zip(a[1:], b[1:], strict=True):
        total = add(total, mul(u, v))
    return total


def cross(a: list[Dd], b: list[Dd]) -> list[Dd]:
    return [
        sub(mul(a[1], b[2]), mul(a[2], b[1])),
        sub(mul(a[2], b[0]), mul(a[0], b[2])),
        sub(mul(a[0], b[1]), mul(a[1], b[0])),
    ]


def where(condition: np.ndarray, x: Dd, y: Dd) -> Dd:
    return np.where(condition, x[0], y[0]), np.where(condition, x[1], y[1])


def absolute(x: Dd) -> Dd:
    negative = x[0] < 0
    return np.where(negative, -x[0], x[0]), np.where(negative, -x[1], x[1])


# ---------------------------------------------------------------------- constants and tables
@functools.cache
def _constant(name: str) -> tuple[float, float, float]:
    """π, π/2 or 2π as three doubles (hi + mid + lo to about 160 bits)."""
    import mpmath

    with mpmath.workprec(240):
        value = {"pi": mpmath.pi, "half_pi": mpmath.pi / 2, "two_pi": 2 * mpmath.pi}[name]
        parts = []
        for _ in range(3):
            parts.append(float(value))
            value -= parts[-1]
    return parts[0], parts[1], parts[2]


def constant(name: str) -> Dd:
    """``"pi"``, ``"half_pi"`` or ``"two_pi"`` as a double-double (scalars)."""
    hi, mid, _ = _constant(name)
    return np.asarray(hi), np.asarray(mid)


#: Table points j/256 of the transcendental functions.
_STEPS = 256


@functools.cache
def _table(kind: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """sin and cos of j/256 for |j| ≤ 256·π/4 + 1, or atan of j/256 for 0 ≤ j ≤ 256, as
    double-doubles (index j + offset)."""
    import mpmath

    if kind == "atan":
        points = range(0, _STEPS + 1)
        funcs = (mpmath.atan, mpmath.atan)
    else:
        last = int(_STEPS * np.pi / 4) + 2
        points = range(-last, last + 1)
        funcs = (mpmath.sin, mpmath.cos)
    out = []
    with mpmath.workprec(200):
        for f in funcs:
            hi, lo = [], []
            for j in points:
                v = f(mpmath.mpf(j) / _STEPS)
                h = float(v)
                hi.append(h)
                lo.append(float(v - h))
            out += [np.array(hi), np.array(lo)]
    return out[0], out[1], out[2], out[3]


def _offset(kind: str) -> int:
    return 0 if kind == "atan" else int(_STEPS * np.pi / 4) + 2


# ---------------------------------------------------------------------- functions
def reduce(x: Dd) -> Dd:
    """x − 2πk in [−π, π] (k the nearest integer to x/2π): an angle of magnitude below 2²⁰
    reduced with the error of one operation (2π in three parts, k 2π's first two products
    exact)."""
    c1, c2, c3 = _constant("two_pi")
    k = np.rint(x[0] / c1)
    y = add(x, neg(two_prod(k, np.asarray(c1))))
    y = add(y, neg(two_prod(k, np.asarray(c2))))
    return add_d(y, -k * c3)


def sincos(x: Dd) -> tuple[Dd, Dd]:
    """(sin x, cos x) for |x| ≤ 8."""
    h1, h2, h3 = _constant("half_pi")
    k = _index(x[0] / h1, 5)
    t = add(x, neg(two_prod(k, np.asarray(h1))))
    t = add_d(add(t, neg(two_prod(k, np.asarray(h2)))), -k * h3)  # |t| ≤ π/4
    j = _index(t[0] * _STEPS, _offset("sincos"))
    z = add_d(t, -j / _STEPS)  # |z| ≤ 2⁻⁹
    z2 = square(z)
    z3 = mul(z2, z)
    zh, z2h = z[0], z2[0]
    # sin z = z − z³/6 + z⁵/120 − …, cos z = 1 − z²/2 + z⁴/24 − z⁶/720 + …: the terms past
    # z³/6 and z⁴/24 are below 2⁻⁵¹ and 2⁻⁶³, so double's rounding of them is below 2⁻¹⁰⁴.
    tail_s = zh * z2h * z2h * (1 / 120 - z2h * (1 / 5040 - z2h / 362880))
    tail_c = z2h * z2h * z2h * (-1 / 720 + z2h * (1 / 40320 - z2h / 3628800))
    sin_z = add_d(sub(z, mul(z3, _reciprocal(6))), tail_s)
    cos_z = add_d(add(add_d(scale(z2, -0.5), 1.0), mul(square(z2), _reciprocal(24))), tail_c)
    s_hi, s_lo, c_hi, c_lo = _table("sincos")
    i = j.astype(np.int64) + _offset("sincos")
    S, C = (s_hi[i], s_lo[i]), (c_hi[i], c_lo[i])
    sin_t = add(mul(S, cos_z), mul(C, sin_z))
    cos_t = sub(mul(C, cos_z), mul(S, sin_z))
    q = np.mod(k, 4)
    sin_x = where(q == 0, sin_t, where(q == 1, cos_t, where(q == 2, neg(sin_t), neg(cos_t))))
    cos_x = where(q == 0, cos_t, where(q == 1, neg(sin_t), where(q == 2, neg(cos_t), sin_t)))
    return sin_x, cos_x


def atan2(y: Dd, x: Dd) -> Dd:
    """The angle of (x, y) in (−π, π]: π for y = ±0 and x < 0 (the angle of
    :meth:`cayley_heyoka.mechanics.kepler._Kind.angle`); NaN for x = y = 0."""
    ay, ax = absolute(y), absolute(x)
    swap = ay[0] > ax[0]
    t = div(where(swap, ax, ay), where(swap, ay, ax))  # in [0, 1]
    j = _index(t[0] * _STEPS, _STEPS)
    c = j / _STEPS
    z = div(add_d(t, -c), add_d(mul_d(t, c), 1.0))  # atan t = atan c + atan z, |z| ≤ 2⁻⁹
    z2 = square(z)
    z3 = mul(z2, z)
    zh, z2h = z[0], z2[0]
    # atan z = z − z³/3 + z⁵/5 − …: past z³/3 the terms are below 2⁻⁴⁷.
    tail = zh * z2h * z2h * (1 / 5 - z2h * (1 / 7 - z2h * (1 / 9 - z2h / 11)))
    a_hi, a_lo, _, _ = _table("atan")
    i = j.astype(np.int64)
    a = add_d(add((a_hi[i], a_lo[i]), sub(z, mul(z3, _reciprocal(3)))), tail)
    a = where(swap, sub(constant("half_pi"), a), a)
    a = where(x[0] < 0, sub(constant("pi"), a), a)
    return where(y[0] < 0, neg(a), a)


def _index(x: np.ndarray, largest: int) -> np.ndarray:
    """The nearest integer to x, kept in [−largest, largest] (NaN: 0), so that a value out of
    range gives a wrong number, never an index out of a table."""
    return np.clip(np.nan_to_num(np.rint(x)), -largest, largest)


@functools.cache
def _reciprocal(n: int) -> Dd:
    from fractions import Fraction

    hi = 1 / n
    return np.asarray(hi), np.asarray(float(Fraction(1, n) - Fraction(hi)))


# ---------------------------------------------------------------------- rounding
def gap(x: Dd) -> np.ndarray:
    """How far hi + lo lies from the nearest rounding boundary of double (a midpoint between
    neighbouring doubles), for hi = fl(hi + lo): a value known to within less than this
    rounds to hi. Zero for hi = 0 (a value near zero rounds to any tiny double)."""
    hi, lo = x
    a = np.abs(hi)
    toward = np.where(hi < 0, -lo, lo)  # lo's sign relative to hi's
    up = np.spacing(a)
    down = a - np.nextafter(a, 0.0)
    out = np.where(toward >= 0, up / 2 - toward, down / 2 + toward)
    return np.where(a == 0, 0.0, out)
