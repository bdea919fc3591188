"""Hamilton's system with one predominant mass (Hamilton 1835, Second Essay §31–39).

The N5 system throughout: M = 1, G = 1 and two bodies whose relative orbits (Hamilton's
meaning: Kepler orbits of ξ with parameter G(M + m)) have, at the start time,

    m₁ = 1e-3:  a = 1,   e = 0.05, i = 0.05, Ω = 0.3, ω = 1.1, ℓ = 0.4
    m₂ = 3e-4:  a = 1.8, e = 0.08, i = 0.08, Ω = 2.0, ω = 4.0, ℓ = 2.5

**The round-off law of the position comparisons.** Every step rounds the energy by ~ε, so the
mean motion n ∝ |H|^{3/2} walks like ε√N over N steps and the along-track position error grows
like (3/2) ε √N n t a. The largest n·a of N5 is the inner body's, 1. Two runs compared carry
the walks of both (N = the sum of their steps); the bound is 10 ε √N t (the factor 10 for the
spread of the walk, as in the other families' energy tests), plus the error of the starting
state: the eccentricity of Hamilton's elements comes from 1 − e² and carries ε/e, so the
conversion moves ξ by ~ε a/e: 4 ε max(a)/min(e).
"""

from __future__ import annotations

import copy
import math
from pathlib import Path

import heyoka as hy
import mpmath
import numpy as np
import pytest

from cayley_heyoka import Scene, SceneError, load_scene, run
from cayley_heyoka.hamilton.elements import lagrange_brackets
from cayley_heyoka.hamilton.predominant_mass import equations as pe
from cayley_heyoka.hamilton.predominant_mass import system as planets
from cayley_heyoka.hamilton.scene import MAX_BODIES
from cayley_heyoka.mechanics.kepler import Elements

EPS = 2.0**-52
EPS_QUAD = 2.0**-112
TWO_PI = "6.283185307179586476925286766559005768394"
# "N5": the two bodies of the bundled example (their numbers live there only).
_N5 = load_scene(Path(__file__).resolve().parents[2] / "examples" / "planets.toml").to_dict()
MASSES = tuple(body["mass"] for body in _N5["hamiltonian"]["bodies"])
ELEMENTS = tuple(body["elements"] for body in _N5["hamiltonian"]["bodies"])
POSITIONS = ("x1", "y1", "z1", "x2", "y2", "z2")
VELOCITIES = ("vx1", "vy1", "vz1", "vx2", "vy2", "vz2")
STATE_FLOOR = 4 * 1.8 / 0.05  # × ε: the starting state's ε a/e


def n5(formulation: str, stop: str, count: int = 11, precision: str = "double", start="0"):
    """The N5 scene dictionary from ``start`` to ``stop``."""
    return {
        "hamiltonian": {
            "model": "predominant_mass",
            "G": "1",
            "central_mass": "1",
            "formulation": formulation,
            "bodies": [
                {"mass": m, "elements": dict(e)} for m, e in zip(MASSES, ELEMENTS, strict=True)
            ],
        },
        "integrator": {"precision": precision},
        "output": {
            "times": {"start": start, "stop": stop, "count": count},
            "principal_function": True,
        },
    }


def orbits(k: float) -> str:
    """2πk as decimal text."""
    with mpmath.workdps(40):
        return mpmath.nstr(mpmath.mpf(k) * mpmath.mpf(TWO_PI), 38)


def law(steps: int, t: float, eps: float = EPS) -> float:
    """The position bound of the module's docstring."""
    return 10 * eps * math.sqrt(steps) * t + STATE_FLOOR * eps


def positions(result, names=POSITIONS) -> np.ndarray:
    return np.stack([np.asarray(result[k], dtype=float) for k in names], axis=1)


