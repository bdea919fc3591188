"""Encke's formulation (``orbit.formulation = "encke"``, ``cayley_heyoka/orbit/encke.py``) with
its bookkeeping replaced: the library's rectification handler timed (for the share of the wall
time it takes), and two diagnostics of the formulation's design, with the ellipse's anomaly
solved from Kepler's equation inside the equations (heyoka's ``kepE``, as the prototype that
preceded the library formulation did) instead of integrated: on a clock τ reset at each
rectification, and on heyoka's global time, ``M₀ + n((t − T_hi) − T_lo)`` (heyoka hands its
equations only the leading double of its double-length time)."""

from __future__ import annotations

import contextlib
import math
import time
import types
from typing import Any

import heyoka as hy
import numpy as np

import cayley_heyoka.orbit.encke as encke_module
import cayley_heyoka.orbit.model as orbit_model
from cayley_heyoka.core import structures

from .case import LD, exact_text


# ------------------------------------------------------------ Encke: the handler's share of time
class TimedEncke(encke_module.Encke):
    """The library's rectification handler, timed (for the share of the wall time it takes)."""

    seconds = 0.0

    def __call__(self, ta: Any, pars: Any) -> str | None:
        t0 = time.perf_counter()
        out = super().__call__(ta, pars)
        TimedEncke.seconds += time.perf_counter() - t0
        return out


class KeplerClockEncke(encke_module.Encke):
    """Diagnostic: the ellipse's anomaly solved from Kepler's equation by heyoka's ``kepE``,
    ``E − e sin E = M₀ + ν τ``, on a clock τ (τ̇ = c, a power of two with c × period ≤ ½,
    reset at each rectification: the state's last slot), instead of integrated. Everything
    else is the library's. The rectification event stays on τ (< 1)."""

    EXTRA = ("M0", "nu", "clock_rate", "tau_next", "T_hi", "T_lo")

    def __init__(self, pars: Any, precision: Any, mu: Any, values: Any) -> None:
        super().__init__(pars, precision, mu, values)
        self.extra = {k: pars.add(f"encke.{k}", values[f"encke.{k}"]) for k in self.EXTRA}
        self.extra_index = {k: pars.index(f"encke.{k}") for k in self.EXTRA}

    def phase(self, tau: Any) -> Any:
        q = self.extra
        return q["M0"] + q["nu"] * tau

    def curve(self, tau: Any) -> tuple[list, list, dict]:
        E = hy.kepE(self.par["e"], self.phase(tau))
        y, ydot, parts = self.ellipse(hy.sin(0.5 * E), hy.cos(0.5 * E))
        parts["psi_rate"] = self.extra["clock_rate"]
        return y, ydot, parts

    def event(self, tau: Any) -> Any:
        return tau - self.extra["tau_next"]

    def phase_now(self, ta: Any, pars: Any) -> Any:
        """M at the integrator's state, in long double."""
        v = {k: LD(float(pars[i])) for k, i in self.extra_index.items()}
        return v["M0"] + v["nu"] * LD(float(ta.state[6]))

    def anomaly(self, ta: Any, pars: Any) -> Any:
        return _kepler_ld(LD(float(pars[self.index["e"]])), self.phase_now(ta, pars))

    @classmethod
    def start(cls, numbers: Any) -> Any:
        """The library's start (its ellipse and (δ, ψ) among ``numbers``) moved to the phase."""
        values = dict(numbers.values)
        p = {k: LD(float(values[f"encke.{k}"])) for k in encke_module.PARAMETERS}
        st = [LD(float(c)) for c in numbers.initial_state]
        extra = cls._to_kepler_phase(p, st, (0.0, 0.0))
        values |= {f"encke.{k}": exact_text(value) for k, value in extra.items()}
        return type(numbers)([float(c) for c in st], values)

    def __call__(self, ta: Any, pars: Any) -> str | None:
        out = super().__call__(ta, pars)
        if out is None:
            p = {k: LD(float(pars[i])) for k, i in self.index.items()}
            st = [LD(float(c)) for c in ta.state]
            extra = self._to_kepler_phase(p, st, ta.dtime)
            for k, value in extra.items():
                pars[self.extra_index[k]] = value
            ta.state[:] = [float(c) for c in st]
        return out

    @staticmethod
    def _to_kepler_phase(p: dict, st: list, dtime: tuple) -> dict[str, float]:
        """From the library's rectified state (δ at E₀ = 2ψ₀): the phase M₀ rounded to double,
        δ moved to the anomaly kepE returns for it (in long double), τ = 0, and the clock."""
        e, E0 = p["e"], 2 * st[6]
        M0 = float(E0 - e * np.sin(E0))
        ar = types.SimpleNamespace(sin=np.sin, cos=np.cos)  # long double, by numpy
        y0, v0 = encke_module.ellipse_state(ar, p, E0)
        y1, v1 = encke_module.ellipse_state(ar, p, _kepler_ld(e, LD(M0)))
        for i in range(3):
            st[i] += y0[i] - y1[i]
            st[3 + i] += v0[i] - v1[i]
        st[6] = LD(0)
        n = float(p["n"])
        period = 2 * math.pi / n
        k = math.ceil(math.log2(2 * period))
        to_apocentre = (math.pi - M0) / n
        if to_apocentre <= period / 4:
            to_apocentre += period
        hi, lo = dtime
        return {
            "M0": M0,
            "nu": math.ldexp(n, k),
            "clock_rate": math.ldexp(1.0, -k),
            "tau_next": math.ldexp(to_apocentre, -k),
            "T_hi": float(hi),
            "T_lo": float(lo),
        }


