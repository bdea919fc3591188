"""The closed forms against each other: Euler 1758 and Cayley 1846 against FreeRigidBody."""

from __future__ import annotations

import mpmath
from rotation_cases import BY_NAME

from cayley_heyoka.reference import FreeRigidBody

from .laws import CLOSED_FORM_DPS, CLOSED_FORM_TIMES
from .verdicts import sci, verdict


def closed_form_section(dps: int = CLOSED_FORM_DPS) -> list[str]:
    """Euler 1758 and Cayley 1846 against FreeRigidBody (Cayley 1843), when they exist.

    Compared at a few times of two cases: the rates; Cayley 1846's quaternion against
    FreeRigidBody's from the same initial Rodrigues attitude (up to sign); Euler's body
    components (cos l, cos m, cos n) of a fixed direction P against Rᵀ P from FreeRigidBody's
    quaternion (identity initial attitude, so P's space components are its body components at
    t = 0). Tolerance: both sides are certified to 10⁻ᵈᵖˢ, so 10 · 10⁻ᵈᵖˢ.
    """
    lines = [
        "## The closed forms against each other",
        "",
        "_Section built by `closed_form_section()`; the Euler 1758 and Cayley 1846 modules are "
        "written and validated elsewhere — this only cross-checks them against "
        "`FreeRigidBody`._",
        "",
    ]
    try:
        from cayley_heyoka.rotation.cayley1846 import Cayley1846
        from cayley_heyoka.rotation.euler1758 import Euler1758
    except Exception as exc:  # the modules may not exist yet
        return [*lines, f"Skipped: the imports failed ({type(exc).__name__}: {exc}).", ""]
    tol = 10 * mpmath.mpf(10) ** -dps
    direction = ("0", "0.6", "0.8")
    rodrigues = ("0.1", "0.2", "-0.3")
    lines += [
        f"dps = {dps}, tolerance {mpmath.nstr(tol, 2)} (10 × 10⁻ᵈᵖˢ); times in periods of "
        f"(p, q, r); P = {direction} (body components at t = 0), Cayley 1846 and FreeRigidBody "
        f"from Rodrigues {rodrigues}.",
        "",
        "| case | t/T | Euler: p,q,r | Euler: cos l,m,n vs RᵀP | Cayley 1846: p,q,r "
        "| Cayley 1846: quaternion | verdict |",
        "|---|---|---|---|---|---|---|",
    ]
    for name in ("generic", "unsorted"):
        case = BY_NAME[name]
        try:
            ref = FreeRigidBody(case.inertia, case.rates, attitude=(1, 0, 0, 0), dps=dps)
            ref_r = FreeRigidBody(case.inertia, case.rates, rodrigues=rodrigues, dps=dps)
            euler = Euler1758(case.inertia, case.rates, direction, dps=dps)
            cayley = Cayley1846(case.inertia, case.rates, rodrigues, dps=dps)
        except Exception as exc:
            lines.append(f"| {name} | – | construction failed: {type(exc).__name__}: {exc} |||||")
            continue
        for frac in CLOSED_FORM_TIMES:
            with mpmath.workdps(dps + 10):
                t = mpmath.mpf(frac) * ref.period
                try:
                    s, sr, e, c = ref.at(t), ref_r.at(t), euler.at(t), cayley.at(t)
                except Exception as exc:
                    lines.append(
                        f"| {name} | {frac} | evaluation failed: {type(exc).__name__}: {exc} |||||"
                    )
                    continue
                d_e = max(abs(e.p - s.p), abs(e.q - s.q), abs(e.r - s.r))
                R = _matrix(s.quaternion)
                P = [mpmath.mpf(x) for x in direction]
                body = [sum(R[i][j] * P[i] for i in range(3)) for j in range(3)]
                d_dir = max(
                    abs(a - b) for a, b in zip((e.cos_l, e.cos_m, e.cos_n), body, strict=True)
                )
                d_c = max(abs(c.p - sr.p), abs(c.q - sr.q), abs(c.r - sr.r))
                d_q = min(
                    max(abs(a - b) for a, b in zip(c.quaternion, sr.quaternion, strict=True)),
                    max(abs(a + b) for a, b in zip(c.quaternion, sr.quaternion, strict=True)),
                )
                ok = max(d_e, d_dir, d_c, d_q) <= tol
                lines.append(
                    f"| {name} | {frac} | {sci(d_e)} | {sci(d_dir)} | {sci(d_c)} | {sci(d_q)} "
                    f"| {verdict(ok)} |"
                )
    return [*lines, ""]


def _matrix(q) -> list[list[mpmath.mpf]]:
    """R(q) with R[i][j] = cos(space i, body j) (v_space = R v_body)."""
    w, x, y, z = q
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