def start_states(dps: int = 40) -> list[tuple[list, list]]:
    """(ξ, x′) of both bodies at the start, in mpmath."""
    with mpmath.workdps(dps):
        return [
            planets.classical_state(Elements(**e), m, "1", "1")
            for m, e in zip(MASSES, ELEMENTS, strict=True)
        ]


# -- (a) (F2.) against an independent barycentric N-body integration ---------------------------


def test_canonical_equations_follow_a_barycentric_nbody_integration():
    """Check N1: ``heyoka.model.nbody`` (barycentric, Newton's equations, nothing of ours but the
    starting state), converted to (ξ, x′), over 100 inner orbits in double."""
    res = run(Scene.from_dict(n5("canonical", orbits(100), 21)))
    with mpmath.workdps(40):
        states = start_states()
        m = [mpmath.mpf(v) for v in MASSES]
        X, V = planets.barycentric([s[0] for s in states], [s[1] for s in states], m, 1)
        start = [float(c) for x, v in zip(X, V, strict=True) for c in (*x, *v)]
    system = hy.model.nbody(3, masses=[1.0, 1e-3, 3e-4], Gconst=1.0)
    ta = hy.taylor_adaptive(system, start, compact_mode=True)
    grid = np.asarray(res.t, dtype=float)
    out = ta.propagate_grid(grid)
    rows = out[-1]
    X = [[rows[:, 6 * b + j] for j in range(3)] for b in range(3)]
    V = [[rows[:, 6 * b + 3 + j] for j in range(3)] for b in range(3)]
    xs, vs = planets.heliocentric(X, V, [1.0, 1e-3, 3e-4])
    ours = positions(res)
    theirs = np.stack([c for x in xs for c in x], axis=1)
    bound = law(res.counters["steps"] + out[3], grid[-1])
    assert np.max(np.abs(ours - theirs)) < bound
    ours_v = positions(res, VELOCITIES)
    theirs_v = np.stack([c for v in vs for c in v], axis=1)
    assert np.max(np.abs(ours_v - theirs_v)) < bound  # n a = 1 for the inner body too


# -- (b) Hamilton's brackets -------------------------------------------------------------------


@pytest.mark.parametrize("body", [0, 1])
def test_brackets_of_hamiltons_elements_are_the_unit_ones(body):
    """(188.)–(210.) in Lagrange's form: with ξ(z, t) and x′(z, t) of :func:`state_from_elements`,
    [a, b] = Σ (∂ξ/∂a ∂x′/∂b − ∂ξ/∂b ∂x′/∂a) is 1 for (μ, τ), (ϖ, λ), (χ, ν) and 0 otherwise,
    at the epochs of the test (N2): the inverse transpose of Hamilton's unit Poisson
    brackets. Symbolic derivatives in double: each bracket sums products of two partials, which
    grow with t − τ (∂ℓ/∂μ does) and carry 1/e (e = √(1 − b²): ∂e/∂μ = −∂(b²)/∂μ / 2e), and
    cancel to 0 or 1; the bound is 64 ε (1 + |t − τ|)²/e²."""
    c = pe.Coefficients("1", "1", MASSES)
    z = list(hy.make_vars(*pe.ELEMENTS))
    xi, xprime = pe.state_from_elements(z, body, c)
    coordinates, momenta = [z[0], z[2], z[4]], [z[1], z[3], z[5]]
    L = lagrange_brackets(xi, xprime, coordinates, momenta)
    cf = hy.cfunc([e for row in L for e in row], coordinates + momenta)
    with mpmath.workdps(40):
        x, v = start_states()[body]
        el = planets.hamilton_elements(x, v, 0, MASSES[body], "1", "1")
        values = [float(getattr(el, k)) for k in ("mu", "varpi", "chi", "tau", "lam", "nu")]
    J = np.block([[np.zeros((3, 3)), np.eye(3)], [-np.eye(3), np.zeros((3, 3))]])
    for t in (0.0, 2.7, 11.3, 40.1):
        got = cf(np.array(values), time=t).reshape(6, 6)
        bound = 64 * EPS * (1 + abs(t - values[3])) ** 2 / float(ELEMENTS[body]["e"]) ** 2
        assert np.max(np.abs(got - J)) < bound, t


