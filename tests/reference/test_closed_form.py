"""The closed-form free rigid body against the 25-digit reference values and against itself.

Values: 25 digits of the closed form computed independently at 50 digits and confirmed by a
quad-precision Taylor integration, kept below.
"""

from __future__ import annotations

import mpmath
import pytest

from cayley_heyoka.core.accuracy import certify
from cayley_heyoka.reference import FreeRigidBody, PrecisionNotReached, free_rigid_body
from cayley_heyoka.rotation.attitude import quaternion_to_matrix

CASES = {
    "1": {  # major axis (C largest)
        "inertia": ("1", "1.5", "2.5"),
        "rates": ("0.125", "0.25", "1"),
        "t": "10",
        "p": "0.03701005140819792930314192",
        "q": "-0.2770473896191092908781587",
        "r": "0.9985734568778841172878553",
        "phi": "0.01425525609476254647016710",
        "psi": "10.21730164715751540734054",
        "nu0": "-2.390092871587000921892715",
        "lambda0": "-0.1002544949724092960912453",
        "mu0": "0.1902029234444625537810625",
        "h": "2.609375000000000000000000",
        "k": "2.531057091414573366655863",
        "m": "0.01543209876543209876543210",
        "period": "6.268581733982502710048354",
        "psi_increment": "6.404793050753033757941550",
    },
    "2": {  # minor axis (A smallest)
        "inertia": ("1", "1.5", "2.5"),
        "rates": ("1", "0.1875", "0.25"),
        "t": "12.5",
        "p": "0.9081804870265588525008913",
        "q": "-0.4586550479218585552298852",
        "r": "0.1657056408308405367168351",
        "phi": "0.1752082029842023678024533",
        "psi": "14.34219064198322012199627",
        "nu0": "1.229337411019955974857845",
        "lambda0": "0.2634213254742426020622825",
        "mu0": "-1.078296648331565776955060",
        "h": "1.208984375000000000000000",
        "k": "1.212322796329426447529853",
        "m": "0.3358490566037735849056604",
        "period": "15.25667676181130599763690",
        "psi_increment": "16.62937704102276594983964",
    },
    "3": {  # near separatrix, k^2 > B h
        "inertia": ("1", "2", "4"),
        "rates": ("0.353515625", "1", "0.125"),
        "t": "20",
        "p": "-0.1188316517811490544189771",
        "q": "-1.040739761775525836866903",
        "r": "0.04205303845427765317846974",
        "phi": "0.05542616782705217988120718",
        "psi": "19.58646947796283588510129",
        "nu0": "0.3860888415540709385255673",
        "lambda0": "-0.9413693845242142546937643",
        "mu0": "-0.3030301114758499011952187",
        "h": "2.187473297119140625000000",
        "k": "2.091643683116017881040434",
        "m": "0.9999816894531250000000000",
        "period": "36.99929960692085259195150",
        "psi_increment": "36.23264736073909059695503",
    },
    "4": {  # near separatrix, k^2 < B h
        "inertia": ("1", "2", "4"),
        "rates": ("0.3536376953125", "1", "0.125"),
        "t": "15",
        "p": "1.199755217912417413724303",
        "q": "-0.1193116820701070020919138",
        "r": "-0.4241687405034309588277103",
        "phi": "-0.6571764816810678048773050",
        "psi": "18.41625481103854140468570",
        "nu0": "-0.2201051047057250176249989",
        "lambda0": "-1.272681413497601418296978",
        "mu0": "-2.904465600736079107545848",
        "h": "2.187559619545936584472656",
        "k": "2.091664318084031519168841",
        "m": "0.9999591196969109875046082",
        "period": "34.82657257151276784732468",
        "psi_increment": "40.24424495390832989492924",
    },
    "5": {  # nearly symmetric, B = A + 2^-20
        "inertia": ("1", "1.00000095367431640625", "1.75"),
        "rates": ("0.5", "0.375", "1.25"),
        "t": "20",
        "p": "0.5348028498582591933490689",
        "q": "0.3234360838479013029952452",
        "r": "1.250000010467277558845814",
        "phi": "-0.04801884534780698265455853",
        "psi": "26.75068739063758727779966",
        "nu0": "1.048297389964720842451613",
        "lambda0": "0.1981091328848386306841161",
        "mu0": "-0.04386416006451705302512804",
        "h": "3.125000134110450744628906",
        "k": "2.275034399348948171185100",
        "m": "1.816524490594279002138283e-7",
        "period": "6.702071869736016248392140",
        "psi_increment": "8.964251472833606293894557",
    },
    "6": {  # C intermediate (A > C > B)
        "inertia": ("2.5", "1", "1.75"),
        "rates": ("0.5", "-0.75", "0.625"),
        "t": "8",
        "p": "0.1762150868396231963175924",
        "q": "0.1230015937894296575196216",
        "r": "-1.008063196956143300424109",
        "phi": "0.7298274772336801860054467",
        "psi": "6.616502345604230056625799",
        "nu0": "0.1682188402831881917506973",
        "lambda0": "3.379203639073671863888878",
        "mu0": "-7.197802712981020955886950",
        "h": "1.871093750000000000000000",
        "k": "1.822440413977916590473370",
        "m": "0.9353535353535353535353535",
        "period": "22.34287911001530219924638",
        "psi_increment": "20.87720705604533257503321",
    },
    "7": {  # generic, negative components, many periods
        "inertia": ("0.75", "1.25", "2"),
        "rates": ("-0.5", "0.625", "-0.875"),
        "t": "30",
        "p": "0.4779119451527790979974745",
        "q": "0.6420476405067516975541129",
        "r": "-0.8719088007526522462148617",
        "phi": "0.02160017268028706321802123",
        "psi": "83.71784422784718890878176",
        "nu0": "1.621642095802462592209878",
        "lambda0": "6.621268377451328484693534",
        "mu0": "4.512217821806508601448420",
        "h": "2.207031250000000000000000",
        "k": "1.952812474995999199820757",
        "m": "0.1855203619909502262443439",
        "period": "7.113739968669692480213665",
        "psi_increment": "20.08679728914509536784258",
    },
}
STATE = ("p", "q", "r", "phi", "psi", "nu0", "lambda0", "mu0")
CONSTANTS = ("h", "k", "m", "period", "psi_increment")
# The references carry 25 significant digits.
REF = mpmath.mpf("1e-24")


