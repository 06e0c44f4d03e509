"""Soft Soil Creep (Vermeer & Neher 1999), backward Euler in time, with its consistent tangent.

The formulation of the PLAXIS Material Models manual (Soft Soil Creep model). Invariants
compression positive (:mod:`pilegroup.constitutive.critical_state`); stresses kPa, Mandel,
tension positive; time in days.

* Strain = elastic + creep (viscoplastic); no separate instantaneous plastic strain.
* Elasticity: ``K = p/kappa*``, exactly integrated over a step (``p = p_n exp(d eps_v^e/kappa*)``),
  ``G = 3 K_n (1 - 2 nu_ur)/(2 (1 + nu_ur))`` at the step's initial pressure.
* Equivalent pressure (an MCC ellipse): ``p_eq = p + q^2/(M^2 p)``, with ``M`` from ``K0nc``
  (:func:`critical_state.m_from_k0nc`, the manual's formula) and ``K0nc = 1 - sin phi`` unless
  given.
* Creep: ``d eps_v^c/dt = (mu*/tau) (p_eq/p_p^eq)^beta``, ``beta = (lambda* - kappa*)/mu*``;
  direction ``d p_eq/d sigma'`` (associated), so ``d eps_q^c = d eps_v^c 2 eta/(M^2 - eta^2)``;
  hardening ``p_p^eq = p_p0^eq exp(eps_v^c/(lambda* - kappa*))``.
* Backward Euler: with ``x = d eps_v^c`` and ``w = q_tr/q`` (radial deviatoric return,
  ``q = q_tr - 3 G d eps_q^c``) the step is two equations,
  ``E1 = (w - 1)(1 - b/w^2) - k = 0`` with ``b = q_tr^2/(M^2 p^2)``, ``k = 6 G x/(M^2 p)``
  (the deviatoric creep), and ``E2 = ln x - ln(dt mu*/tau) - beta ln(p_eq/p_p^eq) = 0`` (the rate),
  ``p = p_tr exp(-x/kappa*)``. ``E1`` gives ``w(x)`` (unique root ``w > max(1, sqrt b)``), then
  ``E2`` is increasing in ``ln x`` and solved by a bracketed Newton; the tangent follows from the
  linearised pair. At ``eta -> M`` the shear creep rate grows without bound, so the implicit
  step keeps ``eta < M``: the ellipse's top is a viscous limit on the shear stress.
* Constant effective stress: ``eps_v^c(t) = mu* ln(1 + t/tau_c)``,
  ``tau_c = tau (p_p^eq/p_eq)^beta`` at the start (Vermeer & Neher 1999; :meth:`creep_time`).
* Initial state: ``p_p^eq`` given, or from ``OCR``/``POP`` and the vertical effective stress
  (z vertical): ``sigma'_p = OCR sigma'_v0 + POP`` on the K0-NC line, ``p_p^eq = p_eq`` there,
  at least the ``p_eq`` of the initial stress (PLAXIS's initialisation).

**Limitation**: PLAXIS adds a Mohr–Coulomb failure surface (``c``, ``phi``, ``psi = 0``) as a
perfectly plastic cut-off; this law does not (``c`` is validated and kept for it, ``phi`` gives
``K0nc``). The shear stress is limited only by the viscous ellipse top ``q -> M p`` with the
``M`` of ``K0nc``, which lies above the Mohr–Coulomb line for soft clays; a failure check must
be made separately.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pilegroup.constitutive.base import as_points
from pilegroup.constitutive.critical_state import (
    ElasticTrial,
    bracketed_newton,
    initial_stress,
    k0_stress,
    m_from_k0nc,
    pq,
    pq_tangent,
    preconsolidation_vertical,
    require_ocr_pop,
    vertical_effective,
)
from pilegroup.errors import ConstitutiveError
from pilegroup.validate import require_in_range, require_non_negative, require_positive

__all__ = ["SoftSoilCreep", "ssc_creep_strain"]

#: ``ln x`` below which a creep increment is nil (``exp(-700) ~ 1e-304``).
LOG_X_MIN = -700.0


@dataclass(frozen=True)
class SoftSoilCreep:
    """Soft Soil Creep (Vermeer & Neher 1999) at material points (Mandel, kPa, day).

    Attributes:
        lambda_star: modified compression index, - (> kappa_star).
        kappa_star: modified swelling index, - (in (0, lambda_star)).
        mu_star: modified creep index, - (> 0).
        phi_deg: friction angle, deg (in (0, 90)); gives ``K0nc = 1 - sin phi`` by default.
        c: cohesion, kPa (>= 0; for the Mohr–Coulomb cut-off, not applied: module docstring).
        nu_ur: unloading–reloading Poisson's ratio, - (in (-1, 0.5); PLAXIS default 0.15).
        OCR: vertical over-consolidation ratio, - (in [1, 100]); or ``POP``, kPa (>= 0).
        K0nc: ``sigma'_h/sigma'_v`` of normal compression, - (in (0, 1)).
        tau: reference time, day (> 0; 1 day: the creep rate of a normally consolidated
            state is ``mu*/tau``, the standard oedometer's 24 h load steps).

    State (:meth:`state_layout`): ``stress`` (6, kPa), ``pp`` (1, ``p_p^eq``, kPa),
    ``eps_c`` (6, creep strain, Mandel, tension positive).
    """

    lambda_star: float
    kappa_star: float
    mu_star: float
    phi_deg: float
    c: float = 0.0
    nu_ur: float = 0.15
    OCR: float = 1.0
    POP: float = 0.0
    K0nc: float | None = None
    tau: float = 1.0

    def __post_init__(self) -> None:
        E = ConstitutiveError
        require_positive("lambda_star", self.lambda_star, "-", error=E)
        require_in_range("kappa_star", self.kappa_star, 0.0, self.lambda_star, "-",
                         lo_open=True, hi_open=True, why="0 < kappa_star < lambda_star", error=E)
        require_positive("mu_star", self.mu_star, "-", error=E)
        require_in_range("phi_deg", self.phi_deg, 0.0, 90.0, "deg", lo_open=True, hi_open=True,
                         error=E)
        require_non_negative("c", self.c, "kPa", error=E)
        require_in_range("nu_ur", self.nu_ur, -1.0, 0.5, "-", lo_open=True, hi_open=True,
                         error=E)
        require_ocr_pop(self.OCR, self.POP)
        if self.K0nc is not None:
            require_in_range("K0nc", self.K0nc, 0.0, 1.0, "-", lo_open=True, hi_open=True,
                             error=E)
        require_positive("tau", self.tau, "day", error=E)
        _ = self.m  # K0nc must give an ellipse

    @property
    def k0nc(self) -> float:
        """``K0nc`` in use: given, or Jaky's ``1 - sin phi``."""
        if self.K0nc is not None:
            return float(self.K0nc)
        return 1.0 - math.sin(math.radians(self.phi_deg))

    @cached_property
    def m(self) -> float:
        """Slope ``M`` of the ``p_eq`` ellipse, from ``K0nc`` (the manual's formula), -."""
        return m_from_k0nc(self.k0nc, self.lambda_star, self.kappa_star, self.nu_ur)

    @property
    def beta(self) -> float:
        """Creep exponent ``(lambda* - kappa*)/mu*``, -."""
        return (self.lambda_star - self.kappa_star) / self.mu_star

    #: ``initial_state`` needs the in-situ effective stress (the solver gives it at the start).
    needs_initial_stress = True

    def elastic_moduli(self, p: float) -> tuple[float, float]:
        """Bulk and shear moduli (kPa) at the mean effective stress ``p`` (kPa).

        ``K = p/kappa*``, ``G = 3K(1 - 2 nu_ur)/(2(1 + nu_ur))``: the tangent moduli of the
        elastic part there (the solver's representative moduli, docs/model.md).
        """
        K = p / self.kappa_star
        return K, 1.5 * K * (1.0 - 2.0 * self.nu_ur) / (1.0 + self.nu_ur)

    def state_layout(self) -> dict[str, int]:
        """State name -> components per point."""
        return {"stress": 6, "pp": 1, "eps_c": 6}

    def equivalent_pressure(self, stress: np.ndarray) -> np.ndarray:
        """``p_eq = p + q^2/(M^2 p)`` (kPa) of Mandel stresses ``(n, 6)``."""
        p, q, _ = pq(as_points(stress, 6, "stress"))
        return p + q * q / (self.m**2 * p)

    def creep_time(self, stress: np.ndarray, pp: np.ndarray) -> np.ndarray:
        """``tau_c = tau (p_p^eq/p_eq)^beta`` (day) of stresses ``(n, 6)`` and ``p_p^eq``.

        Under this stress held constant the creep strain grows as ``mu* ln(1 + t/tau_c)``
        (:func:`ssc_creep_strain`).
        """
        ratio = np.asarray(pp, dtype=float).reshape(-1) / self.equivalent_pressure(stress)
        return self.tau * ratio**self.beta

    def initial_state(self, n: int, stress0: np.ndarray | None = None,
                      pp0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points.

        Args:
            n: number of points.
            stress0: effective stress (Mandel, kPa, ``(6,)`` or ``(n, 6)``), ``p' > 0``.
            pp0: ``p_p^eq`` (kPa, scalar or ``(n,)``); default from ``OCR``/``POP`` (module
                docstring). Raised to the ``p_eq`` of ``stress0`` if lower.
        """
        s0, _, _ = initial_stress(n, stress0, "Soft Soil Creep")
        peq0 = self.equivalent_pressure(s0)
        if pp0 is None:
            sp = preconsolidation_vertical(vertical_effective(s0), self.OCR, self.POP)
            pp = self.equivalent_pressure(k0_stress(sp, self.k0nc))
        else:
            pp = np.broadcast_to(np.asarray(pp0, dtype=float), (n,))
        return {"stress": s0, "pp": np.maximum(pp, peq0)[:, None].copy(),
                "eps_c": np.zeros((n, 6))}

    def update(self, d_strain: np.ndarray, state_n: dict[str, np.ndarray], dt: float
               ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Stress, trial state and consistent tangent of the increment ``d_strain`` over ``dt``.

        Args:
            d_strain: (n, 6) Mandel strain increment, tension positive.
            state_n: committed state (not mutated).
            dt: time step, day; ``dt <= 0`` is an instantaneous (elastic) step.

        Returns:
            ``(stress, state_trial, tangent)``: stress (n, 6) kPa, tangent (n, 6, 6) kPa.
        """
        de = as_points(d_strain, 6, "d_strain")
        tr = ElasticTrial(de, state_n["stress"], self.kappa_star, ("nu", self.nu_ur))
        n = de.shape[0]
        ppn = state_n["pp"][:, 0]
        if dt > 0.0:
            p, a, pp, dp, da = self._creep(tr, ppn, dt)
        else:
            p, a, pp = tr.p_tr.copy(), np.ones(n), ppn.copy()
            dp, da = np.zeros((n, 2)), np.zeros((n, 2))
            dp[:, 0] = 1.0
        stress, D = pq_tangent(tr, p, a, dp, da)
        _, _, s = pq(stress)
        eps_c = state_n["eps_c"] + de - tr.elastic_part(p, s)
        if dt <= 0.0:
            eps_c = state_n["eps_c"].copy()
        return stress, {"stress": stress, "pp": pp[:, None], "eps_c": eps_c}, D

    # -- the implicit step ------------------------------------------------------------------
    def _w(self, x: np.ndarray, p: np.ndarray, Q: np.ndarray, G: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``w = q_tr/q`` of the creep increments ``x``: the root of ``E1``; and ``b``, ``k``."""
        M2 = self.m**2
        b = Q / (M2 * p * p)
        k = 6.0 * G * x / (M2 * p)
        lo = np.maximum(1.0, np.sqrt(b))

        def e1(w: np.ndarray, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            bi = b[i]
            return ((w - 1.0) * (1.0 - bi / (w * w)) - k[i],
                    1.0 - bi / (w * w) + 2.0 * bi * (w - 1.0) / w**3)

        w = bracketed_newton(e1, lo, np.maximum(2.0 * lo, 3.0 * k), lo + k,
                             what="Soft Soil Creep deviatoric return")
        return w, b, k

    def _e2(self, xi: np.ndarray, p_tr: np.ndarray, Q: np.ndarray, G: np.ndarray,
            ppn: np.ndarray, L0: float) -> tuple[np.ndarray, ...]:
        """``E2`` at ``xi = ln x`` (``w`` solved), ``dE2/dxi`` and the state there."""
        ks, th, beta = self.kappa_star, self.lambda_star - self.kappa_star, self.beta
        x = np.exp(xi)
        p = p_tr * np.exp(-x / ks)
        w, b, k = self._w(x, p, Q, G)
        w2 = w * w
        E2 = xi - L0 - beta * (np.log(p) + np.log1p(b / w2) - np.log(ppn) - x / th)
        e1_xi = -2.0 * b * (w - 1.0) * x / (w2 * ks) - k * (1.0 + x / ks)
        e1_w = 1.0 - b / w2 + 2.0 * b * (w - 1.0) / (w2 * w)
        e2_xi = 1.0 + x * (beta / th + beta * (w2 - b) / ((w2 + b) * ks))
        e2_w = 2.0 * beta * b / (w * (w2 + b))
        return E2, e2_xi - e2_w * e1_xi / e1_w, x, p, w, b, k

    def _creep(self, tr: ElasticTrial, ppn: np.ndarray, dt: float) -> tuple[np.ndarray, ...]:
        """Backward-Euler creep step of every point: p, a = 1/w, p_p, d(p, a)/d(p_tr, Q)."""
        ks, th, beta, M2 = self.kappa_star, self.lambda_star - self.kappa_star, self.beta, self.m**2
        p_tr, Q, G = tr.p_tr, tr.Q, tr.G
        L0 = math.log(dt * self.mu_star / self.tau)
        # bracket: p_eq <= 2p <= 2p_tr and p_p >= p_pn give E2 >= xi - C + beta c1 x
        C = L0 + beta * np.log(2.0 * p_tr / ppn)
        c1 = 1.0 / ks + 1.0 / th
        hi = np.minimum(C + 1.0, np.log((np.maximum(C, 0.0) + 751.0) / (beta * c1)))
        lo = np.minimum(LOG_X_MIN, hi - 1.0)
        # explicit estimate (the trial rate): to the right of the root
        x0 = L0 + beta * np.log((p_tr + Q / (M2 * p_tr)) / ppn)

        def F(xi: np.ndarray, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            r = self._e2(xi, p_tr[i], Q[i], G[i], ppn[i], L0)
            return r[0], r[1]

        xi = bracketed_newton(F, lo, hi, np.minimum(x0, hi), xtol=1e-15,
                              what="Soft Soil Creep rate equation")
        _, _, x, p, w, b, k = self._e2(xi, p_tr, Q, G, ppn, L0)
        w2 = w * w
        J = np.empty((x.size, 2, 2))  # rows E1, E2; columns (xi, w)
        J[:, 0, 0] = -2.0 * b * (w - 1.0) * x / (w2 * ks) - k * (1.0 + x / ks)
        J[:, 0, 1] = 1.0 - b / w2 + 2.0 * b * (w - 1.0) / (w2 * w)
        J[:, 1, 0] = 1.0 + x * (beta / th + beta * (w2 - b) / ((w2 + b) * ks))
        J[:, 1, 1] = 2.0 * beta * b / (w * (w2 + b))
        B = np.empty((x.size, 2, 2))  # d (E1, E2) / d (p_tr, Q)
        B[:, 0, 0] = (2.0 * b * (w - 1.0) / w2 + k) / p_tr
        B[:, 0, 1] = -(w - 1.0) / (w2 * M2 * p * p)
        B[:, 1, 0] = -beta * (w2 - b) / ((w2 + b) * p_tr)
        B[:, 1, 1] = -beta / ((w2 + b) * M2 * p * p)
        X = -np.linalg.solve(J, B)  # d (xi, w) / d (p_tr, Q)
        dp = np.column_stack([p / p_tr - p * x / ks * X[:, 0, 0], -p * x / ks * X[:, 0, 1]])
        da = -X[:, 1, :] / w2[:, None]
        return p, 1.0 / w, ppn * np.exp(x / th), dp, da


def ssc_creep_strain(t: np.ndarray, tau_c: float, mu_star: float) -> np.ndarray:
    """Volumetric creep strain under constant effective stress: ``mu* ln(1 + t/tau_c)``.

    Vermeer & Neher (1999): with ``p_eq`` constant the rate equation integrates to this
    logarithmic law, ``tau_c = tau (p_p^eq/p_eq)^beta`` at ``t = 0`` (compression positive).
    """
    return mu_star * np.log1p(np.asarray(t, dtype=float) / tau_c)
