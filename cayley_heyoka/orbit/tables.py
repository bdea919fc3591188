"""Many orbits' numbers at once: the orbit family's ``table`` (:mod:`..core.structures`).

The members of a sweep that differ only in their initial position and velocity, or in their
elements, share a structure; :func:`cayley_heyoka.orbit.numbers.numbers` gives each its
initial state one member at a time, in mpmath with guard digits (33 digits in double: the
Cartesian state, Kepler's equation, Cayley's angles by arc tangents, ρ less its whole
revolutions), each value rounded once to double. :func:`table` computes the same values for
every member at once in double-double arithmetic (:mod:`cayley_heyoka.core.ddouble`, about
106 bits), from the same exact inputs (a member's decimal text as a double and its rest), by
the same mathematics (not the same operations: where ``numbers`` goes from elements to the
Cartesian state and back, the table takes Cayley's state from the elements directly), and
rounds each value to double only where it vouches for the rounding.

The bound. Let ε = 2⁻⁸⁰. Each value v of a row has a scale S (r for r and a position, |v|
for ṙ and a velocity, r|v| for h, 8 for an angle, 1 for a quaternion's component) and the
row a condition K ≥ 1: |x||v|/h (how far the motion is from rectilinear) over sin Φ (Θ and
u are ill-conditioned like 1/sin Φ near the reference plane) for a Cartesian start; for
elements 4/(1 − e)² (Kepler's equation, the true anomaly and the flight-path angle) times the
largest of 1 and the angles' magnitudes (their reduction modulo 2π), over sin Φ for the
formulations that carry Φ. mpmath's value at 113 bits errs from the exact one by a few tens
of units of 2⁻¹¹³ of K·S, its text of 33 digits by 0.51·10⁻³² of it, and the double-double
value by a few tens of units of 2⁻¹⁰³ of K·S: all far below εK·S. A value is rounded by the
table where :func:`cayley_heyoka.core.ddouble.gap` (its distance to the nearest rounding
boundary) exceeds εK·S, so that both round to the same double; the row is a *suspect*
(validated and built alone by ``numbers``) where any value is within it, where K exceeds
2²⁰ (the first-order analysis no longer holds with room), where a value is exactly zero
(mpmath's may be a rounding residue), where an angle is within the bound of a branch of
its arc tangent (Θ, u at ±π; ρ at a whole number of revolutions, which decides the count),
or where the scene's validation could refuse the member or start it in another variant: a
swept coordinate outside 0 ∪ [2⁻¹²⁰, 2¹²⁰] (no product overflows or underflows), e or the
inclination at or beyond its range, a motion near the rectilinear, sin Φ within 2⁻³⁰K of
``equatorial_limit`` or below it where the run would start tilted.

Not offered (None, each member built alone): the ``encke`` formulation (its state is the
deviation from the first osculating ellipse: rounding residues), a moving reference plane,
a perturber with a Legendre ``degree`` (its validation compares the apocentre), a start on
the tilted frame, and any other swept field (μ, the gauge Σ, a perturbation's numbers).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..core import ddouble as dd
from ..core.ddouble import Dd
from ..core.scene import Scene
from ..core.structures import Table, double_doubles
from ..mechanics.kepler import ELEMENT_KEYS
from . import revolutions
from .numbers import hands_over, start_variant
from .scene import Orbit
from .tilt import LEVEL

#: The swept fields the table knows, by the orbit's initial state.
_CARTESIAN: dict[tuple[str | int, ...], int] = {
    ("orbit", kind, i): 3 * j + i
    for j, kind in enumerate(("position", "velocity"))
    for i in range(3)
}
_ELEMENTS: dict[tuple[str | int, ...], int] = {
    ("orbit", "elements", k): i for i, k in enumerate(ELEMENT_KEYS)
}

#: ε of the bound, and the largest condition K a row may have (module docstring).
_EPS = 2.0**-80
_CONDITION_LIMIT = 2.0**20
#: A swept coordinate is 0 or of a magnitude in this range (no product overflows).
_SMALLEST, _LARGEST = 2.0**-120, 2.0**120
#: The angles' scale.
_ANGLE = 8.0


def table(
    scene: Scene,
    model: Any,
    fields: tuple[tuple[str | int, ...], ...],
    x: np.ndarray,
    exact: np.ndarray,
    low: np.ndarray | None = None,
) -> Table | None:
    """The numbers of orbits that are ``scene`` with other initial positions and velocities,
    or other elements, as arrays (double precision;
    :func:`cayley_heyoka.core.structures.table_for`).

    ``x`` and ``low`` hold each orbit's numbers at ``fields`` (``orbit.position[i]``,
    ``orbit.velocity[i]`` or ``orbit.elements.KEY``, as the scene gives its start) as a double
    and its rest; ``exact``, whether each is that double. Every trusted row is
    :func:`cayley_heyoka.orbit.numbers.numbers` bit for bit (the module docstring says why;
    ``table_for`` checks two rows against full builds); None where the table offers none.

    Examples
    --------
    >>> import numpy as np
    >>> import cayley_heyoka as ch
    >>> from cayley_heyoka.core.structures import model_for
    >>> data = {"orbit": {"mu": 1, "position": [1, 0, "0.1"], "velocity": [0, 1, "0.2"]},
    ...         "output": {"times": [0, 1]}}
    >>> scene = ch.Scene.from_dict(data)
    >>> vy = np.array([[1.0], [1.125]])
    >>> fields = (("orbit", "velocity", 1),)
    >>> t = table(scene, model_for(scene), fields, vy, vy == vy, 0 * vy)
    >>> t.suspect.tolist(), t.initial[:, 0].tolist() == [1.004987562112089] * 2
    ([False, False], True)
    """
    orbit: Orbit = scene.model
    if low is None or orbit.form.deviation:
        return None
    third = orbit.third_body
    if orbit.plane is not None or (third is not None and third.degree is not None):
        return None
    known = _ELEMENTS if orbit.initial[0] == "elements" else _CARTESIAN
    if any(f not in known for f in fields) or start_variant(scene) not in (None, LEVEL):
        return None
    n = len(x)
    given = _given(orbit)
    columns = [(np.full(n, hi), np.full(n, lo)) for hi, lo in given]
    suspect = np.zeros(n, dtype=bool)
    for j, f in enumerate(fields):
        columns[known[f]] = (x[:, j].copy(), low[:, j].copy())
    with np.errstate(all="ignore"):  # a value double cannot hold makes its row a suspect
        for hi, _ in columns:
            size = np.abs(hi)
            suspect |= ~((hi == 0) | ((size >= _SMALLEST) & (size <= _LARGEST)))
        columns = [dd.of(hi, lo) for hi, lo in columns]
        if orbit.initial[0] == "elements":
            values, bounds, doubtful = _from_elements(orbit, columns)
        else:
            values, bounds, doubtful = _from_cartesian(orbit, columns)
        suspect |= doubtful
        if "rho" in values:
            k, doubtful = _count(scene, values, bounds)
            suspect |= doubtful
        initial = np.repeat(np.asarray(model.initial_state, dtype=np.float64)[None], n, axis=0)
        pars = np.repeat(np.asarray(model.pars.values, dtype=np.float64)[None], n, axis=0)
        for name, value in values.items():
            i = model.state_names.index(name)
            if name in bounds:
                suspect |= ~(dd.gap(value) > bounds[name])
            initial[:, i] = value[0] + 0.0  # never −0: mpmath has no signed zero
        if "rho" in values:
            _count_pars(scene, model, k, pars, suspect)
        suspect |= ~(np.isfinite(initial).all(axis=1) & np.isfinite(pars).all(axis=1))
    return Table(initial, pars, suspect)


def _given(orbit: Orbit) -> list[tuple[float, float]]:
    """The orbit's initial numbers (position and velocity, or the elements in order) as a
    double and its rest."""
    if orbit.initial[0] == "elements":
        numbers = [orbit.initial[1][k] for k in ELEMENT_KEYS]
    else:
        numbers = [*orbit.initial[1], *orbit.initial[2]]
    x, low, _, _ = double_doubles([numbers])
    return list(zip(x[0].tolist(), low[0].tolist(), strict=True))


def _scalar(value: Any) -> Dd:
    x, low, _, _ = double_doubles([[value]])
    return np.asarray(x[0, 0]), np.asarray(low[0, 0])


def _stacked(fn: Any, *args: list[Dd]) -> Any:
    """``fn`` of several double-doubles of the same length at once (numpy's cost is per call)."""
    n = len(args[0][0][0])
    joined = [
        (np.concatenate([a[0] for a in arg]), np.concatenate([a[1] for a in arg])) for arg in args
    ]
    out = fn(*joined)
    parts = out if isinstance(out, tuple) and isinstance(out[0], tuple) else (out,)
    split = []
    for part in parts:
        split.append(
            [
                (part[0][k * n : (k + 1) * n], part[1][k * n : (k + 1) * n])
                for k in range(len(args[0]))
            ]
        )
    return split[0] if len(split) == 1 else split


# ---------------------------------------------------------------------- from a Cartesian start
def _from_cartesian(
    orbit: Orbit, columns: list[Dd]
) -> tuple[dict[str, Dd], dict[str, np.ndarray], np.ndarray]:
    X, V = columns[:3], columns[3:]
    r = dd.sqrt(dd.dot(X, X))
    speed = np.sqrt(sum(v[0] * v[0] for v in V))
    H = dd.cross(X, V)
    s2 = dd.add(dd.square(H[0]), dd.square(H[1]))
    h = dd.sqrt(dd.add(s2, dd.square(H[2])))
    A = r[0] * speed / h[0]  # |x||v|/h: ≥ 1, large near rectilinear motion
    doubtful = ~(A <= _CONDITION_LIMIT)  # and h = 0, NaN
    if orbit.form.cartesian:
        values, bounds = {}, {}
        for name, column in zip(("x", "y", "z", "vx", "vy", "vz"), columns, strict=True):
            values[name] = column
            bounds[name] = 2.0**-90 * np.abs(column[0])
            # A number that is a double is its own state (mpmath holds it exactly).
            bounds[name] = np.where(column[1] == 0, -1.0, bounds[name])
        return values, bounds, doubtful
    s = dd.sqrt(s2)
    sin_phi = s[0] / h[0]
    K = A / sin_phi
    doubtful |= ~(K <= _CONDITION_LIMIT)
    # u = atan2(x·(n × node), x·node), n = H/h, node = (cos Θ, sin Θ, 0) = (−H₁, H₀, 0)/s;
    # the positive factors s and h taken out of both arguments.
    N = dd.sub(dd.mul(X[2], s2), dd.mul(H[2], dd.add(dd.mul(X[0], H[0]), dd.mul(X[1], H[1]))))
    D = dd.mul(dd.sub(dd.mul(X[1], H[0]), dd.mul(X[0], H[1])), h)
    Phi, Theta, u = _stacked(dd.atan2, [s, H[0], N], [H[2], dd.neg(H[1]), D])
    rdot = dd.div(dd.dot(X, V), r)
    values = {"r": r, "rdot": rdot, "h": h, "Theta": Theta, "Phi": Phi, "u": u}
    scales = {"r": r[0], "rdot": speed, "h": r[0] * speed}
    return _cayley(orbit, values, scales, K, sin_phi, doubtful)


# ---------------------------------------------------------------------- from elements
def _from_elements(
    orbit: Orbit, columns: list[Dd]
) -> tuple[dict[str, Dd], dict[str, np.ndarray], np.ndarray]:
    a, e, inclination, node, omega, M = columns
    mu = _scalar(orbit.mu)
    pi_hi = np.pi
    doubtful = ~((a[0] > 0) & (e[0] >= 0) & (e[0] < 1))
    doubtful |= ~((inclination[0] >= 0) & (inclination[0] < pi_hi))
    angles = np.maximum.reduce(
        [np.ones_like(a[0]), np.abs(M[0]), np.abs(omega[0]), np.abs(node[0])]
    )
    K = angles * 4 / (1 - e[0]) ** 2
    doubtful |= ~(K <= _CONDITION_LIMIT)
    Mr = dd.reduce(M)
    E0 = _kepler(Mr[0], np.where(doubtful, 0.0, e[0]))
    # One Newton step in double-double from E₀ (converged in double): the error after it is
    # of the order of the square of E₀'s, below 2⁻¹⁰⁰K.
    half = dd.of(E0 * 0.5)
    s0, c0 = dd.sincos(half)
    sin_E0 = dd.scale(dd.mul(s0, c0), 2.0)
    cos_E0 = dd.add_d(dd.scale(dd.square(s0), -2.0), 1.0)
    g = dd.sub(dd.sub(dd.of(E0), dd.mul(e, sin_E0)), Mr)
    slope = 1 - e[0] * cos_E0[0]
    delta = dd.div(g, dd.of(slope))
    half_delta = dd.scale(delta, 0.5)
    d2 = delta[0] * delta[0] / 8
    # sin and cos of (E₀ − δ)/2, to second order in δ (δ³ is below 2⁻¹⁵⁰).
    sE = dd.add_d(dd.sub(s0, dd.mul(c0, half_delta)), -s0[0] * d2)
    cE = dd.add_d(dd.add(c0, dd.mul(s0, half_delta)), -c0[0] * d2)
    one_plus, one_minus = dd.add_d(e, 1.0), dd.add_d(dd.neg(e), 1.0)
    f = dd.scale(dd.atan2(dd.mul(dd.sqrt(one_plus), sE), dd.mul(dd.sqrt(one_minus), cE)), 2.0)
    r = dd.mul(a, dd.add(one_minus, dd.scale(dd.mul(e, dd.square(sE)), 2.0)))
    p = dd.mul(dd.mul(a, one_minus), one_plus)
    sin_E = dd.scale(dd.mul(sE, cE), 2.0)
    rdot = dd.div(dd.mul(dd.mul(dd.sqrt(dd.mul(mu, a)), e), sin_E), r)
    h = dd.sqrt(dd.mul(mu, p))
    Theta = dd.reduce(node)
    u = dd.reduce(dd.add(omega, f))
    speed = np.sqrt(float(mu[0]) * np.abs(2 / r[0] - 1 / a[0]))
    values = {"r": r, "rdot": rdot, "h": h, "Theta": Theta, "Phi": inclination, "u": u}
    scales = {"r": r[0], "rdot": speed, "h": r[0] * speed}
    sin_phi = np.sin(inclination[0])
    if orbit.form.cartesian:
        return _cartesian_state(values, scales, K, inclination, doubtful)
    K = K / sin_phi
    doubtful |= ~(K <= _CONDITION_LIMIT)
    return _cayley(orbit, values, scales, K, sin_phi, doubtful)


def _kepler(M: np.ndarray, e: np.ndarray) -> np.ndarray:
    """E with E − e sin E = M in double (M in [−π, π], 0 ≤ e < 1): Newton's method from
    :func:`cayley_heyoka.mechanics.kepler._solve_kepler`'s start, kept in [−π, π]."""
    E = np.where(e < 0.8, M + e * np.sin(M), M + 0.85 * e * np.sign(M))
    E = np.clip(E, -np.pi, np.pi)
    for _ in range(60):
        step = (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
        E = np.clip(E - step, -np.pi, np.pi)
        if not np.any(np.abs(step) > 2.0**-50 * (np.abs(E) + 1)):
            break
    for _ in range(2):  # to the double nearest the root
        E = E - (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    return E


def _cartesian_state(
    values: dict[str, Dd],
    scales: dict[str, np.ndarray],
    K: np.ndarray,
    inclination: Dd,
    doubtful: np.ndarray,
) -> tuple[dict[str, Dd], dict[str, np.ndarray], np.ndarray]:
    """x = r x̂₃, v = ṙ x̂₃ + (h/r) ŷ₃ (:func:`cayley_heyoka.mechanics.kepler.cayley_to_cartesian`
    on the fixed frame)."""
    r, rdot, h = values["r"], values["rdot"], values["h"]
    (sT, cT), (sP, cP), (su, cu) = zip(
        *_stacked(dd.sincos, [values["Theta"], values["Phi"], values["u"]]), strict=True
    )
    x3 = [
        dd.sub(dd.mul(cT, cu), dd.mul(dd.mul(sT, cP), su)),
        dd.add(dd.mul(sT, cu), dd.mul(dd.mul(cT, cP), su)),
        dd.mul(sP, su),
    ]
    y3 = [
        dd.sub(dd.neg(dd.mul(cT, su)), dd.mul(dd.mul(sT, cP), cu)),
        dd.add(dd.neg(dd.mul(sT, su)), dd.mul(dd.mul(cT, cP), cu)),
        dd.mul(sP, cu),
    ]
    w = dd.div(h, r)
    out, bounds = {}, {}
    for k, name in enumerate(("x", "y", "z")):
        out[name] = dd.mul(r, x3[k])
        out["v" + name] = dd.add(dd.mul(rdot, x3[k]), dd.mul(w, y3[k]))
        bounds[name] = _EPS * K * scales["r"]
        bounds["v" + name] = _EPS * K * scales["rdot"]
    # In the plane of reference (inclination 0 exactly) sin Φ is 0 exactly on both sides,
    # and so are z and v_z.
    flat = (inclination[0] == 0) & (inclination[1] == 0)
    for name in ("z", "vz"):
        bounds[name] = np.where(flat, -1.0, bounds[name])
    return out, bounds, doubtful


# ---------------------------------------------------------------------- Cayley's state
def _cayley(
    orbit: Orbit,
    values: dict[str, Dd],
    scales: dict[str, np.ndarray],
    K: np.ndarray,
    sin_phi: np.ndarray,
    doubtful: np.ndarray,
) -> tuple[dict[str, Dd], dict[str, np.ndarray], np.ndarray]:
    """The state of the ``cayley`` or ``quaternion`` formulation (ρ not yet reduced: see
    :func:`_revolutions`), its bounds, and the rows in doubt."""
    angle = _EPS * K * _ANGLE
    for name in ("Theta", "u"):  # (−π, π]: a value near ±π is on either side
        doubtful |= ~(np.pi - np.abs(values[name][0]) > angle + 2.0**-50)
    if hands_over(orbit):  # tilted at or below the limit
        limit = float(orbit.equatorial_limit)
        doubtful |= ~(sin_phi > limit * (1 + 2.0**-40) + 2.0**-30 * K)
    sigma = _scalar(orbit.sigma0)
    rho = dd.add(values["u"], sigma)
    out = {"r": values["r"], "rdot": values["rdot"], "rho": rho, "h": values["h"]}
    bounds = {name: _EPS * K * scales[name] for name in ("r", "rdot", "h")}
    bounds["rho"] = angle
    if orbit.form.angles:  # Θ and Φ in the state; else the plane as a quaternion
        out |= {"Theta": values["Theta"], "Phi": values["Phi"]}
        bounds |= {"Theta": angle, "Phi": angle}
        return out, bounds, doubtful
    # q = q₃(Θ) q₁(Φ) q₃(−Σ), each q_k(a) = (cos a/2, sin a/2 along axis k)
    # (numbers._plane_quaternion on the fixed frame, whose factors are 1 exactly).
    n = len(K)
    half_sigma = dd.scale((np.full(n, sigma[0]), np.full(n, sigma[1])), 0.5)
    (sT, cT), (sP, cP), (sS, cS) = zip(
        *_stacked(
            dd.sincos,
            [dd.scale(values["Theta"], 0.5), dd.scale(values["Phi"], 0.5), half_sigma],
        ),
        strict=True,
    )
    sS = dd.neg(sS)
    a = [dd.mul(cT, cP), dd.mul(cT, sP), dd.mul(sT, sP), dd.mul(sT, cP)]
    q = [
        dd.sub(dd.mul(a[0], cS), dd.mul(a[3], sS)),
        dd.add(dd.mul(a[1], cS), dd.mul(a[2], sS)),
        dd.sub(dd.mul(a[2], cS), dd.mul(a[1], sS)),
        dd.add(dd.mul(a[0], sS), dd.mul(a[3], cS)),
    ]
    # An error δ in Θ moves each component by half its partner's size times δ, and Θ errs
    # like A/sin Φ = A/(2 sin(Φ/2) cos(Φ/2)): qx, qy (∝ sin(Φ/2)) by A/cos(Φ/2), qw, qz by
    # A/sin(Φ/2). With a gauge Σ ≠ 0 the components mix: the whole of K for each.
    A = K * sin_phi
    plain = sigma[0] == 0 and sigma[1] == 0
    for name, value, part in zip(("qw", "qx", "qy", "qz"), q, (sP, cP, cP, sP), strict=True):
        out[name] = value
        bounds[name] = _EPS * (A / np.abs(part[0]) + _ANGLE) if plain else _EPS * K
    return out, bounds, doubtful


def _count(scene: Scene, values: dict[str, Dd], bounds: dict[str, np.ndarray]) -> tuple:
    """ρ less its whole revolutions k = ⌊ρ/C⌋ (:func:`cayley_heyoka.orbit.revolutions.values`),
    put in ``values``; returns k and the rows in doubt: a ρ within its bound of a multiple of
    C (the count is on either side)."""
    C = float(revolutions._Turn.of(scene.integrator.precision).C)
    rho = values["rho"]
    m = np.rint(rho[0] / C)
    m = np.where(np.isfinite(m), m, 0.0)
    near = dd.add(rho, dd.neg(dd.two_prod(m, np.full_like(m, C))))
    doubtful = ~(np.abs(near[0]) > bounds["rho"] + 2.0**-50) | ~(np.abs(m) <= 2**20)
    k = np.where(near[0] < 0, m - 1, m)
    values["rho"] = dd.add(rho, dd.neg(dd.two_prod(k, np.full_like(k, C))))
    return k, doubtful


def _count_pars(
    scene: Scene, model: Any, k: np.ndarray, pars: np.ndarray, suspect: np.ndarray
) -> None:
    """The parameters of each row's count k (computed once for each count)."""
    prec = scene.integrator.precision
    offset, phase = model.pars.index("orbit.rho_offset"), model.pars.index("orbit.rho_phase")
    for count in np.unique(k[~suspect]).tolist():
        texts = revolutions.count_values(prec, int(count))
        rows = (k == count) & ~suspect
        pars[rows, offset] = float(texts["orbit.rho_offset"])
        pars[rows, phase] = float(texts["orbit.rho_phase"])