def scaled(value, ref) -> mpmath.mpf:
    ref = mpmath.mpf(ref)
    return abs(value - ref) / max(1, abs(ref))


def body(case: dict, **kw) -> FreeRigidBody:
    # Cases 3-4 use A, B, C = 1, 2, 4: no rigid body has them, Euler's equations don't mind.
    return FreeRigidBody(case["inertia"], case["rates"], require_physical=False, **kw)


@pytest.fixture(autouse=True)
def _digits():
    with mpmath.workdps(60):
        yield


@pytest.mark.parametrize("name", sorted(CASES))
def test_reference_values(name):
    case = CASES[name]
    b = body(case)
    state = b.at(case["t"])
    for key in STATE:
        assert scaled(getattr(state, key), case[key]) < REF, key
    for key in CONSTANTS:
        assert scaled(getattr(b, key), case[key]) < REF, key
    assert state.error < mpmath.mpf("1e-30")


def test_entry_point_matches_class():
    case = CASES["1"]
    s = free_rigid_body(case["inertia"], case["rates"], case["t"], dps=30)
    assert scaled(s.psi, case["psi"]) < REF
    assert set(s.errors) >= set(STATE)


def test_higher_precision_is_consistent():
    case = CASES["7"]
    s30, s60 = body(case).at(case["t"]), body(case, dps=60).at(case["t"])
    assert s60.error < mpmath.mpf("1e-60")
    for key in STATE:
        assert scaled(getattr(s30, key), getattr(s60, key)) < mpmath.mpf("1e-29"), key


@pytest.mark.parametrize("name", ["3", "6"])
@pytest.mark.parametrize("form", ["time", "phi", "r"])
def test_psi_quadratures_match_elliptic_pi(name, form):
    """Cayley's three quadratures for 2 tan⁻¹ν₀ against the Π(n; χ|m) closed form."""
    case = CASES[name]
    b = body(case)
    psi, error = b.psi_by_quadrature(case["t"], form)
    assert error < mpmath.mpf("1e-30")
    assert scaled(psi, b.at(case["t"]).psi) < mpmath.mpf("1e-30")