# -- (c), (d) elements against canonical -------------------------------------------------------


@pytest.fixture(scope="module")
def twenty_orbits():
    """Both formulations over 20 inner orbits from t₀ = 3.5 (τ is absolute)."""
    start = "3.5"
    with mpmath.workdps(40):
        stop = mpmath.nstr(mpmath.mpf(start) + 20 * mpmath.mpf(TWO_PI), 38)
    return {
        f: run(Scene.from_dict(n5(f, stop, 41, start=start))) for f in ("canonical", "elements")
    }


def test_elements_and_canonical_agree_over_twenty_orbits(twenty_orbits):
    a, b = twenty_orbits["elements"], twenty_orbits["canonical"]
    t = float(a.t[-1] - a.t[0])
    bound = law(a.counters["steps"] + b.counters["steps"], t)
    for names in (POSITIONS, VELOCITIES):
        assert np.max(np.abs(positions(a, names) - positions(b, names))) < bound
    # S = ∫ (T + U) dt: its error is the state's times |∂(T + U)/∂ξ| ~ m/r² integrated.
    assert np.max(np.abs(a["S"] - b["S"])) < bound * 1e-3 * t + 64 * EPS * np.max(np.abs(b["S"]))


def test_h1_is_the_sum_of_m_mu_and_h_is_conserved(twenty_orbits):
    """(212.), check N6: H₁ of (H2.) from the reconstructed state equals Σ mᵢμᵢ; H₁ depends on
    a only, and the ε/e of the eccentricity moves ξ, x′ along orbits of the same a, so the
    comparison costs a few roundings: 64 ε |H₁|. H and Σ ξ × p are conserved (Brouwer:
    10 ε √N)."""
    res = twenty_orbits["elements"]
    xs = [[res[f"{a}{i}"] for a in "xyz"] for i in (1, 2)]
    vs = [[res[f"v{a}{i}"] for a in "xyz"] for i in (1, 2)]
    split = planets.energy(xs, vs, [float(m) for m in MASSES], 1.0, 1.0)
    sum_m_mu = sum(float(m) * res[f"mu{i}"] for i, m in enumerate(MASSES, start=1))
    assert np.max(np.abs(split.H1 - sum_m_mu)) < 64 * EPS * np.max(np.abs(split.H1))
    assert np.max(np.abs(split.H - res.monitors["energy"])) < 64 * EPS * abs(split.H[0])
    steps = res.counters["steps"]
    assert res.conserved == ("energy", "angular_momentum")
    for name in res.conserved:
        assert np.max(np.abs(res.drift(name))) < 10 * EPS * math.sqrt(steps), name
    # H₂ is the small part, of the order of m₁m₂/M next to H₁ ~ m: (H2.) is a real split.
    assert np.max(np.abs(split.H2)) < 1e-3 * np.max(np.abs(split.H1))


def test_elements_vary_slowly_and_the_positions_do_not():
    """What the formulation is for: over one inner orbit the elements move by O(m/M), the
    positions by O(a)."""
    res = run(Scene.from_dict(n5("elements", orbits(1), 21)))
    for name in ("mu1", "lambda1", "chi1", "nu1", "mu2", "lambda2"):
        spread = np.ptp(np.asarray(res[name], dtype=float))
        assert spread < 5e-3 * max(1.0, abs(float(res[name][0]))), name
    assert np.ptp(np.asarray(res["x1"], dtype=float)) > 1


