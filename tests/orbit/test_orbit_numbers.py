"""The short cuts of an orbit's numbers (cayley_heyoka.orbit.numbers) give the bits of the
computations they stand for: a double from an mpmath number without its decimal text, the
start variant decided from doubles, the fixed frame's rotation left out, cos and sin of an
angle at once, the start's position and velocity computed once an orbit. Near the edges where
each stops deciding (a double rounding boundary, sin Φ at the limit, a nearly rectilinear
orbit) the long way is taken: there the text's double is not always the nearest one."""

from __future__ import annotations

import copy
import random
import struct
from types import SimpleNamespace
from typing import Any

import mpmath
import pytest

import cayley_heyoka as ch
from cayley_heyoka.core import vectors
from cayley_heyoka.core.precision import Precision, exact_fraction, rational_mpf
from cayley_heyoka.mechanics import frames, kepler
from cayley_heyoka.orbit import numbers
from cayley_heyoka.orbit.tilt import LEVEL, TILTED

DOUBLE = Precision("double")
#: The working digits of a double run's numbers (the precision's and the guard digits).
DPS = DOUBLE.dps + numbers.GUARD_DIGITS
J2 = {"zonal": {"J2": "1e-3", "radius": "0.5"}}


def bits(x: float) -> bytes:
    return struct.pack("<d", x)


def text_double(y: Any, digits: int) -> float:
    """What the initial state's double was taken from: the text, read by the precision."""
    return DOUBLE.number(mpmath.nstr(y, digits, strip_zeros=False))


# ---------------------------------------------------------------------- a double from mpmath
def test_nearest_double_is_the_double_of_the_text() -> None:
    rng = random.Random(33)
    decided = 0
    cases = 0
    for prec in (64, 113, 130, 200, 400):
        for _ in range(400):
            digits = rng.choice([19, 20, 25, 33, 38, 60])
            man = rng.getrandbits(prec) | (1 << (prec - 1))
            exp = rng.randint(-1100, 1100) - prec
            y = mpmath.mpf((rng.choice([1, -1]) * man, exp))
            got = numbers.nearest_double(y, digits)
            cases += 1
            if got is not None:
                decided += 1
                assert bits(got) == bits(text_double(y, digits)), (y, digits)
    # Outside double's normal range (about a fifth of the exponents drawn) the text decides.
    assert decided > 0.75 * cases
    assert numbers.nearest_double(mpmath.mpf(0), DPS) == 0.0
    assert numbers.nearest_double(mpmath.inf, DPS) is None
    assert numbers.nearest_double(mpmath.nan, DPS) is None
    assert numbers.nearest_double(mpmath.mpf("0.1"), 18) is None  # too few digits to prove


@pytest.mark.parametrize("prec", [113, 200])
def test_nearest_double_leaves_the_boundaries_to_the_text(prec: int) -> None:
    """Values within 2⁻ʲ of a midpoint between two doubles: far from it the short cut
    decides, as the text does; near it, where the text's own rounding can land across (and
    does, for some), it declines."""
    rng = random.Random(prec)
    across = 0
    for _ in range(60):
        q = rng.getrandbits(53) | (1 << 52)
        e = rng.randint(-60, 60)
        for j in range(2, prec - 54):
            for side in (1, -1):
                # Between q·2ᵉ and (q + 1)·2ᵉ, 2⁻ʲ of a unit from their midpoint (exactly:
                # the mantissa has 54 + j ≤ prec bits).
                with mpmath.workprec(prec):
                    y = mpmath.mpf((((2 * q + 1) << j) + side, e - 1 - j))
                got = numbers.nearest_double(y, DPS)
                text = text_double(y, DPS)
                nearest = float(mpmath.mpf((q + (side > 0), e)))
                if j < 40:
                    assert got is not None and bits(got) == bits(text) == bits(nearest)
                elif j > 115:  # within the text's 10⁻³² of the midpoint
                    assert got is None
                    across += bits(text) != bits(nearest)
                if got is not None:
                    assert bits(got) == bits(text)
    if prec > 170:
        assert across > 0  # the text's double is not always the nearest one


# ---------------------------------------------------------------------- the start variant
def reference_at_most(x: list, v: list, limit: str) -> bool:
    """sin Φ ≤ limit as the start variant is decided in mpmath, the fixed frame's M₀₁ᵀ
    applied as for any other frame."""
    zero = mpmath.mpf(0)
    H = vectors.cross(x, v)
    h = mpmath.sqrt(vectors.dot(H, H))
    M01T = vectors.transpose(frames.plane_matrix(zero, zero, zero))
    n = vectors.matvec(M01T, [c / h for c in H])
    return mpmath.sqrt(n[0] ** 2 + n[1] ** 2) <= rational_mpf(exact_fraction(limit))