def test_quadrature_route_matches_jacobi_route():
    """t(χ) inverted by Newton + the φ-form for Ψ: no Jacobi function, no Π."""
    case = CASES["6"]
    b = body(case)
    jac, quad = b.at(case["t"]), b.at(case["t"], method="quadrature")
    for key in ("p", "q", "r", "phi", "psi"):
        assert scaled(getattr(quad, key), getattr(jac, key)) < mpmath.mpf("1e-30"), key


@pytest.mark.parametrize(
    "inertia, nearly",
    [
        (("1", "1", "2"), ("1", "1.00000000000000000000000000001", "2")),
        (("1", "2", "2"), ("1", "2", "2.00000000000000000000000000001")),
        (("2", "1", "2"), ("2.00000000000000000000000000001", "1", "2")),
    ],
)
def test_symmetric_limits(inertia, nearly):
    """Exact A = B, B = C, C = A against the general formula 1e-29 away (error O(1e-29·t))."""
    rates = ("0.3", "-0.4", "0.7")
    exact, general = FreeRigidBody(inertia, rates), FreeRigidBody(nearly, rates)
    assert exact.kind == "symmetric" and general.kind == "asymmetric"
    for t in ("3.7", "-12.1", "40"):
        s, g = exact.at(t), general.at(t)
        for key in ("p", "q", "r", "phi", "psi"):
            assert scaled(getattr(s, key), getattr(g, key)) < mpmath.mpf("1e-26"), (t, key)
        for x, y in zip(s.quaternion, g.quaternion, strict=True):
            assert abs(x - y) < mpmath.mpf("1e-26")
    for axis in ("x1", "y1", "z1"):
        a, b = exact.crossing_times(axis, 0, 30), general.crossing_times(axis, 0, 30)
        assert [c.direction for c in a] == [c.direction for c in b]
        assert all(abs(c.time - d.time) < mpmath.mpf("1e-26") for c, d in zip(a, b, strict=True))


def test_steady_rotation():
    b = FreeRigidBody(("1", "2", "3"), ("0", "0", "1.5"))
    assert b.kind == "steady"
    s = b.at("5")
    assert (s.p, s.q, s.r) == (0, 0, mpmath.mpf("1.5"))
    assert s.psi == mpmath.mpf("1.5") * 5  # (h + kr)/(k + Cr) = r
    # About −z₁ the body is a half-turn from the invariable frame: k + Cr = 0, ν₀ undefined.
    with pytest.raises(ValueError, match="half-turn from the invariable frame"):
        FreeRigidBody(("1", "2", "3"), ("0", "0", "-1.5"))
    spin = FreeRigidBody(("1", "2", "3"), ("0.5", "0", "0"))
    assert spin.crossing_times("y1", 0, 100) == []
    assert spin.at("2").psi == mpmath.mpf("2") * spin.at("1").psi


def test_flow_property_with_general_attitude():
    """Starting again from the state at t₀ (rates and attitude) reaches the same state later.

    This exercises the composition with the constant space-side rotation (l, m, n), the
    azimuth convention ν₀(0) = 0 and the continuity of the quaternion, for t₀ of both signs.
    """
    inertia = ("0.75", "1.25", "2")
    first = FreeRigidBody(inertia, ("-0.5", "0.625", "-0.875"), rodrigues=("0.3", "-1.2", "2"))
    for t0, t1 in (("-4.5", "11.25"), ("7", "-9.5")):
        s0 = first.at(t0)
        again = FreeRigidBody(inertia, s0.rates, attitude=s0.quaternion)
        a, b = again.at(t1), first.at(mpmath.mpf(t0) + mpmath.mpf(t1))
        for key in ("p", "q", "r"):
            assert abs(getattr(a, key) - getattr(b, key)) < mpmath.mpf("1e-30")
        for x, y in zip(a.quaternion, b.quaternion, strict=True):
            assert abs(x - y) < mpmath.mpf("1e-30")