class KeplerGlobalTimeEncke(KeplerClockEncke):
    """Diagnostic: as :class:`KeplerClockEncke`, with the phase on heyoka's global time,
    ``M₀ + n((t − T_hi) − T_lo)``, T the rectification time held exactly in two parameters
    (heyoka hands the equations only the leading double of t)."""

    def phase(self, tau: Any) -> Any:
        q = self.extra
        return q["M0"] + self.par["n"] * ((hy.time - q["T_hi"]) - q["T_lo"])

    def phase_now(self, ta: Any, pars: Any) -> Any:
        hi, lo = ta.dtime
        T = LD(float(pars[self.extra_index["T_hi"]])) + LD(float(pars[self.extra_index["T_lo"]]))
        n = LD(float(pars[self.index["n"]]))
        return LD(float(pars[self.extra_index["M0"]])) + n * ((LD(hi) - T) + LD(lo))


def _kepler_ld(e: Any, M: Any) -> Any:
    """E − e sin E = M in long double: Newton in double from Danby's start, then in long
    double until the step is below √ε, and once more."""
    two_pi = 2 * np.arccos(LD(-1))
    M = M - two_pi * np.rint(M / two_pi)
    ed, Md = float(e), float(M)
    E = Md + math.copysign(0.85 * ed, math.sin(Md))
    for _ in range(50):
        step = (E - ed * math.sin(E) - Md) / (1 - ed * math.cos(E))
        E -= step
        if abs(step) < 1e-12:
            break
    E = LD(E)
    for _ in range(3):
        E -= (E - e * np.sin(E) - M) / (1 - e * np.cos(E))
    return E


@contextlib.contextmanager
def encke_variant(cls: type) -> Any:
    """Build ``formulation = "encke"`` scenes with ``cls`` for the Encke bookkeeping (the
    structures built before and within are forgotten: each is built with its own class)."""
    saved, numbers = orbit_model.Encke, orbit_model.variant_numbers
    orbit_model.Encke = cls
    if hasattr(cls, "start"):

        def moved(scene: Any, variant: Any) -> Any:
            given = numbers(scene, variant)
            return cls.start(given) if scene.model.formulation == "encke" else given

        orbit_model.variant_numbers = moved
    structures.clear()
    try:
        yield
    finally:
        orbit_model.Encke, orbit_model.variant_numbers = saved, numbers
        structures.clear()
