"""The numbers of an orbit scene's model, and the structure they fill.

:func:`numbers` is the one place an orbit model's numbers are computed — the initial state of
the formulation (Encke's deviation from its first osculating ellipse, ρ reduced by its whole
revolutions, Cayley's angles on the start variant's frame), μ, the reference plane's angles
and rates, the disturbing terms' parameters (:mod:`.disturbing`), the revolutions',
Encke's and the hand-over's parameters — so that :func:`cayley_heyoka.orbit.model.build_model`
and a scene of an already built structure (:mod:`cayley_heyoka.core.structures`) take the
same values. :func:`structure` names what the build compiles: the scene with its numbers
masked, except what the numbers decide about the equations — a rate of the reference plane
that is zero (no time terms), a zonal axis along a coordinate (no axis parameters) and its
sign, a circular or resting perturber, ``equatorial_limit`` = 0 (no hand-over), and the
variant a Cayley run starts in (from sin Φ at the start).
"""

from __future__ import annotations

import functools
import math
import threading
import weakref
from fractions import Fraction
from typing import Any

import mpmath
from mpmath import libmp

from ..core import vectors
from ..core.errors import SceneError
from ..core.model import Numbers
from ..core.precision import Precision, exact_fraction, scene_mpf
from ..core.scene import Scene
from ..core.structures import MASK as _MASK
from ..core.structures import structure_text
from ..mechanics import frames
from ..mechanics import kepler as el
from . import encke, revolutions
from .disturbing import ThirdBody, UserPotential, Zonal, perturbation_key
from .scene import Orbit, PlaneMotion
from .tilt import FRAME, LEVEL, TILTED, angles_in

#: Digits beyond the run's precision of every number computed in mpmath.
GUARD_DIGITS = 15


def structure(scene: Scene) -> str:
    """The scene's model structure: its dictionary with every number the model holds as a
    parameter or an initial value masked (a number that decides a term: whether it is zero,
    or its sign, instead), without its output times, and with the variant a Cayley run
    starts in.

    Examples
    --------
    >>> import cayley_heyoka as ch
    >>> def orbit(a):
    ...     return ch.Scene.from_dict({
    ...         "orbit": {"mu": 1, "elements": {"a": a, "e": "0.1", "inclination": "0.5",
    ...                   "node": 0, "argument_of_pericentre": 0, "mean_anomaly": 0}},
    ...         "perturbations": {"zonal": {"J2": "1e-3", "radius": "0.5"}},
    ...         "output": {"times": {"start": 0, "stop": 1, "count": 2}}})
    >>> structure(orbit(1)) == structure(orbit(2))
    True
    """
    orbit: Orbit = scene.model
    data = {k: v for k, v in scene.source.items()}
    data["orbit"] = {
        "formulation": orbit.formulation,
        "initial": orbit.initial[0],  # elements, or position and velocity
        "equatorial_limit": _zero_or_mask(orbit.equatorial_limit),
    }
    data["perturbations"] = {perturbation_key(t): _term_structure(t) for t in orbit.perturbations}
    if orbit.plane is not None:
        plane = orbit.plane
        sigma_rate = None if plane.sigma_rate is None else _zero_or_mask(plane.sigma_rate)
        data["reference_plane"] = {
            "theta_rate": _zero_or_mask(plane.theta_rate),
            "phi_rate": _zero_or_mask(plane.phi_rate),
            "sigma_rate": sigma_rate,
        }
    data["variant"] = start_variant(scene)
    return structure_text(scene, data)


def _zero_or_mask(value: Any) -> str:
    return "0" if exact_fraction(value) == 0 else _MASK


def _term_structure(term: Any) -> dict[str, Any]:
    """A disturbing term's table as its structure: the text of a potential (its literals are
    the structure's), a zonal field's degrees and axis, a perturber's kind of orbit."""
    if isinstance(term, UserPotential):
        return {"Omega": term.text}
    if isinstance(term, Zonal):
        i = term.coordinate_axis()
        if i is None:
            axis = "oblique"
        else:
            axis = ("+" if exact_fraction(term.axis[i]) > 0 else "-") + "xyz"[i]
        return {"degrees": [n for n, _ in term.coefficients], "axis": axis}
    assert isinstance(term, ThirdBody)
    return {
        "circular": term.circular,
        "moving": term.time_dependent,
        "degree": term.degree,
    }