def near_limit(limit: str, eta: Any, psi: float, speed: str = "1.1", radial: str = "0.3"):
    """Position and velocity (40-digit text) whose orbit has sin Φ = limit·(1 + eta), its
    node at longitude ψ."""
    with mpmath.workdps(60):
        s = mpmath.mpf(limit) * (1 + mpmath.mpf(eta))
        c = mpmath.sqrt(1 - s * s)
        n = [s * mpmath.sin(psi), -s * mpmath.cos(psi), c]
        xhat = [mpmath.cos(psi), mpmath.sin(psi), mpmath.mpf(0)]
        x = [mpmath.mpf("0.9") * a for a in xhat]
        along = vectors.cross(n, xhat)
        v = [
            mpmath.mpf(speed) * b + mpmath.mpf(radial) * a for a, b in zip(xhat, along, strict=True)
        ]
        return [mpmath.nstr(a, 40) for a in x], [mpmath.nstr(b, 40) for b in v]


def orbit_scene(position: list, velocity: list, limit: str) -> ch.Scene:
    return ch.Scene.from_dict(
        {
            "orbit": {
                "mu": "1",
                "position": position,
                "velocity": velocity,
                "formulation": "cayley",
                "equatorial_limit": limit,
            },
            "perturbations": copy.deepcopy(J2),
            "output": {"times": {"start": "0", "stop": "1", "count": 2}},
        }
    )


def decide(position: list, velocity: list, limit: str) -> tuple[bool | None, bool, str]:
    """The double decision, the mpmath one, and the scene's start variant."""
    with mpmath.workdps(DPS):
        x = [mpmath.mpf(a) for a in position]
        v = [mpmath.mpf(b) for b in velocity]
        quick = numbers.at_most(x, v, exact_fraction(limit))
        slow = reference_at_most(x, v, limit)
    return quick, slow, numbers.start_variant(orbit_scene(position, velocity, limit))


@pytest.mark.parametrize("limit", ["1e-3", "0.25", "1e-100", "0.0123456789"])
def test_start_variant_near_its_limit(limit: str) -> None:
    """sin Φ = limit·(1 ± 10⁻ᵏ): decided in double down to about 10⁻¹⁰ of the limit, left to
    mpmath within 10⁻¹⁶ of it; every answer is mpmath's."""
    rng = random.Random(limit)
    for k in range(1, 31):
        for sign in (1, -1):
            psi = rng.uniform(-3, 3)
            position, velocity = near_limit(limit, f"{sign}e-{k}", psi)
            quick, slow, variant = decide(position, velocity, limit)
            assert variant == (TILTED if slow else LEVEL)
            assert slow == (sign < 0)  # the orbit is on the side it was built on
            if quick is not None:
                assert quick == slow
            if limit != "1e-100":
                # 10⁻¹⁰ of 10⁻¹⁰⁰ is beyond any double's reach next to the 10⁻¹⁶ of 1.
                if k <= 10:
                    assert quick is not None
            if k >= 16:
                assert quick is None


def test_start_variant_of_random_and_ill_conditioned_orbits() -> None:
    """Random orbits, and nearly rectilinear ones (|x × v| ≪ |x||v|, where sin Φ loses
    digits in both arithmetics): the double decides only where its bound allows, as mpmath."""
    rng = random.Random(7)
    decided = 0
    for k in range(300):
        limit = rng.choice(["1e-3", "0.01", "0.25", f"{rng.uniform(1e-4, 0.25):.6g}"])
        position = [f"{rng.uniform(-1.5, 1.5):.17g}" for _ in range(3)]
        if k % 3 == 0:  # a nearly radial velocity
            scale = 10.0 ** -rng.randint(4, 15)
            velocity = [f"{float(p) * 0.7 + scale * rng.uniform(-1, 1):.17g}" for p in position]
        else:
            velocity = [f"{rng.uniform(-1, 1):.17g}" for _ in range(3)]
        if k % 5 == 0:  # near the reference plane
            position[2] = f"{rng.uniform(-1e-3, 1e-3):.17g}"
            velocity[2] = f"{rng.uniform(-1e-3, 1e-3):.17g}"
        quick, slow, variant = decide(position, velocity, limit)
        assert variant == (TILTED if slow else LEVEL)
        if quick is not None:
            decided += 1
            assert quick == slow
    assert decided > 200