def test_space_momentum_is_constant():
    inertia = ("0.75", "1.25", "2")
    b = FreeRigidBody(inertia, ("-0.5", "0.625", "-0.875"), attitude=("0.6", "0", "0.8", "0"))
    moments = [mpmath.mpf(x) for x in inertia]
    for t in ("0", "3.3", "-21", "1000"):
        s = b.at(t)
        R = quaternion_to_matrix(s.quaternion)
        L = [moments[j] * s.rates[j] for j in range(3)]
        for i in range(3):
            assert abs(sum(R[i][j] * L[j] for j in range(3)) - b.momentum_space[i]) < 1e-30


@pytest.mark.parametrize(
    ("inertia", "t_stop"), [(("1", "2", "3"), "1e300"), (("1", "1", "1.5"), "1e400")]
)
def test_crossing_window_too_long_is_refused_before_listing(inertia, t_stop):
    """10^300 time units hold ~10^299 crossings: listing them never ended."""
    b = FreeRigidBody(inertia, ("0.25", "-0.15", "1.2"))
    with pytest.raises(ValueError, match=r"t_stop: .* crossings, more than 1000000"):
        b.crossing_times("y1", 0, t_stop)


@pytest.mark.parametrize("name", ["1", "4", "6"])
def test_crossing_times(name):
    case = CASES[name]
    b = body(case)
    T = b.period
    for index, axis in enumerate(("x1", "y1", "z1")):
        crossings = b.crossing_times(axis, -T, 3 * T)
        # An oscillating component vanishes twice a period; the dn component never.
        assert len(crossings) in (0, 8), (axis, len(crossings))
        for c in crossings:
            assert -T <= c.time <= 3 * T
            assert c.error < mpmath.mpf("1e-30")
            assert abs(b.at(c.time).rates[index]) < mpmath.mpf("1e-30")
            later = b.at(c.time + T / 1000).rates[index]
            assert (later > 0) == (c.direction > 0)
        assert [c.direction for c in crossings] == [
            crossings[0].direction * (-1) ** i for i in range(len(crossings))
        ]
    total = sum(len(b.crossing_times(a, 0, 10 * T)) for a in ("x1", "y1", "z1"))
    assert total == 40


@pytest.mark.parametrize("distance", ["1e-6", "1e-10", "1e-14", "-1e-14"])
def test_next_to_the_separatrix(distance):
    """States 1e-14 from the separatrix are certified: the lost digits become working digits."""
    A, B, C = 1, 2, 3
    p, q, d = mpmath.mpf("0.5"), mpmath.mpf("0.2"), mpmath.mpf(distance)

    def off(r):
        h = A * p * p + B * q * q + C * r * r
        k2 = A * A * p * p + B * B * q * q + C * C * r * r
        return (h * B - k2) / k2 - d

    r = float(mpmath.findroot(off, 0.288))
    b = FreeRigidBody((A, B, C), (0.5, 0.2, r))
    assert abs(b.separatrix_distance / d - 1) < 0.01
    s = b.at(3 * b.period + 1)
    assert s.error < mpmath.mpf("1e-30")
    # Energy and |L|² from the returned rates: their defects bound the rates' error.
    h = A * s.p**2 + B * s.q**2 + C * s.r**2
    k2 = (A * s.p) ** 2 + (B * s.q) ** 2 + (C * s.r) ** 2
    assert abs(h - b.h) < 1e-30 and abs(k2 - b.k**2) < 1e-30