def start_variant(scene: Scene) -> str | None:
    """The variant a Cayley run starts in (:mod:`.tilt`): tilted where sin Φ at the start is
    at most ``equatorial_limit``; None for a model without variants (:func:`hands_over`)."""
    orbit: Orbit = scene.model
    if not hands_over(orbit):
        return None
    # Asked by the structure and by the numbers of each scene: computed once a scene.
    held = _VARIANTS.get(id(scene))
    if held is not None and held[0]() is scene:
        return held[1]
    with mpmath.workdps(scene.integrator.precision.dps + GUARD_DIGITS):
        t0 = scene_mpf(start_time(scene))
        low = None
        if orbit.plane is None:
            x, v = initial_cartesian(orbit, t0)
            low = at_most(x, v, exact_fraction(orbit.equatorial_limit))
        if low is None:
            low = sin_phi(orbit, t0) <= scene_mpf(orbit.equatorial_limit)
    variant = TILTED if low else LEVEL
    with _LOCK:
        if len(_VARIANTS) >= _VARIANTS_HELD:
            _VARIANTS.pop(next(iter(_VARIANTS)))
        _VARIANTS[id(scene)] = (weakref.ref(scene), variant)
    return variant


#: The start variants of the scenes last asked about (by id, with a reference to check it).
_VARIANTS: dict[int, tuple[weakref.ref, str]] = {}
_VARIANTS_HELD = 64
_LOCK = threading.Lock()


def numbers(scene: Scene) -> Numbers:
    """The initial state and every parameter value of ``scene``'s model, in the variant it
    starts in (:func:`start_variant`).

    Raises
    ------
    SceneError
        As :func:`variant_numbers`.
    """
    return variant_numbers(scene, start_variant(scene))


def variant_numbers(scene: Scene, variant: str | None) -> Numbers:
    """The initial state and every parameter value of ``scene``'s model in ``variant`` (None:
    a model without variants).

    Raises
    ------
    SceneError
        ``orbit.elements`` / ``orbit.velocity``: an Encke orbit whose eccentricity rounds to 1
        in the run's precision.
    """
    orbit: Orbit = scene.model
    prec = scene.integrator.precision
    dps = prec.dps + GUARD_DIGITS
    values: dict[str, Any] = {"mu": orbit.mu}
    values |= plane_numbers(orbit.plane)
    for term in orbit.perturbations:
        values |= term.values(orbit.mu, dps)
    t0 = start_time(scene)
    if orbit.form.deviation:
        with mpmath.workdps(dps):
            try:
                x, v = initial_cartesian(orbit, scene_mpf(t0))
                ellipse, state = encke.start(prec, orbit.mu, x, v)
            except encke.Unbound as exc:
                raise SceneError(
                    initial_field(orbit),
                    f"{exc} at the start in {prec.name}: its eccentricity rounds to 1 in the "
                    "run's precision (a nearly radial orbit), and formulation = 'encke' follows "
                    "an osculating ellipse; use formulation = 'cartesian', or a higher precision",
                ) from None
        values |= ellipse
    else:
        state = _initial_values(orbit, t0, dps, variant)
    if orbit.form.revolutions:
        turns, state[2] = revolutions.values(prec, _text(state[2], dps))
        values |= turns
    if variant is not None:
        cos, sin = FRAME[variant]
        values["orbit.frame_cos"], values["orbit.frame_sin"] = cos, sin
        values["orbit.theta_before"] = values["orbit.sigma_before"] = "0"
    if variant is not None or "equatorial" in scene.output.events:
        values["orbit.equatorial_limit"] = orbit.equatorial_limit
    return Numbers([_state_number(prec, c, dps) for c in state], values)


def _text(value: Any, dps: int) -> str:
    return value if isinstance(value, str) else mpmath.nstr(value, dps, strip_zeros=False)


def _state_number(prec: Precision, value: Any, dps: int) -> Any:
    """An initial value (mpmath's decimal text, or an mpmath number) in the run's precision,
    as ``prec.number`` takes its text with ``dps`` digits (:func:`initial_state`)."""
    if prec.kind == "double":
        x: float | None
        if isinstance(value, str):
            # mpmath's text (digits, a point, an exponent) is the number decimal_text
            # normalises it to, and float() rounds either correctly; prec.number refuses only
            # what rounds to 0 or overflows.
            x = float(value)
        else:
            x = nearest_double(value, dps)
        if x and math.isfinite(x):
            return x
    return prec.number(_text(value, dps))


