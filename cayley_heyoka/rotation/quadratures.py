"""Cayley's 1843 quadratures of the free body at one working precision (:class:`Constants`):
everything that depends on the inputs only — the invariants, the Jacobi form's modulus,
frequency and phase, the third-kind integral's characteristic — and the evaluations built on
them (φ, the rates, Ψ = 2 tan⁻¹ν₀, the invariable-plane crossings). Symbols:
:mod:`.closed_form`, which evaluates each value at two such precisions."""

from __future__ import annotations

from collections.abc import Sequence

import mpmath

from ..core.accuracy import PrecisionNotReached, to_mpf
from .attitude import (
    quaternion_multiply,
    quaternion_to_matrix,
)


class Constants:
    """Everything that depends on the inputs only, at one working precision."""

    def __init__(self, inertia: Sequence[object], rates: Sequence[object], attitude, dps: int):
        with mpmath.workdps(dps):
            A, B, C = (to_mpf(x) for x in inertia)
            w1 = [to_mpf(x) for x in rates]
            self.A, self.B, self.C = A, B, C
            self.w1 = w1
            I = (A, B, C)  # noqa: E741 - the inertia triple, as in the memoir
            self.I = I
            self.h = sum(I[i] * w1[i] ** 2 for i in range(3))
            self.k = mpmath.sqrt(sum((I[i] * w1[i]) ** 2 for i in range(3)))
            self.kind = _kind(I, w1)
            if self.kind == "asymmetric":
                self._jacobi()
            elif self.kind == "symmetric":
                self._symmetric()
            if w1[0] == 0 and w1[1] == 0 and w1[2] < 0:
                raise ValueError(
                    "rates: a steady rotation about −z₁ (p = q = 0, r < 0) leaves the body a "
                    "half-turn from the invariable frame (k + Cr = 0), where Cayley's ν₀ and its "
                    "azimuth convention are undefined; turn the body labels (p, q, r) → "
                    "(p, −q, −r) by a half-turn about x₁"
                )
            # Invariable-frame attitude at t = 0 (Ψ = 0) and the constant space-side factor.
            self.q0_start = self.invariable_quaternion(mpmath.mpf(0), *w1)
            self.attitude: list[mpmath.mpf] | None = None
            if attitude is None:
                self.outer = (mpmath.mpf(1), mpmath.mpf(0), mpmath.mpf(0), mpmath.mpf(0))
            else:
                qa = [to_mpf(x) for x in attitude]
                norm = mpmath.sqrt(sum(x * x for x in qa))
                qa = [x / norm for x in qa]
                self.attitude = qa
                w, x, y, z = self.q0_start
                self.outer = tuple(quaternion_multiply(qa, (w, -x, -y, -z)))

    # -- the invariable frame -------------------------------------------------------------------
    def k_plus_Cr(self, r: mpmath.mpf, Ap: mpmath.mpf, Bq: mpmath.mpf) -> mpmath.mpf:
        # For r < 0, k + Cr cancels; (k² − C²r²)/(k − Cr) = (A²p² + B²q²)/(k − Cr) does not.
        if r >= 0:
            return self.k + self.C * r
        return (Ap * Ap + Bq * Bq) / (self.k - self.C * r)

    def invariable_quaternion(self, psi, p, q, r):
        """§7.4: the unit quaternion of the body in the invariable frame, regular at θ = π."""
        Ap, Bq = self.A * p, self.B * q
        kc = self.k_plus_Cr(r, Ap, Bq)
        c, s = mpmath.cos(psi / 2), mpmath.sin(psi / 2)
        f = mpmath.sqrt(kc / (2 * self.k))
        g = mpmath.sqrt(2 * self.k * kc)
        return (c * f, (s * Ap + c * Bq) / g, (s * Bq - c * Ap) / g, s * f)

    # -- the general case: Jacobi elliptic functions (§7.1) -----------------------------------
    def _jacobi(self) -> None:
        A, B, C = self.I
        w1 = self.w1
        a = [(C - B) / A, (A - C) / B, (B - A) / C]
        self.a = a
        Kc = -a[0] * a[1] * a[2]
        s = 1 if Kc > 0 else -1
        e = [s * w1[i] ** 2 / a[i] for i in range(3)]
        # The intermediate axis has the only e ≤ 0; then the cn (e₂) and dn (e₁) roots.
        order = sorted(range(3), key=lambda i: e[i])
        iX, iY, iZ = order
        e3, e2, e1 = e[iX], e[iY], e[iZ]
        if e1 == e2:
            raise ValueError(
                "rates: the state lies exactly on the separatrix (2T·B_mid = |L|²); the motion "
                "is aperiodic and not covered by the Jacobi form"
            )
        self.s, self.iX, self.iY, self.iZ = s, iX, iY, iZ
        self.m = (e2 - e3) / (e1 - e3)
        self.Omega = mpmath.sqrt(abs(Kc) * (e1 - e3))
        self.cX = mpmath.sqrt(-s * a[iX] * (e2 - e3))
        self.cY = mpmath.sqrt(s * a[iY] * (e2 - e3))
        self.cZ = mpmath.sqrt(s * a[iZ] * (e1 - e3))
        self.sZ = 1 if w1[iZ] > 0 else -1
        self.sY = s * self.sZ
        self.e3, self.e2 = e3, e2
        self.K = mpmath.ellipk(self.m)
        # χ₀ is undefined only when both oscillating components vanish: a steady rotation about
        # the dn axis, which _kind() has already sent elsewhere.
        self.chi0 = mpmath.atan2(w1[iX] / self.cX, self.sY * w1[iY] / self.cY)
        self.u0 = mpmath.ellipf(self.chi0, self.m)
        # Ψ (§7.3): D = k² − C²r² = D₀(1 − n sn²u).
        k2, C2 = self.k**2, C**2
        if iX == 2:
            D0, D1 = k2, k2 - C2 * self.cX**2
        elif iY == 2:
            D0, D1 = k2 - C2 * self.cY**2, k2
        else:
            D0, D1 = k2 - C2 * self.cZ**2, k2 - C2 * self.cZ**2 * (1 - self.m)
        self.D0 = D0
        self.n = 1 - D1 / D0
        self.psi_coeff = self.k * (C * self.h - k2) / (C * self.Omega * D0)
        self.Pi_complete = mpmath.ellippi(self.n, self.m)
        self.Pi_chi0 = mpmath.ellippi(self.n, self.chi0, self.m)
        self.r_is_dn = iZ == 2
        if self.r_is_dn:
            self.winding_coeff = self.sZ * self.cZ * (k2 - C * self.h) / (self.Omega * D0)
            self.winding_chi0 = _pi_circular(self.n, self.chi0)
        self.period = 4 * self.K / self.Omega
        winding = 0
        if self.r_is_dn:
            winding = self.sZ * (1 if k2 - C * self.h > 0 else -1)
        self.psi_increment = (
            self.k * self.period / C
            + 4 * self.psi_coeff * self.Pi_complete
            + 2 * mpmath.pi * winding
        )

    def jacobi_state(self, t: mpmath.mpf) -> dict[str, mpmath.mpf]:
        u = self.Omega * t + self.u0
        j = mpmath.floor((u + self.K) / (2 * self.K))
        ur = u - 2 * j * self.K  # in [−K, K): cn ≥ 0, so atan2 gives am in (−π/2, π/2]
        sn, cn, dn = (mpmath.ellipfun(f, ur, m=self.m) for f in ("sn", "cn", "dn"))
        # sn, cn change sign with each half-period 2K; dn does not.
        sign = -1 if int(j) % 2 else 1
        chi_r = mpmath.atan2(sn, cn)
        w = [mpmath.mpf(0)] * 3
        w[self.iX] = sign * self.cX * sn
        w[self.iY] = sign * self.sY * self.cY * cn
        w[self.iZ] = self.sZ * self.cZ * dn
        # φ = s[e₃ + (e₂ − e₃)sn²u] with e₃ = −(e₂ − e₃) sin²χ₀, written without cancellation.
        phi = self.s * (self.e2 - self.e3) * (sn**2 - mpmath.sin(self.chi0) ** 2)
        Pi = mpmath.ellippi(self.n, chi_r, self.m) + 2 * j * self.Pi_complete
        psi = self.k * t / self.C + self.psi_coeff * (Pi - self.Pi_chi0)
        psi += self._phi_e_change(w, j, chi_r)
        return {"p": w[0], "q": w[1], "r": w[2], "phi": phi, "psi": psi}

    def _phi_e_change(self, w, j, chi_r) -> mpmath.mpf:
        """φ_e(t) − φ_e(0), φ_e = atan2(Ap, Bq) followed continuously (§7.3)."""
        if self.r_is_dn:
            chi = _pi_circular(self.n, chi_r) + j * mpmath.pi / mpmath.sqrt(1 - self.n)
            return self.winding_coeff * (chi - self.winding_chi0)
        # r changes sign, so (Bq, Ap) stays in an open half-plane: the principal angle is exact.
        x1, y1 = self.B * self.w1[1], self.A * self.w1[0]
        x, y = self.B * w[1], self.A * w[0]
        return mpmath.atan2(x1 * y - y1 * x, x1 * x + y1 * y)

    # -- two equal moments (§7.5) ---------------------------------------------------------------
    def _symmetric(self) -> None:
        I, w1 = self.I, self.w1
        # i: the symmetry axis (its rate is constant); (j, l) the equal pair, a right-handed cycle.
        i = next(i for i in range(3) if I[(i + 1) % 3] == I[(i + 2) % 3])
        j, l = (i + 1) % 3, (i + 2) % 3
        self.sym_axis, self.pair = i, (j, l)
        # Euler: ẇ_j = (I_j − I_i)/I_j w_i w_l = −ω w_l, ẇ_l = ω w_j, ω = (I_i − I_j) w_i / I_j.
        self.omega_pair = (I[i] - I[j]) * w1[i] / I[j]
        self.period = 2 * mpmath.pi / abs(self.omega_pair) if self.omega_pair != 0 else mpmath.inf
        self.m = mpmath.mpf(0)
        C, k, h = self.C, self.k, self.h
        if i == 2:
            self.psi_rate = (h + k * w1[2]) / self.k_plus_Cr(w1[2], I[0] * w1[0], I[1] * w1[1])
            self.psi_increment = self.psi_rate * self.period
            return
        # r oscillates: r = ρ cos(ωt + δ) and Ψ = kt/C + (h − k²/C)∫dt/(k + Cρ cos(ωt + δ)).
        other = j if l == 2 else l
        # r(t) is the rotating pair's component 2; write it as ρ cos(ωt + δ).
        r1, x1 = w1[2], w1[other]
        # r = w_l = r₁cos ωt + w_j₁ sin ωt, or r = w_j = r₁cos ωt − w_l₁ sin ωt.
        sign = -1 if other == j else 1
        self.rho = mpmath.sqrt(r1 * r1 + x1 * x1)
        self.delta = mpmath.atan2(sign * x1, r1)
        self.arc_a, self.arc_b = k, C * self.rho
        self.arc_s = mpmath.sqrt((k - C * self.rho) * (k + C * self.rho))
        self.psi_increment = k * self.period / C + (h - k * k / C) * 2 * mpmath.pi / (
            self.arc_s * abs(self.omega_pair)
        )

    def symmetric_state(self, t: mpmath.mpf) -> dict[str, mpmath.mpf]:
        i, (j, l) = self.sym_axis, self.pair
        w1, om = self.w1, self.omega_pair
        c, s = mpmath.cos(om * t), mpmath.sin(om * t)
        w = [mpmath.mpf(0)] * 3
        w[i] = w1[i]
        w[j] = w1[j] * c - w1[l] * s
        w[l] = w1[l] * c + w1[j] * s
        A, B, C = self.I
        phi = (
            (w1[0] ** 2 - w[0] ** 2) / ((C - B) / A)
            if C != B
            else ((w1[1] ** 2 - w[1] ** 2) / ((A - C) / B))
        )
        if i == 2:
            psi = self.psi_rate * t
        else:
            theta = om * t + self.delta
            integral = (self._arc(theta) - self._arc(self.delta)) / om
            psi = self.k * t / C + (self.h - self.k**2 / C) * integral
        return {"p": w[0], "q": w[1], "r": w[2], "phi": phi, "psi": psi}

    def _arc(self, theta: mpmath.mpf) -> mpmath.mpf:
        """Continuous antiderivative of 1/(a + b cos θ), a > |b|."""
        a, b, s = self.arc_a, self.arc_b, self.arc_s
        jj = mpmath.floor((theta + mpmath.pi) / (2 * mpmath.pi))
        tr = theta - 2 * jj * mpmath.pi
        half = mpmath.atan2(
            mpmath.sqrt(a - b) * mpmath.sin(tr / 2), mpmath.sqrt(a + b) * mpmath.cos(tr / 2)
        )
        return (2 * jj * mpmath.pi + 2 * half) / s

    def steady_state(self, t: mpmath.mpf) -> dict[str, mpmath.mpf]:
        p, q, r = self.w1
        rate = (self.h + self.k * r) / self.k_plus_Cr(r, self.A * p, self.B * q)
        return {"p": p, "q": q, "r": r, "phi": mpmath.mpf(0), "psi": rate * t}

    def state(self, t: mpmath.mpf) -> dict[str, mpmath.mpf]:
        if self.kind == "asymmetric":
            return self.jacobi_state(t)
        if self.kind == "symmetric":
            return self.symmetric_state(t)
        return self.steady_state(t)

    # -- derived constants, crossings --------------------------------------------------------------
    def summary(self) -> dict[str, mpmath.mpf]:
        moments = sorted(self.I)
        # L in space is R(attitude) L(0): rotating (0, 0, k) by the outer factor is the same
        # vector, but cancels to the digits of k in a component much smaller than k (p = 1e300
        # and C r = 2.5 lost 300 digits in g″).
        L0 = [self.I[i] * self.w1[i] for i in range(3)]
        zero = mpmath.mpf(0)
        g = (zero, zero, self.k) if self.attitude is None else quaternion_rotate(self.attitude, L0)
        out = {
            "h": self.h,
            "k": self.k,
            "m": self.m if self.kind != "steady" else mpmath.mpf(0),
            "period": getattr(self, "period", mpmath.inf),
            "psi_increment": getattr(self, "psi_increment", mpmath.inf),
            "separatrix_distance": (moments[1] * self.h - self.k**2) / self.k**2,
            "g": g[0],
            "g1": g[1],
            "g2": g[2],
        }
        if self.kind == "asymmetric":
            out["frequency"] = self.Omega
        return out

    def crossing_indices(self, index: int, t0, t1) -> list[tuple[int, int]]:
        """Candidate zeros of component ``index`` in [t0, t1] (with a margin) and directions."""
        if self.kind == "asymmetric":
            if index == self.iZ:
                return []
            lo, hi = (self.Omega * t + self.u0 for t in (t0, t1))
            # X = c_X sn u vanishes at u = 2jK, Y = σ_Y c_Y cn u at u = (2j + 1)K.
            shift = 0 if index == self.iX else 1
            first = int(mpmath.floor((lo / self.K - shift) / 2)) - 1
            last = int(mpmath.ceil((hi / self.K - shift) / 2)) + 1
            _check_crossing_count(last - first, t0, t1)
            if index == self.iX:
                return [(j, (-1) ** (j % 2)) for j in range(first, last + 1)]
            return [(j, -self.sY * (-1) ** (j % 2)) for j in range(first, last + 1)]
        if self.kind == "steady" or index == self.sym_axis:
            return []
        theta0, theta1 = sorted(self.omega_pair * t + self._pair_phase(index) for t in (t0, t1))
        # ρ cos θ vanishes at θ = π/2 + jπ, with d/dt = −ρω sin θ.
        first = int(mpmath.floor((theta0 - mpmath.pi / 2) / mpmath.pi)) - 1
        last = int(mpmath.ceil((theta1 - mpmath.pi / 2) / mpmath.pi)) + 1
        _check_crossing_count(last - first, t0, t1)
        sign = 1 if self.omega_pair > 0 else -1
        return [(j, -sign * (-1) ** (j % 2)) for j in range(first, last + 1)]

    def crossing_time(self, index: int, j: int) -> mpmath.mpf:
        if self.kind == "asymmetric":
            u = (2 * j if index == self.iX else 2 * j + 1) * self.K
            return (u - self.u0) / self.Omega
        theta = mpmath.pi / 2 + j * mpmath.pi
        return (theta - self._pair_phase(index)) / self.omega_pair

    def _pair_phase(self, index: int) -> mpmath.mpf:
        """δ with w_index = ρ cos(ωt + δ) for a component of the rotating pair."""
        j, l = self.pair
        if index == j:  # w_j = w_j₁ cos ωt − w_l₁ sin ωt
            return mpmath.atan2(self.w1[l], self.w1[j])
        return mpmath.atan2(-self.w1[j], self.w1[l])  # w_l = w_l₁ cos ωt + w_j₁ sin ωt

    # -- quadrature routes (cross-checks, §7.2–§7.3) ------------------------------------------
    def components_at_chi(self, chi) -> list[mpmath.mpf]:
        w = [mpmath.mpf(0)] * 3
        s, c = mpmath.sin(chi), mpmath.cos(chi)
        w[self.iX] = self.cX * s
        w[self.iY] = self.sY * self.cY * c
        w[self.iZ] = self.sZ * self.cZ * mpmath.sqrt(1 - self.m * s * s)
        return w

    def _quad(self, f, points, wdps: int) -> mpmath.mpf:
        value, error = mpmath.quad(f, points, error=True, maxdegree=12)
        if error > mpmath.mpf(10) ** -(wdps - 4):
            raise PrecisionNotReached("quadrature", wdps - 4, float(error))
        return value

    def _tau(self, chi_r, wdps: int) -> mpmath.mpf:
        """t(χ) − t(0) = ∫₀^χ dχ/(Ω√(1 − m sin²χ)), |χ| ≤ π/2."""
        f = lambda x: 1 / (self.Omega * mpmath.sqrt(1 - self.m * mpmath.sin(x) ** 2))  # noqa: E731
        return self._quad(f, [0, chi_r], wdps) if chi_r != 0 else mpmath.mpf(0)

    def quadrature_state(self, t, wdps: int) -> dict[str, mpmath.mpf]:
        pi = mpmath.pi
        half = 2 * self._tau(pi / 2, wdps)  # time for χ to advance by π
        j0 = mpmath.nint(self.chi0 / pi)
        target = t + j0 * half + self._tau(self.chi0 - j0 * pi, wdps)
        j = mpmath.nint(target / half)
        goal = target - j * half
        # Safeguarded Newton for τ(χ) = goal on [−π/2, π/2]; dτ/dχ = 1/(Ω√(1 − m sin²χ)).
        lo, hi = -pi / 2, pi / 2
        x = pi * goal / half
        tol = mpmath.mpf(10) ** -(wdps - 2)
        for _ in range(200):
            f = self._tau(x, wdps) - goal
            if f > 0:
                hi = x
            else:
                lo = x
            step = f * self.Omega * mpmath.sqrt(1 - self.m * mpmath.sin(x) ** 2)
            new = x - step
            if not lo < new < hi:
                new = (lo + hi) / 2
            if abs(new - x) < tol:
                x = new
                break
            x = new
        else:
            raise PrecisionNotReached("quadrature inversion t -> χ", wdps, float(hi - lo))
        chi = j * pi + x
        w = self.components_at_chi(chi)
        phi = self.s * (self.e2 - self.e3) * (mpmath.sin(chi) ** 2 - mpmath.sin(self.chi0) ** 2)
        psi = self._psi_phi_form(chi, wdps) - self._psi_phi_form(self.chi0, wdps)
        return {"p": w[0], "q": w[1], "r": w[2], "phi": phi, "psi": psi}

    def _psi_rate_chi(self, x) -> mpmath.mpf:
        """dΨ/dχ = (h + kr)/(k + Cr) · dt/dχ."""
        p, q, r = self.components_at_chi(x)
        rate = (self.h + self.k * r) / self.k_plus_Cr(r, self.A * p, self.B * q)
        return rate / (self.Omega * mpmath.sqrt(1 - self.m * mpmath.sin(x) ** 2))

    def _psi_phi_form(self, chi, wdps: int) -> mpmath.mpf:
        """∫₀^χ dΨ/dχ dχ, whole turns of χ (2π: one period of p, q, r) added as increments."""
        pi = mpmath.pi
        turns = mpmath.floor((chi + pi) / (2 * pi))
        rest = chi - 2 * turns * pi
        value = mpmath.mpf(0)
        if turns:
            full = self._quad(self._psi_rate_chi, _quarters(-pi, pi), wdps)
            value += turns * full
        if rest:
            value += self._quad(self._psi_rate_chi, _quarters(0, rest), wdps)
        return value

    def _components_at_t(self, t) -> list[mpmath.mpf]:
        u = self.Omega * t + self.u0
        sn, cn, dn = (mpmath.ellipfun(f, u, m=self.m) for f in ("sn", "cn", "dn"))
        w = [mpmath.mpf(0)] * 3
        w[self.iX], w[self.iY], w[self.iZ] = (
            self.cX * sn,
            self.sY * self.cY * cn,
            self.sZ * self.cZ * dn,
        )
        return w

    def _am(self, t) -> mpmath.mpf:
        u = self.Omega * t + self.u0
        j = mpmath.floor((u + self.K) / (2 * self.K))
        ur = u - 2 * j * self.K
        sn, cn = (mpmath.ellipfun(f, ur, m=self.m) for f in ("sn", "cn"))
        return j * mpmath.pi + mpmath.atan2(sn, cn)

    def psi_quadrature(self, t, form: str, wdps: int) -> mpmath.mpf:
        if form == "phi":
            return self._psi_phi_form(self._am(t), wdps) - self._psi_phi_form(self.chi0, wdps)
        if form == "time":

            def rate(x):
                p, q, r = self._components_at_t(x)
                return (self.h + self.k * r) / self.k_plus_Cr(r, self.A * p, self.B * q)

            T = self.period
            n = mpmath.floor(t / T)
            rest = t - n * T
            value = mpmath.mpf(0)
            if n:
                value += n * self._quad(rate, mpmath.linspace(0, T, 9), wdps)
            if rest:
                pieces = max(2, int(mpmath.ceil(8 * rest / T)) + 1)
                value += self._quad(rate, mpmath.linspace(0, rest, pieces), wdps)
            return value
        # r-form: from χ₀ to χ(t) over the quarters of χ, on each of which r is monotone.
        pi = mpmath.pi
        chi1 = self._am(t)
        turns = mpmath.floor((chi1 - self.chi0) / (2 * pi))
        value = mpmath.mpf(0)
        if turns:
            full = sum(self._r_form_piece(a, b, wdps) for a, b in _pairs(_quarters(0, 2 * pi)))
            value += turns * full
        start = self.chi0 + 2 * turns * pi
        for a, b in _pairs(_quarters(start, chi1)):
            value += self._r_form_piece(a, b, wdps)
        return value

    def _r_form_piece(self, chi_a, chi_b, wdps: int) -> mpmath.mpf:
        """Ψ increment while χ runs over [χ_a, χ_b] inside one quarter: ∫ G(r) dr, r monotone.

        Cayley's r-form: dΨ = (h + kr)/(k + Cr) · C√(AB) dr/√(b_p b_q) with the brackets
        b_p = k² − Bh + (B − C)Cr² = A(A − B)p², b_q = Ah − k² + (C − A)Cr² = B(A − B)q².
        r = r_a + Δ sin²θ; a bracket vanishing at an end (a zero of p or q) is formed as
        (r − r_end)(r + r_end)·coefficient with r − r_end = Δ sin²θ or −Δ cos²θ exactly, so the
        inverse square roots at the turning points cancel analytically.
        """
        A, B, C, h, k = self.A, self.B, self.C, self.h, self.k
        half = mpmath.pi / 2
        ra, rb = self.components_at_chi(chi_a)[2], self.components_at_chi(chi_b)[2]

        def root_of(chi) -> int | None:
            ratio = chi / half
            # Break points are built as j·π/2; the division may leave one ulp.
            if abs(ratio - mpmath.nint(ratio)) > mpmath.mpf(10) ** (-wdps // 2):
                return None
            vanishing = self.iX if int(mpmath.nint(ratio)) % 2 == 0 else self.iY
            return vanishing if vanishing != 2 else None

        end_a, end_b = root_of(chi_a), root_of(chi_b)
        coeff = {0: (B - C) * C, 1: (C - A) * C}
        const = {0: k * k - B * h, 1: A * h - k * k}
        delta = rb - ra

        def integrand(theta):
            s, c = mpmath.sin(theta), mpmath.cos(theta)
            r = ra + delta * s * s
            # dr = 2Δ sin θ cos θ dθ; a bracket vanishing at an end takes its factor away.
            scale = (s if end_a is None else 1) * (c if end_b is None else 1)
            product = mpmath.mpf(1)
            for i in (0, 1):
                if end_a == i:
                    product *= coeff[i] * delta * (r + ra)
                elif end_b == i:
                    product *= -coeff[i] * delta * (r + rb)
                else:
                    product *= const[i] + coeff[i] * r * r
            root = mpmath.sqrt(abs(product))
            # p, q for the robust k + Cr: only their squares matter there.
            ap2 = (const[0] + coeff[0] * r * r) * A / (A - B)
            bq2 = (const[1] + coeff[1] * r * r) * B / (A - B)
            kc = k + C * r if r >= 0 else (ap2 + bq2) / (k - C * r)
            return (h + k * r) / kc * C * mpmath.sqrt(A * B) * 2 * abs(delta) * scale / root

        return self._quad(integrand, [0, half], wdps) if delta else mpmath.mpf(0)


def _check_crossing_count(count: int, t0: mpmath.mpf, t1: mpmath.mpf) -> None:
    if count > MAX_CROSSINGS:
        raise ValueError(
            f"t_stop: [{mpmath.nstr(t0, 6)}, {mpmath.nstr(t1, 6)}] holds about "
            f"{mpmath.nstr(mpmath.mpf(count), 3)} crossings, more than {MAX_CROSSINGS}; ask for "
            "shorter windows"
        )


def _pi_circular(n: mpmath.mpf, chi: mpmath.mpf) -> mpmath.mpf:
    """Π(n; χ | 0) = arctan(√(1 − n) tan χ)/√(1 − n) for |χ| ≤ π/2, continuous at ±π/2."""
    root = mpmath.sqrt(1 - n)
    return mpmath.atan2(root * mpmath.sin(chi), mpmath.cos(chi)) / root


def _kind(I: Sequence[mpmath.mpf], w: Sequence[mpmath.mpf]) -> str:
    nonzero = [i for i in range(3) if w[i] != 0]
    if len(nonzero) == 1:
        return "steady"
    A, B, C = I
    if A == B == C:
        return "steady"  # every axis is principal: ω is constant
    if A == B or B == C or C == A:
        # Rotation about the symmetry axis alone, or within the equal-moment plane, is steady.
        i = next(i for i in range(3) if I[(i + 1) % 3] == I[(i + 2) % 3])
        if w[i] == 0:
            return "steady"
        return "symmetric"
    return "asymmetric"


def _quarters(a, b) -> list[mpmath.mpf]:
    """[a, …, b] with every multiple of π/2 strictly between them (quadrature break points)."""
    half = mpmath.pi / 2
    lo, hi = (a, b) if a <= b else (b, a)
    inner = [j * half for j in range(int(mpmath.floor(lo / half)) + 1, int(mpmath.ceil(hi / half)))]
    inner = [x for x in inner if lo < x < hi]
    points = [lo, *inner, hi]
    return points if a <= b else points[::-1]


def _pairs(points: list) -> list[tuple]:
    return list(zip(points[:-1], points[1:], strict=True))


def quaternion_rotate(q, v) -> list[mpmath.mpf]:
    """R(q) v."""
    R = quaternion_to_matrix(q)
    return [sum(R[i][j] * v[j] for j in range(3)) for i in range(3)]


#: The most invariable-plane crossings one call of ``crossing_times`` lists (each certified).
MAX_CROSSINGS = 10**6