def test_many_periods_add_whole_increments():
    case = CASES["7"]
    b = body(case)
    n = 10**6
    s0, s1 = b.at(case["t"]), b.at(mpmath.mpf(case["t"]) + n * b.period)
    assert scaled(s1.psi - s0.psi, n * b.psi_increment) < mpmath.mpf("1e-30")
    assert abs(s1.p - s0.p) < mpmath.mpf("1e-30")


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        (
            dict(inertia=("1", "-2", "3"), rates=("1", "1", "1")),
            "inertia: the principal moments must be > 0",
        ),
        (dict(inertia=("1", "2", "4"), rates=("1", "1", "1")), "triangle inequality"),
        (dict(inertia=("1", "2", "nan"), rates=("1", "1", "1")), r"inertia\[2\] must be finite"),
        (
            dict(inertia=("1", "2", "3"), rates=("0", "0", "0")),
            "rates: the angular velocity is zero",
        ),
        (dict(inertia=("1", "2"), rates=("1", "1", "1")), "inertia: expected a sequence of three"),
        (dict(inertia=("1", "2", "3"), rates=("1", "x", "1")), r"rates\[1\]: 'x' is not a number"),
        (
            dict(inertia=("1", "2", "3"), rates=("1", "1", "1"), dps=3),
            "dps must be an integer in 5 … 1000",
        ),
        (
            dict(inertia=("1", "2", "3"), rates=("1", "1", "1"), dps=10**4),
            "dps must be an integer in 5 … 1000",
        ),
        (
            dict(inertia=("1", "2", "3"), rates=("1", "1", "1"), attitude=("1", "0", "0", "0.1")),
            "attitude: quaternion must have unit norm",
        ),
        (
            dict(
                inertia=("1", "2", "3"),
                rates=("1", "1", "1"),
                attitude=("1", "0", "0", "0"),
                rodrigues=("0", "0", "0"),
            ),
            "at most one",
        ),
    ],
)
def test_bad_input(kwargs, fragment):
    with pytest.raises(ValueError, match=fragment):
        FreeRigidBody(**kwargs)


def test_bad_arguments_of_methods():
    b = FreeRigidBody(("1", "2", "3"), ("1", "1", "1"))
    with pytest.raises(ValueError, match="axis must be one of"):
        b.crossing_times("z", 0, 1)
    with pytest.raises(ValueError, match="t_stop must be >= t_start"):
        b.crossing_times("x1", 1, 0)
    with pytest.raises(ValueError, match="t must be finite"):
        b.at("inf")
    with pytest.raises(ValueError, match="form must be"):
        b.psi_by_quadrature("1", "u")
    with pytest.raises(ValueError, match="method='quadrature' needs"):
        FreeRigidBody(("1", "1", "1.5"), ("1", "1", "1")).at("1", method="quadrature")


def test_absurd_spans_are_refused_at_once():
    """A time 10²⁰⁰⁰⁰ periods away would be computed at 20 000 digits, the quadratures are slow
    long before: refused by name, before any work, in every route."""
    b = FreeRigidBody(("1", "1.5", "2.5"), ("0.125", "0.25", "1"))
    for call in (b.at, b.enclose):
        with pytest.raises(ValueError, match="t: 1.0e\\+20000 is .* periods away"):
            call("1e20000")
    with pytest.raises(ValueError, match="quadrature route"):
        b.psi_by_quadrature("1e40")
    with pytest.raises(ValueError, match="quadrature route"):
        b.at("1e40", method="quadrature")


def test_exact_separatrix_is_refused():
    # A, B, C = 3, 4, 6 and p₁ = 2r₁: 2T·B − |L|² = Ap²(B − A) + Cr²(B − C) = 0 exactly.
    with pytest.raises(ValueError, match="exactly on the separatrix"):
        FreeRigidBody(("3", "4", "6"), ("2", "0.5", "1"))


def test_certify_refuses_what_it_cannot_reach():
    # A "computation" whose result depends on the working precision at the 1e-20 level.
    def compute(wdps):
        return {"x": mpmath.mpf(1) + mpmath.mpf(10) ** (20 - wdps)}

    with pytest.raises(PrecisionNotReached, match="x: cannot certify 30 digits"):
        certify(compute, 30)

    def converged(wdps):
        return {"x": mpmath.mpf(1) + mpmath.mpf(10) ** (5 - wdps)}

    assert certify(converged, 30).errors["x"] < mpmath.mpf("1e-30")


def test_space_momentum_keeps_small_components_of_a_large_momentum():
    """L in space is R(attitude) L(0), formed directly: rotating (0, 0, k) back cancelled 300
    digits of k = 1e300 in C r = 2.5, and 41 digits could not be certified."""
    body = FreeRigidBody(
        ("1", "1.5", "2.5"), ("1e300", "0.25", "1"), attitude=("1", "0", "0", "0"), dps=41
    )
    with mpmath.workdps(60):
        for got, want in zip(body.momentum_space, ("1e300", "0.375", "2.5"), strict=True):
            assert abs(got - mpmath.mpf(want)) <= mpmath.mpf("1e-41") * abs(mpmath.mpf(want))