def nearest_double(value: Any, digits: int) -> float | None:
    """The double that the decimal text of ``value`` (an mpmath number) to ``digits``
    significant digits rounds to, found without the text: None where that is not proved
    (then convert the text).

    ``mpmath.nstr(y, n)`` (``libmp.to_str``, mpmath 1.3) truncates |y| to at least n + 5
    digits, which errs by under 6·10⁻⁽ⁿ⁺⁵⁾|y|, and rounds that to n digits, within half a unit
    of the n-th: the text s it writes is within 0.51·10¹⁻ⁿ|y| of y, and the bound taken here,
    10²⁻ⁿ|y| < 10²⁻ⁿ·2ᵉ for |y| < 2ᵉ, has room to spare. ``float(s)``, correctly rounded, is
    then the double nearest y wherever no rounding boundary (a midpoint between neighbouring
    doubles) lies within the bound of y. With |y| = m·2ᵏ and m = q·2ʲ + r (q of 53 bits,
    0 ≤ r < 2ʲ, half = 2ʲ⁻¹), the boundaries nearest y are q·2ʲ + half (between q and q + 1)
    and, below q, q·2ʲ − half (q·2ʲ − half/2 where q = 2⁵², the first of its binade): y is at
    least min(|r − half|, half/2)·2ᵏ from either. A y of at most 53 bits is a double, at
    least 2ᵉ⁻⁵⁵ from a boundary, beyond the bound for n ≥ 19. Only normal, finite doubles are
    taken (there the text's own checks refuse nothing).
    """
    sign, man, exp, bc = value._mpf_
    if not man:  # zero, which the text writes as 0.0; or not finite
        return 0.0 if value._mpf_ == libmp.fzero else None
    top = exp + bc  # 2^(top - 1) <= |y| < 2^top
    if not -1020 <= top <= 1023 or digits < 19:
        return None
    shift = bc - 53
    if shift <= 0:
        x = math.ldexp(int(man), exp)
    else:
        q, r = divmod(int(man), 1 << shift)
        half = 1 << (shift - 1)
        if min(abs(r - half), half >> 1) * _tens(digits - 2) <= 1 << bc:
            return None
        x = math.ldexp(q + (r > half), exp + shift)
    return -x if sign else x


@functools.lru_cache(maxsize=16)
def _tens(n: int) -> int:
    return 10**n


def plane_numbers(motion: PlaneMotion | None) -> dict[str, Any]:
    """The reference plane's parameters by name: the numbers :func:`plane_angles` builds (a
    rate that is exactly zero has none)."""
    out: dict[str, Any] = {}
    if motion is None:
        return out

    def value(name: str, v: Any) -> Any:
        out[f"reference_plane.{name}"] = v
        return scene_mpf(v)

    plane_angles(motion, mpmath.mpf(0), value)
    return out


def hands_over(orbit: Orbit) -> bool:
    """Whether a ``cayley`` orbit can reach the reference plane: Φ can change (a perturbation,
    a turning plane) and ``equatorial_limit`` is not 0."""
    if not orbit.form.angles or exact_fraction(orbit.equatorial_limit) == 0:
        return False
    plane = orbit.plane
    turning = plane is not None and (
        exact_fraction(plane.theta_rate) != 0 or exact_fraction(plane.phi_rate) != 0
    )
    return bool(orbit.perturbations) or turning


def initial_field(orbit: Orbit) -> str:
    """The scene field holding the orbit's initial state."""
    return "orbit.elements" if orbit.initial[0] == "elements" else "orbit.velocity"


def sin_phi(orbit: Orbit, t: Any) -> Any:
    """sin Φ of the osculating orbit on the reference plane at time t (mpmath)."""
    x, v = initial_cartesian(orbit, t)
    H = vectors.cross(x, v)
    h = mpmath.sqrt(vectors.dot(H, H))
    n = [c / h for c in H]
    if orbit.plane is not None:
        # On the fixed frame M₀₁ is the identity exactly, and M₀₁ᵀ n gives back n's bits
        # (each component 0 + 1·nᵢ + 0·nⱼ + 0·nₖ).
        n = vectors.matvec(vectors.transpose(_plane_matrix_at(orbit.plane, t)), n)
    return mpmath.sqrt(n[0] ** 2 + n[1] ** 2)


#: Magnitudes the double decision of :func:`at_most` takes for a coordinate: products and
#: squares of these stay normal doubles, with no overflow.
_SMALLEST, _LARGEST = 2.0**-250, 2.0**250