def test_check_formulations_reports_rows_within_their_bounds():
    """The ready-made check (for ``cayley-heyoka check``): both formulations, ξ and x′ rows
    with the law's bounds, conservation rows for each run."""
    from cayley_heyoka.hamilton.predominant_mass.check import check_formulations

    report = check_formulations(Scene.from_dict(n5("canonical", orbits(2), 9)))
    assert report.passed, report.text()
    assert len(report.rows) == 6 and len(report.series["position"]) == 9
    assert report.rows[0].error > 0  # the two runs are different computations
    with pytest.raises(ValueError, match="predominant_mass"):
        check_formulations(Scene.from_toml(EXAMPLE_PROJECTILE))


EXAMPLE_PROJECTILE = """
[hamiltonian]
model = "projectile"
g = 1.0
mu = 0.3
nu = 0.45
[initial]
eta = [0.2, -0.4, 1.5]
varpi = [0.7, 0.3, 2.1]
[output]
times = [0.0, 1.0]
"""


# -- (e) real128 -------------------------------------------------------------------------------


def test_both_formulations_agree_far_below_double_in_quad():
    """real128 over two inner orbits: the same law with real128's ε (the starting states are
    built from the scene's decimal text in mpmath, so nothing carries a double's error)."""
    runs = {f: run(Scene.from_dict(n5(f, orbits(2), 5, "quad"))) for f in ("canonical", "elements")}
    a, b = runs["elements"], runs["canonical"]
    steps = a.counters["steps"] + b.counters["steps"]
    bound = law(steps, 4 * math.pi, EPS_QUAD)
    assert bound < 1e-28
    with mpmath.workdps(40):
        for name in POSITIONS + VELOCITIES:
            for u, w in zip(a[name], b[name], strict=True):
                assert abs(mpmath.mpf(str(u)) - mpmath.mpf(str(w))) < bound, name


# -- (f) conversions ---------------------------------------------------------------------------


def test_hamiltons_elements_have_their_newtonian_meaning():
    """§8.3's table, in mpmath at 40 digits: μ = −GM/(2a), λ = M/(M+m) √(K a(1 − e²)),
    χ = λ(1 − cos i), ν = Ω, ϖ = Ω + ω, τ = t − ℓ/n, K = G(M + m), n = √(K/a³)."""
    t = mpmath.mpf("3.5")
    with mpmath.workdps(40):
        for (x, v), m, e in zip(start_states(), MASSES, ELEMENTS, strict=True):
            m = mpmath.mpf(m)
            z = planets.hamilton_elements(x, v, t, m, 1, 1)
            a, ecc, i = (mpmath.mpf(e[k]) for k in ("a", "e", "inclination"))
            K = 1 + m
            lam = mpmath.sqrt(K * a * (1 - ecc**2)) / (1 + m)
            expected = {
                "mu": -1 / (2 * a),
                "lam": lam,
                "chi": lam * (1 - mpmath.cos(i)),
                "nu": mpmath.mpf(e["node"]),
                "varpi": mpmath.mpf(e["node"]) + mpmath.mpf(e["argument_of_pericentre"]),
                "tau": t - mpmath.mpf(e["mean_anomaly"]) / mpmath.sqrt(K / a**3),
            }
            for key, value in expected.items():
                got = getattr(z, key)
                if key == "varpi":
                    got = value + mpmath.atan2(mpmath.sin(got - value), mpmath.cos(got - value))
                assert abs(got - value) < mpmath.mpf(10) ** -35, key


@pytest.mark.parametrize("dps", [None, 50])
def test_conversions_round_trip(dps):
    """classical → (ξ, x′) → Hamilton's elements → (ξ, x′): each conversion costs a few
    roundings of a, and the eccentricity from 1 − e² costs ε/e: 16 ε a/e (in double and at
    50 digits)."""
    t = "12.25"
    for m, e in zip(MASSES, ELEMENTS, strict=True):
        if dps is None:
            values = Elements(**{k: float(v) for k, v in e.items()})
            x, v = planets.classical_state(values, float(m), 1.0, 1.0)
            z = planets.hamilton_elements(x, v, float(t), float(m), 1.0, 1.0)
            x2, v2 = planets.hamilton_state(z, float(t), float(m), 1.0, 1.0)
            eps = EPS
        else:
            with mpmath.workdps(dps):
                x, v = planets.classical_state(Elements(**e), m, "1", "1")
                z = planets.hamilton_elements(x, v, t, m, "1", "1")
                x2, v2 = planets.hamilton_state(z, t, m, "1", "1")
            eps = 10.0**-dps
        bound = 16 * eps * float(e["a"]) / float(e["e"])
        for u, w in zip([*x, *v], [*x2, *v2], strict=True):
            assert abs(float(u - w)) < bound