# ---------------------------------------------------------------------- the fixed frame
def test_the_fixed_frame_rotates_nothing() -> None:
    """M₀₁ᵀ x with M₀₁(0, 0, 0) is x rounded to the working precision, bit for bit, also for
    an x of more bits than that; and Cayley's state and sin Φ are those of the rotation."""
    rng = random.Random(1)
    zero = mpmath.mpf(0)
    with mpmath.workdps(DPS):
        kind, _ = kepler._prepare([("x", zero)])
        M01T = vectors.transpose(frames.plane_matrix(zero, zero, zero))
        for _ in range(200):
            with mpmath.workprec(rng.choice([60, 113, 300])):
                x = [mpmath.mpf(rng.uniform(-2, 2)) / 3 for _ in range(3)]
            assert kepler._on_reference(kind, (zero, zero, zero), x) == vectors.matvec(M01T, x)
            assert [c._mpf_ for c in kepler._on_reference(kind, (0, 0, 0), x)] == [
                c._mpf_ for c in vectors.matvec(M01T, x)
            ]


def test_cayley_state_and_sin_phi_on_the_fixed_frame(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = random.Random(2)
    cases = []
    with mpmath.workdps(DPS):
        for _ in range(100):
            x = [mpmath.mpf(f"{rng.uniform(-2, 2):.20g}") for _ in range(3)]
            v = [mpmath.mpf(f"{rng.uniform(-1, 1):.20g}") for _ in range(3)]
            cases.append((x, v, kepler.cartesian_to_cayley(x, v, sigma=mpmath.mpf("0.3"))))
    monkeypatch.setattr(
        kepler,
        "_on_reference",
        lambda kind, frame, x: vectors.matvec(vectors.transpose(kepler.plane_matrix(*frame)), x),
    )
    with mpmath.workdps(DPS):
        for x, v, quick in cases:
            slow = kepler.cartesian_to_cayley(x, v, sigma=mpmath.mpf("0.3"))
            for name in ("r", "rdot", "rho", "h", "Theta", "Sigma", "Phi"):
                assert getattr(quick, name)._mpf_ == getattr(slow, name)._mpf_
    for x, v, _ in cases[:20]:
        position, velocity = [mpmath.nstr(c, 25) for c in x], [mpmath.nstr(c, 25) for c in v]
        orbit = orbit_scene(position, velocity, "1e-3").model
        with mpmath.workdps(DPS):
            x, v = numbers.initial_cartesian(orbit, 0)
            zero = mpmath.mpf(0)
            H = vectors.cross(x, v)
            h = mpmath.sqrt(vectors.dot(H, H))
            M01T = vectors.transpose(frames.plane_matrix(zero, zero, zero))
            n = vectors.matvec(M01T, [c / h for c in H])
            want = mpmath.sqrt(n[0] ** 2 + n[1] ** 2)
            assert numbers.sin_phi(orbit, 0)._mpf_ == want._mpf_


@pytest.mark.parametrize("prec", [53, 113, 200, 1000])
def test_cos_sin_is_cos_and_sin(prec: int) -> None:
    """mpmath's cos_sin, which the frames and Kepler's equation take in mpmath, gives the bits
    of cos and sin: for tiny, ordinary, large and huge angles."""
    rng = random.Random(prec)
    with mpmath.workprec(prec):
        angles = [mpmath.mpf(0), mpmath.mpf(2) ** -2000, mpmath.pi / 2, -mpmath.pi]
        angles += [mpmath.mpf(rng.uniform(-4, 4)) * mpmath.mpf(10) ** rng.randint(-40, 40)]
        angles += [mpmath.mpf(rng.uniform(-4, 4)) for _ in range(50)]
        for a in angles:
            c, s = mpmath.cos_sin(a)
            assert (c._mpf_, s._mpf_) == (mpmath.cos(a)._mpf_, mpmath.sin(a)._mpf_)
            f = frames.functions_for(a)
            assert [x._mpf_ for x in f.cos_sin(a)] == [c._mpf_, s._mpf_]


# ---------------------------------------------------------------------- once an orbit
def test_initial_cartesian_once_an_orbit_time_and_precision() -> None:
    elements = {
        "a": "1",
        "e": "0.3",
        "inclination": "0.5",
        "node": "0.2",
        "argument_of_pericentre": "0.3",
        "mean_anomaly": "1",
    }
    scene = ch.Scene.from_dict(
        {
            "orbit": {"mu": "1", "elements": elements},
            "reference_plane": {"phi_rate": "0.05"},
            "output": {"times": {"start": "0", "stop": "1", "count": 2}},
        }
    )
    orbit = scene.model
    for dps in (20, DPS, 50):
        with mpmath.workdps(dps):
            for t in (0, "0.5", mpmath.mpf(1)):
                x, v = numbers.initial_cartesian(orbit, t)
                want = numbers._initial_cartesian(orbit, t)
                assert [c._mpf_ for c in x + v] == [c._mpf_ for c in want[0] + want[1]]
                x[0] = v[0] = mpmath.mpf(7)  # the caller's lists, not the orbit's
                again = numbers.initial_cartesian(orbit, t)
                assert again[0] == list(want[0]) and again[1] == list(want[1])
    with mpmath.workdps(DPS):
        assert numbers.initial_cartesian(orbit, 0) != numbers.initial_cartesian(orbit, 1)
    with mpmath.workdps(20):
        low = numbers.initial_cartesian(orbit, 0)[0][0]
    with mpmath.workdps(50):
        high = numbers.initial_cartesian(orbit, 0)[0][0]
    assert low != high


# ---------------------------------------------------------------------- all of them
def _number(rng: random.Random, lo: float, hi: float) -> str:
    return f"{rng.uniform(lo, hi):.{rng.choice([3, 6, 17, 25])}g}"


def random_scene(rng: random.Random) -> dict:
    formulation = rng.choice(["cayley", "cayley", "quaternion", "cartesian", "encke"])
    orbit: dict[str, Any] = {"mu": _number(rng, 0.5, 2), "formulation": formulation}
    near = rng.random() < 0.3
    if rng.random() < 0.5:
        orbit["elements"] = {
            "a": _number(rng, 0.5, 3),
            "e": _number(rng, 0, 0.9),
            "inclination": _number(rng, 0, 2e-3) if near else _number(rng, 0, 3.1),
            "node": _number(rng, -4, 4),
            "argument_of_pericentre": _number(rng, -4, 4),
            "mean_anomaly": _number(rng, -10, 10),
        }
    else:
        z = 1e-3 if near else 1
        orbit["position"] = [_number(rng, -1.5, 1.5), _number(rng, -1.5, 1.5), _number(rng, -z, z)]
        orbit["velocity"] = [_number(rng, -1, 1), _number(rng, -1, 1), _number(rng, -z, z)]
    if formulation in ("cayley", "quaternion") and rng.random() < 0.4:
        orbit["sigma0"] = _number(rng, -3, 3)
    if rng.random() < 0.4:
        orbit["equatorial_limit"] = rng.choice(["0", "1e-3", "0.2", _number(rng, 1e-4, 0.25)])
    d: dict[str, Any] = {
        "orbit": orbit,
        "output": {"times": {"start": rng.choice(["0", "-1.25"]), "stop": "3", "count": 2}},
    }
    if rng.random() < 0.6:
        d["perturbations"] = copy.deepcopy(J2)
    if rng.random() < 0.3:
        d["reference_plane"] = {"theta0": _number(rng, -1, 1), "phi_rate": _number(rng, -0.1, 0.1)}
    if rng.random() < 0.2:
        d["integrator"] = {"precision": rng.choice(["quad", {"bits": 128}])}
    return d


def _shown(x: Any) -> str:
    return x.hex() if isinstance(x, float) else f"{type(x).__name__}:{x!r}"


def _numbers_of(data: list[dict]) -> list[Any]:
    out = []
    for d in data:
        try:
            scene = ch.Scene.from_dict(copy.deepcopy(d))
        except ch.SceneError as exc:
            out.append(str(exc))
            continue
        given = numbers.numbers(scene)
        out.append(
            (
                numbers.structure(scene),
                [_shown(x) for x in given.initial_state],
                {k: _shown(v) for k, v in given.values.items()},
            )
        )
    return out


def test_numbers_of_random_orbits_as_the_long_way(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every short cut off (each double from its text, the variant from mpmath, the fixed
    frame rotated, the start computed at each ask, cos and sin apart): the same structures and
    numbers, bit for bit, in double, quad and multiprecision."""
    rng = random.Random(12)
    data = [random_scene(rng) for _ in range(80)]
    quick = _numbers_of(data)
    monkeypatch.setattr(numbers, "nearest_double", lambda value, digits: None)
    monkeypatch.setattr(
        numbers, "_state_number", lambda prec, value, dps: prec.number(numbers._text(value, dps))
    )
    monkeypatch.setattr(numbers, "at_most", lambda x, v, limit: None)
    monkeypatch.setattr(
        numbers,
        "initial_cartesian",
        numbers._initial_cartesian,
    )
    monkeypatch.setattr(
        kepler,
        "_on_reference",
        lambda kind, frame, x: vectors.matvec(vectors.transpose(kepler.plane_matrix(*frame)), x),
    )
    each = frames.functions_for

    def apart(*values: Any) -> SimpleNamespace:
        f = each(*values)
        return SimpleNamespace(**{**vars(f), "cos_sin": lambda a: (f.cos(a), f.sin(a))})

    monkeypatch.setattr(frames, "functions_for", apart)
    monkeypatch.setattr(kepler, "functions_for", apart)
    slow = _numbers_of(data)
    assert sum(isinstance(q, tuple) for q in quick) > 70
    assert quick == slow