def at_most(x: Any, v: Any, limit: Fraction) -> bool | None:
    """Whether :func:`sin_phi` on the fixed frame, for the position and velocity ``x``, ``v``
    (mpmath numbers, mpmath working at p ≥ 53 bits), is at most ``limit`` (in (0, ¼]), as
    :func:`start_variant` compares them there: decided in double, or None where the double's
    error bound does not decide and mpmath must.

    Let S = |H₁₂|/|H| be sin Φ of the exact H = x × v, A = |x||v|/|H| ≥ 1 (the condition of
    S, large for a nearly rectilinear motion), u = 2⁻⁵³ and w = 2⁻ᵖ ≤ u. Each computed
    component of H errs by at most c·u(|xⱼvₖ| + |xₖvⱼ|) ≤ c·u|x||v| (Cauchy–Schwarz), with
    c = 4.02 in double (x and v rounded to doubles, the products, the difference; with the
    coordinates 0 or in [2⁻²⁵⁰, 2²⁵⁰] nothing overflows or leaves the normal range) and
    c = 2.01·w/u in mpmath. The computed H is then within √3·c·u|x||v| of H, its direction
    within π/2 times that over |H|, and sin Φ with it (|sin a − sin b| ≤ |a − b|): 11u·A in
    double, 5.5w·A in mpmath. Normalising and the square root add at most 4.1u in double
    (sqrt(p/q) of sums of squares; with q ≥ 2⁻⁸⁰⁰ a square that underflows does not count)
    and 6.1w in mpmath (H/h, n₁² + n₂², the square root), to values at most 1: the double s
    is within 16u·A of S, mpmath's sin Φ within 12w·A, and the limit in double and in mpmath
    (each rounded once) within u/4 of the exact one. Â = |x||v|/√q computed in double is at
    least A/2.01 where Â ≤ 2⁴⁰ (the error of H is then under a thousandth of |H|), so the
    margin 2⁻⁴⁴·Â = 512u·Â exceeds 2.01·28u·Â + 4u, the errors above with the rounding of
    s − limit: where s − limit is beyond the margin, mpmath's sin Φ is on the same side of
    its limit.
    """
    xs = [_coordinate(c) for c in x]
    vs = [_coordinate(c) for c in v]
    if None in xs or None in vs:
        return None
    H = vectors.cross(xs, vs)
    p = H[0] * H[0] + H[1] * H[1]
    q = p + H[2] * H[2]
    if not q >= 2.0**-800:
        return None
    bound = math.sqrt(vectors.dot(xs, xs)) * math.sqrt(vectors.dot(vs, vs)) / math.sqrt(q)
    if not bound <= 2.0**40:
        return None
    gap = math.sqrt(p / q) - float(limit)
    margin = bound * 2.0**-44
    if gap > margin:
        return False
    if gap < -margin:
        return True
    return None


def _coordinate(value: Any) -> float | None:
    """An mpmath number as the nearest double, if it is 0 or in [2⁻²⁵⁰, 2²⁵⁰] (None if not)."""
    if not value:
        return 0.0
    x = libmp.to_float(value._mpf_, False, libmp.round_nearest)
    return x if _SMALLEST <= abs(x) <= _LARGEST else None


def initial_cartesian(orbit: Orbit, t: Any) -> tuple[list, list]:
    """Position and velocity at the start time, in mpmath at the current precision.

    Computed once an orbit, time and precision: a scene's validation, its start variant and
    its initial state each ask.
    """
    # The result depends on t only through scene_mpf(t) at this precision (the reference
    # plane's angles), and not at all for a position and velocity in a fixed frame.
    moving = orbit.plane is not None and orbit.initial[0] == "elements"
    key = ("initial_cartesian", mpmath.mp.prec, scene_mpf(t) if moving else None)
    held = orbit.derived.get(key)
    if held is None:
        if len(orbit.derived) >= _DERIVED_HELD:
            orbit.derived.clear()
        held = orbit.derived[key] = _initial_cartesian(orbit, t)
    return held[0][:], held[1][:]


#: Derived values an orbit keeps (other times of a moving plane, other precisions).
_DERIVED_HELD = 8


def _initial_cartesian(orbit: Orbit, t: Any) -> tuple[list, list]:
    if orbit.initial[0] == "cartesian":
        _, x, v = orbit.initial
        return [scene_mpf(c) for c in x], [scene_mpf(c) for c in v]
    values = {k: scene_mpf(v) for k, v in orbit.initial[1].items()}
    return el.elements_to_cartesian(
        el.Elements(**values), scene_mpf(orbit.mu), frame=plane_angles_at(orbit.plane, t)
    )