def test_heyoka_state_from_elements_matches_the_numpy_conversion():
    """:func:`state_from_elements` (heyoka, with kepE, the (V2.) form of the rotation) against
    :func:`planets.hamilton_state` (numpy, Kepler's equation solved there, the classical
    rotation), both in double: 16 ε a/e, plus ε ℓ for the mean anomaly n(t − τ) rounded at
    |ℓ| up to ~60."""
    c = pe.Coefficients("1", "1", MASSES)
    for body, (m, e) in enumerate(zip(MASSES, ELEMENTS, strict=True)):
        z = list(hy.make_vars(*pe.ELEMENTS))
        xi, xp = pe.state_from_elements(z, body, c)
        cf = hy.cfunc([*xi, *xp], z)
        with mpmath.workdps(40):
            x, v = start_states()[body]
            el = planets.hamilton_elements(x, v, 0, m, 1, 1)
            values = [float(u) for u in el.as_tuple()]
        numeric = planets.HamiltonElements(*values)
        for t in (0.0, 3.7, 50.0):
            got = cf(np.array(values), time=t)
            x2, v2 = planets.hamilton_state(numeric, t, float(m), 1.0, 1.0)
            bound = 16 * EPS * float(e["a"]) / float(e["e"]) + 4 * EPS * (1 + t)
            assert np.max(np.abs(got - np.array([*x2, *v2]))) < bound, (body, t)


def test_energy_and_angular_momentum_of_the_starting_state():
    """The monitors at the start against :func:`planets.energy` and Σ mᵢ ξᵢ × x′ᵢ in mpmath."""
    with mpmath.workdps(40):
        states = start_states()
        xs, vs = [s[0] for s in states], [s[1] for s in states]
        m = [mpmath.mpf(v) for v in MASSES]
        H = planets.energy(xs, vs, m, 1, 1).H
        L = planets.angular_momentum(xs, vs, m)
    for formulation in ("canonical", "elements"):
        res = run(Scene.from_dict(n5(formulation, "1", 2)))
        assert abs(res.monitors["energy"][0] - float(H)) < 64 * EPS * abs(float(H))
        got = res.monitors["angular_momentum"][0]
        norm = float(mpmath.sqrt(sum(c * c for c in L)))
        assert np.max(np.abs(got - np.array([float(c) for c in L]))) < 64 * EPS * norm


def test_one_body_is_keplers_motion_in_both_formulations():
    """With one body H₂ = 0: the elements stay exactly constant and ξ(t) is the Kepler orbit
    of parameter G(M + m) through them; the canonical run follows it (the law's bound)."""
    d = n5("elements", orbits(3), 7)
    d["hamiltonian"]["bodies"] = d["hamiltonian"]["bodies"][:1]
    a = run(Scene.from_dict(d))
    for name in pe.ELEMENTS:
        assert np.all(np.asarray(a[f"{name}1"]) == a[f"{name}1"][0]), name
    d["hamiltonian"]["formulation"] = "canonical"
    b = run(Scene.from_dict(d))
    bound = law(a.counters["steps"] + b.counters["steps"], 6 * math.pi)
    assert np.max(np.abs(positions(a, POSITIONS[:3]) - positions(b, POSITIONS[:3]))) < bound


def test_canonical_takes_states_the_elements_refuse():
    """An orbit in the reference plane and a circular one: the canonical formulation runs."""
    d = n5("canonical", "1", 2)
    bodies = d["hamiltonian"]["bodies"]
    bodies[0]["elements"]["inclination"] = "0"
    bodies[1]["elements"]["e"] = "0"
    res = run(Scene.from_dict(d))
    assert res.success and res["z1"][0] == 0  # (body 2, inclined, pulls it out of the plane)


def test_position_and_velocity_give_the_same_run_as_elements():
    """A body given by ξ and x′ (here those the elements give, to 25 digits) runs the same."""
    d = n5("elements", orbits(1), 3)
    with mpmath.workdps(40):
        x, v = start_states()[1]
        state = {
            "mass": MASSES[1],
            "position": [mpmath.nstr(c, 25) for c in x],
            "velocity": [mpmath.nstr(c, 25) for c in v],
        }
    a = run(Scene.from_dict(d))
    d["hamiltonian"]["bodies"][1] = state
    b = run(Scene.from_dict(d))
    assert np.max(np.abs(positions(a) - positions(b))) < law(2 * a.counters["steps"], 2 * math.pi)


# -- (g) bad input -----------------------------------------------------------------------------


def _with(change) -> dict:
    d = copy.deepcopy(n5("elements", "1"))
    change(d)
    return d


def _body(i, **values):
    def change(d):
        d["hamiltonian"]["bodies"][i] = {"mass": MASSES[i], **values}

    return change


def _element(i, key, value):
    def change(d):
        d["hamiltonian"]["bodies"][i]["elements"][key] = value

    return change


def _key(key, value=None):
    def change(d):
        if value is None:
            del d["hamiltonian"][key]
        else:
            d["hamiltonian"][key] = value

    return change


BAD = [
    (_key("G"), "hamiltonian.G", "required"),
    (_key("G", "-1"), "hamiltonian.G", "> 0"),
    (_key("central_mass"), "hamiltonian.central_mass", "required"),
    (_key("bodies"), "hamiltonian.bodies", "required"),
    (_key("bodies", []), "hamiltonian.bodies", "array of 1 to"),
    (_key("bodies", [{"mass": "1e-3"}] * (MAX_BODIES + 1)), "hamiltonian.bodies", "array of 1"),
    (_key("g", "1"), "hamiltonian.g", "not used"),
    (lambda d: d.update(initial={"eta": [1], "varpi": [0]}), "initial", "not used"),
    (lambda d: d["hamiltonian"]["bodies"][1].update(mass="0"), "hamiltonian.bodies[1].mass", ">"),
    (
        lambda d: d["hamiltonian"]["bodies"][0].update(masse="1"),
        "hamiltonian.bodies[0].masse",
        "did you mean 'mass'",
    ),
    (
        lambda d: d["hamiltonian"]["bodies"][0].update(position=[1, 0, 0]),
        "hamiltonian.bodies[0]",
        "not both",
    ),
    (_body(0, position=[1, 0, 0]), "hamiltonian.bodies[0]", "position and velocity"),
    (_body(0, position=[0, 0, 0], velocity=[0, 1, 0]), "hamiltonian.bodies[0].position", "origin"),
    (
        _body(0, position=[1, 0, 0], velocity=[0, 2, 0.1]),
        "hamiltonian.bodies[0].velocity",
        "unbound",
    ),
    (_body(0, position=[1, 0, 0], velocity=[0.5, 0, 0]), "hamiltonian.bodies[0].velocity", "λ = 0"),
    (
        _body(0, position=[1, 0, 0], velocity=[0.1, 0.9, 0]),
        "hamiltonian.bodies[0].velocity",
        "reference plane",
    ),
    (_element(0, "e", "1"), "hamiltonian.bodies[0].elements.e", "[0, 1)"),
    (_element(0, "e", "0"), "hamiltonian.bodies[0].elements.e", "canonical"),
    (_element(1, "inclination", "0"), "hamiltonian.bodies[1].elements.inclination", "canonical"),
    (_element(1, "inclination", "4"), "hamiltonian.bodies[1].elements.inclination", "[0, π]"),
    (_element(0, "a", "0"), "hamiltonian.bodies[0].elements.a", "> 0"),
    (
        lambda d: d["hamiltonian"]["bodies"][0]["elements"].pop("node"),
        "hamiltonian.bodies[0].elements",
        "missing",
    ),
    (
        lambda d: d["hamiltonian"]["bodies"].append(copy.deepcopy(d["hamiltonian"]["bodies"][0])),
        "hamiltonian.bodies[2]",
        "position of hamiltonian.bodies[0]",
    ),
]