def initial_state(orbit: Orbit, t: Any, dps: int, variant: str | None = None) -> list[str]:
    """The formulation's initial state as decimal text with ``dps`` digits (not ``encke``,
    whose state is the deviation from its initial osculating ellipse: :func:`numbers`);
    Cayley's angles on the working frame of ``variant`` (:mod:`.tilt`) if given."""
    return [_text(c, dps) for c in _initial_values(orbit, t, dps, variant)]


def _initial_values(orbit: Orbit, t: Any, dps: int, variant: str | None = None) -> list:
    """:func:`initial_state` as mpmath numbers with the guard digits of ``dps``."""
    if orbit.form.deviation:
        raise ValueError("the encke state is the deviation from its ellipse: build the model")
    with mpmath.workdps(dps):
        t = scene_mpf(t)
        x, v = initial_cartesian(orbit, t)
        if orbit.form.cartesian:
            values = [*x, *v]
        else:
            frame = plane_angles_at(orbit.plane, t)
            s = el.cartesian_to_cayley(x, v, sigma=scene_mpf(orbit.sigma0), frame=frame)
            values = [s.r, s.rdot, s.rho, s.h]
            if orbit.form.angles:
                angles = (s.Theta, s.Sigma, s.Phi)
                if variant == TILTED:
                    angles = angles_in(TILTED, *angles)
                values += list(angles)
            else:
                values += _plane_quaternion(frame, (s.Theta, s.Sigma, s.Phi))
        return values


def plane_angles(motion: PlaneMotion, t: Any, value: Any) -> tuple[tuple, tuple]:
    """(θ′, σ′, φ′) and their rates at time ``t`` (None for a rate that is exactly zero).

    ``value(name, number)`` builds each number: heyoka (``value`` allocates a parameter, ``t``
    is ``hy.time``) and mpmath alike.
    """

    def rate(name: str, v: Any) -> Any:
        # A rate that is exactly zero is left out (None), so a plane at rest compiles no
        # time terms.
        return None if exact_fraction(v) == 0 else value(name, v)

    f = frames.functions_for(t)
    th0, th1 = value("theta0", motion.theta0), rate("theta_rate", motion.theta_rate)
    ph0, ph1 = value("phi0", motion.phi0), rate("phi_rate", motion.phi_rate)
    sg0 = value("sigma0", motion.sigma0)
    theta = th0 if th1 is None else th0 + th1 * t
    phi = ph0 if ph1 is None else ph0 + ph1 * t
    if not motion.departure_point:
        sg1 = rate("sigma_rate", motion.sigma_rate)
        sigma = sg0 if sg1 is None else sg0 + sg1 * t
    elif th1 is None:
        sg1, sigma = None, sg0
    elif ph1 is None:
        sg1 = th1 * f.cos(ph0)
        sigma = sg0 + sg1 * t
    else:
        # σ′ = σ′₀ + θ̇′(sin φ′ − sin φ′₀)/φ̇′, written without the cancelling difference.
        half = ph1 * t / 2
        sigma = sg0 + 2 * th1 * f.cos(ph0 + half) * f.sin(half) / ph1
        sg1 = th1 * f.cos(phi)
    return (theta, sigma, phi), (th1, sg1, ph1)


def plane_angles_at(motion: PlaneMotion | None, t: Any) -> tuple:
    """(θ′, σ′, φ′) at time t in mpmath (zeros for the fixed frame)."""
    if motion is None:
        return (mpmath.mpf(0),) * 3
    return plane_angles(motion, scene_mpf(t), lambda _, v: scene_mpf(v))[0]


def _plane_matrix_at(motion: PlaneMotion | None, t: Any) -> frames.Matrix:
    return frames.plane_matrix(*plane_angles_at(motion, t))


def _plane_quaternion(frame: tuple, angles: tuple) -> list:
    """q of M₀₂ = M(θ′, σ′, φ′) M(Θ, Σ, Φ) as a product of axis quaternions
    (docs/orbits.md, "The quaternion formulation")."""

    def axis(k: int, a: Any) -> list:
        q = [mpmath.cos(a / 2), mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)]
        q[k] = mpmath.sin(a / 2)
        return q

    q = [mpmath.mpf(1), mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0)]
    for theta, sigma, phi in (frame, angles):
        for factor in (axis(3, theta), axis(1, phi), axis(3, -sigma)):
            q = _hamilton(q, factor)
    return q


def _hamilton(a: list, b: list) -> list:
    return [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]


def start_time(scene: Scene) -> Any:
    grid = scene.output
    return grid.times[0] if grid.times is not None else grid.grid[0]