@pytest.mark.parametrize(("change", "field", "text"), BAD)
def test_bad_input_names_the_field(change, field, text):
    with pytest.raises(SceneError, match=text.replace("[", r"\[").replace(")", r"\)")) as info:
        Scene.from_dict(_with(change))
    assert info.value.field == field


def test_circular_state_is_refused_by_the_elements_exactly():
    """A circular relative orbit given by ξ and x′, decided in rationals: ξ = (1, 0, 0) and
    x′ = (0, 0.8, 0.6) with m = 1e-3, M = 1, G = 1.001 make v = 1.001 x′ perpendicular to ξ
    with |v|² = 1.001² = G(M + m)/r."""
    d = _with(_body(0, position=["1", "0", "0"], velocity=["0", "0.8", "0.6"]))
    d["hamiltonian"]["G"] = "1.001"
    with pytest.raises(SceneError, match="circular") as info:
        Scene.from_dict(d)
    assert info.value.field == "hamiltonian.bodies[0].velocity"
    d["hamiltonian"]["formulation"] = "canonical"
    Scene.from_dict(d)


def test_predominant_mass_keys_belong_to_their_model():
    d = {
        "hamiltonian": {"model": "projectile", "g": "1", "mu": "0.3", "nu": "0.4", "G": "1"},
        "initial": {"eta": ["0", "0", "0"], "varpi": ["1", "0", "1"]},
        "output": {"times": ["0", "1"]},
    }
    with pytest.raises(SceneError, match="predominant_mass") as info:
        Scene.from_dict(d)
    assert info.value.field == "hamiltonian.G"


def test_unknown_monitor_is_refused_when_run():
    d = n5("canonical", "1", 2)
    d["output"]["monitors"] = ["energy", "jacobi"]
    with pytest.raises(SceneError, match="angular_momentum") as info:
        run(Scene.from_dict(d))
    assert info.value.field == "output.monitors"


# -- long ---------------------------------------------------------------------------------------


@pytest.mark.slow
def test_elements_and_canonical_agree_over_a_thousand_orbits():
    """1000 inner orbits (t = 2000π) in double, the law's bound (measured: ~3e-10 against a
    bound of ~3e-9)."""
    runs = {f: run(Scene.from_dict(n5(f, orbits(1000), 101))) for f in ("canonical", "elements")}
    a, b = runs["elements"], runs["canonical"]
    bound = law(a.counters["steps"] + b.counters["steps"], 2000 * math.pi)
    for names in (POSITIONS, VELOCITIES):
        assert np.max(np.abs(positions(a, names) - positions(b, names))) < bound
    for res in runs.values():
        for name in res.conserved:
            assert np.max(np.abs(res.drift(name))) < 10 * EPS * math.sqrt(res.counters["steps"])


def test_the_element_equations_compile_in_compact_mode_by_default():
    """Their non-compact code takes ~25 s to compile for two bodies (~1 s compact); two bodies'
    canonical equations are small and step faster without it."""
    from cayley_heyoka.core.families import FAMILIES

    build = FAMILIES["hamiltonian"].build
    assert build(Scene.from_dict(n5("elements", stop="1"))).compact
    assert not build(Scene.from_dict(n5("canonical", stop="1"))).compact
