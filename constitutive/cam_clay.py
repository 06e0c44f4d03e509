"""Modified Cam Clay (Roscoe & Burland 1968), integrated implicitly, with its consistent tangent.

Invariants compression positive (``p``, ``q``, ``eps_v``;
:mod:`pilegroup.constitutive.critical_state`); stresses kPa, Mandel, tension positive. Wood
(1990), *Soil behaviour and critical state soil mechanics* (Cambridge University Press), is the
reference for the model and its closed forms.

* Yield surface (ellipse through the origin and ``p_c``), associated flow:
  ``f = q^2/M^2 + p (p - p_c)``, ``d eps_v^p = dgamma (2p - p_c)``,
  ``d eps_q^p = dgamma 2q/M^2``.
* Hardening: ``p_c = p_c0 exp(eps_v^p (1 + e0)/(lambda - kappa))``.
* Elasticity: ``K = (1 + e0) p/kappa`` integrated exactly over a step, ``G`` from a constant
  ``nu`` at the step's initial pressure or a constant ``G`` (critical_state's docstring).
* Return mapping (backward Euler, exact exponentials): unknowns the multiplier ``dgamma`` and
  ``d eps_v^p``; ``p = p_tr exp(-d eps_v^p/k)``, ``p_c = p_cn exp(d eps_v^p/(l - k))``,
  ``q = q_tr/(1 + 6 G dgamma/M^2)``; the outer scalar equation ``f(dgamma) = 0`` and the inner
  ``d eps_v^p = dgamma (2p - p_c)`` are each solved by a bracketed Newton (a root exists:
  ``f(0) > 0`` and ``f -> -p^2 < 0`` as ``dgamma -> inf``). The consistent tangent follows from
  the linearised pair of equations at the solution (:func:`critical_state.pq_tangent`).
* Initial state: the pre-consolidation pressure ``p_c`` of each point is given, or computed
  from the law's ``OCR``/``POP`` and the vertical effective stress (z vertical): the vertical
  pre-consolidation stress ``sigma'_p = OCR sigma'_v0 + POP`` on the K0-NC line
  (``sigma'_h = K0nc sigma'_p``), ``p_c = p + q^2/(M^2 p)`` there, and never less than the
  ``p_c`` through the initial stress itself (so the state is on or inside the surface).

``dt`` is accepted and ignored (rate independent). Strains are small: ``(1 + e0)`` is fixed, the
void ratio of a point is ``e0 - (1 + e0) eps_v``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pilegroup.constitutive.base import as_points
from pilegroup.constitutive.critical_state import (
    ElasticTrial,
    bracketed_newton,
    eta_k0nc,
    initial_stress,
    k0_stress,
    m_from_phi,
    pq,
    pq_tangent,
    preconsolidation_vertical,
    require_ocr_pop,
    shear_ratio,
    vertical_effective,
)
from pilegroup.errors import ConstitutiveError
from pilegroup.validate import require_in_range, require_positive

__all__ = ["ModifiedCamClay", "mcc_undrained_path"]


def _require_one(a: str, va: float | None, b: str, vb: float | None) -> None:
    if (va is None) == (vb is None):
        raise ConstitutiveError(f"give exactly one of {a} and {b} (got {a} = {va}, {b} = {vb})")


@dataclass(frozen=True)
class ModifiedCamClay:
    """Modified Cam Clay (Roscoe & Burland 1968) at material points (Mandel, kPa).

    Attributes:
        lam: slope lambda of the normal compression line in ``e``–``ln p'``, - (> kappa).
        kappa: slope kappa of the unloading–reloading line, - (in (0, lam)).
        e0: initial void ratio, - (in (0, 10]).
        M: critical-state stress ratio, - (in (0, 3)); or ``phi_cs_deg`` (in (0, 90)),
            ``M = 6 sin phi/(3 - sin phi)``. Exactly one of the two.
        nu: Poisson's ratio, - (in (-1, 0.5)), ``G = 3K(1 - 2nu)/(2(1 + nu))``; or ``G``, a
            constant shear modulus, kPa (> 0). Exactly one of the two.
        OCR: vertical over-consolidation ratio, - (in [1, 100]); or ``POP``, kPa (>= 0).
        K0nc: ``sigma'_h/sigma'_v`` of normal compression, - (in (0, 1)); default: the ratio
            of this law's own oedometric flow (:meth:`k0nc`).

    State (:meth:`state_layout`): ``stress`` (6, kPa), ``pc`` (1, kPa, compression positive),
    ``eps_p`` (6, plastic strain, Mandel, tension positive), ``mode`` (1: 0 elastic, 1 plastic).
    """

    lam: float
    kappa: float
    e0: float
    M: float | None = None
    phi_cs_deg: float | None = None
    nu: float | None = None
    G: float | None = None
    OCR: float = 1.0
    POP: float = 0.0
    K0nc: float | None = None

    def __post_init__(self) -> None:
        require_positive("lam", self.lam, "-", error=ConstitutiveError)
        require_in_range("kappa", self.kappa, 0.0, self.lam, "-", lo_open=True, hi_open=True,
                         why="0 < kappa < lam", error=ConstitutiveError)
        require_in_range("e0", self.e0, 0.0, 10.0, "-", lo_open=True, error=ConstitutiveError)
        _require_one("M", self.M, "phi_cs_deg", self.phi_cs_deg)
        if self.M is not None:
            require_in_range("M", self.M, 0.0, 3.0, "-", lo_open=True, hi_open=True,
                             error=ConstitutiveError)
        else:
            require_in_range("phi_cs_deg", self.phi_cs_deg, 0.0, 90.0, "deg", lo_open=True,
                             hi_open=True, error=ConstitutiveError)
        _require_one("nu", self.nu, "G", self.G)
        if self.nu is not None:
            require_in_range("nu", self.nu, -1.0, 0.5, "-", lo_open=True, hi_open=True,
                             error=ConstitutiveError)
        else:
            require_positive("G", self.G, "kPa", error=ConstitutiveError)
        require_ocr_pop(self.OCR, self.POP)
        if self.K0nc is not None:
            require_in_range("K0nc", self.K0nc, 0.0, 1.0, "-", lo_open=True, hi_open=True,
                             error=ConstitutiveError)

    # -- derived constants ------------------------------------------------------------------
    @cached_property
    def m(self) -> float:
        """The critical-state ratio M in use, -."""
        return float(self.M) if self.M is not None else m_from_phi(float(self.phi_cs_deg))

    @property
    def lam_t(self) -> float:
        """``lambda/(1 + e0)``, -."""
        return self.lam / (1.0 + self.e0)

    @property
    def kap_t(self) -> float:
        """``kappa/(1 + e0)``, -."""
        return self.kappa / (1.0 + self.e0)

    @property
    def shear(self) -> tuple[str, float]:
        """``("nu", nu)`` or ``("G", G)``: how the shear modulus is made."""
        return ("nu", float(self.nu)) if self.nu is not None else ("G", float(self.G))

    def k0nc(self) -> float:
        """``K0nc`` used for the initial state: given, or this law's own.

        With ``nu``: the ratio ``eta`` at which oedometric normal compression goes on at
        constant ``eta`` (:func:`critical_state.eta_k0nc`), ``K0 = (3 - eta)/(3 + 2 eta)``. With
        a constant ``G`` no constant ratio exists; then Jaky's ``1 - sin phi_cs``, with
        ``sin phi_cs = 3M/(6 + M)``.
        """
        if self.K0nc is not None:
            return float(self.K0nc)
        if self.nu is None:
            return 1.0 - 3.0 * self.m / (6.0 + self.m)
        eta = eta_k0nc(self.m, self.lam_t, self.kap_t, shear_ratio(self.kap_t, float(self.nu)))
        return (3.0 - eta) / (3.0 + 2.0 * eta)

    #: ``initial_state`` needs the in-situ effective stress (the solver gives it at the start).
    needs_initial_stress = True

    def elastic_moduli(self, p: float) -> tuple[float, float]:
        """Bulk and shear moduli (kPa) at the mean effective stress ``p`` (kPa).

        ``K = p/kappa~`` and ``G`` from ``nu`` (or the constant ``G``): the tangent moduli of
        the elastic part there (the solver's representative moduli, docs/model.md).
        """
        K = p / self.kap_t
        if self.nu is None:
            return K, float(self.G)
        return K, 1.5 * K * (1.0 - 2.0 * self.nu) / (1.0 + self.nu)

    # -- protocol ---------------------------------------------------------------------------
    def state_layout(self) -> dict[str, int]:
        """State name -> components per point."""
        return {"stress": 6, "pc": 1, "eps_p": 6, "mode": 1}

    def preconsolidation(self, stress0: np.ndarray) -> np.ndarray:
        """``p_c`` (kPa, ``(n,)``) of initial stresses ``(n, 6)`` from ``OCR``/``POP``.

        ``sigma'_p = OCR sigma'_v0 + POP`` on the K0-NC line, at least the ``p_c`` through the
        initial stress (module docstring).
        """
        sp = preconsolidation_vertical(vertical_effective(stress0), self.OCR, self.POP)
        p_nc, q_nc, _ = pq(k0_stress(sp, self.k0nc()))
        p0, q0, _ = pq(stress0)
        return np.maximum(self.pc_through(p_nc, q_nc), self.pc_through(p0, q0))

    def pc_through(self, p: np.ndarray, q: np.ndarray) -> np.ndarray:
        """``p_c`` of the ellipse through ``(p, q)``: ``p + q^2/(M^2 p)``, kPa."""
        return p + q * q / (self.m**2 * p)

    def initial_state(self, n: int, stress0: np.ndarray | None = None,
                      pc0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points.

        Args:
            n: number of points.
            stress0: effective stress (Mandel, kPa, ``(6,)`` or ``(n, 6)``); required, with
                ``p' > 0``.
            pc0: pre-consolidation pressure (kPa, scalar, ``(n,)``); default
                :meth:`preconsolidation`. Raised to the ``p_c`` through ``stress0`` if lower.
        """
        s0, p0, q0 = initial_stress(n, stress0, "Modified Cam Clay")
        if pc0 is None:
            pc = self.preconsolidation(s0)
        else:
            pc = np.maximum(np.broadcast_to(np.asarray(pc0, dtype=float), (n,)),
                            self.pc_through(p0, q0))
        return {"stress": s0, "pc": pc[:, None].copy(), "eps_p": np.zeros((n, 6)),
                "mode": np.zeros((n, 1))}

    def yield_function(self, stress: np.ndarray, pc: np.ndarray) -> np.ndarray:
        """``f = q^2/M^2 + p (p - p_c)`` (kPa^2) of Mandel stresses; f <= 0 admissible."""
        p, q, _ = pq(as_points(stress, 6, "stress"))
        return q * q / self.m**2 + p * (p - np.asarray(pc, dtype=float).reshape(-1))

    def update(self, d_strain: np.ndarray, state_n: dict[str, np.ndarray], dt: float = 0.0
               ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Stress, trial state and consistent tangent for the increment ``d_strain``.

        Args:
            d_strain: (n, 6) Mandel strain increment, tension positive.
            state_n: committed state (not mutated).
            dt: time step, day (ignored).

        Returns:
            ``(stress, state_trial, tangent)``: stress (n, 6) kPa, tangent (n, 6, 6) kPa.
        """
        de = as_points(d_strain, 6, "d_strain")
        tr = ElasticTrial(de, state_n["stress"], self.kap_t, self.shear)
        n = de.shape[0]
        pcn = state_n["pc"][:, 0]
        M2 = self.m**2
        p, a, pc = tr.p_tr.copy(), np.ones(n), pcn.copy()
        dp, da = np.zeros((n, 2)), np.zeros((n, 2))
        dp[:, 0] = 1.0
        f_tr = tr.Q / M2 + tr.p_tr * (tr.p_tr - pcn)
        plastic = f_tr > 1e-12 * pcn * pcn
        mode = np.zeros((n, 1))
        if np.any(plastic):
            k = np.nonzero(plastic)[0]
            p[k], a[k], pc[k], dp[k], da[k] = self._return(tr.p_tr[k], tr.Q[k], tr.G[k], pcn[k])
            mode[k, 0] = 1.0
        stress, D = pq_tangent(tr, p, a, dp, da)
        _, _, s = pq(stress)
        eps_p = state_n["eps_p"] + de - tr.elastic_part(p, s)
        eps_p[~plastic] = state_n["eps_p"][~plastic]
        trial = {"stress": stress, "pc": pc[:, None], "eps_p": eps_p, "mode": mode}
        return stress, trial, D

    # -- return mapping ---------------------------------------------------------------------
    def _ev(self, dg: np.ndarray, p_tr: np.ndarray, pcn: np.ndarray) -> np.ndarray:
        """Plastic volumetric strain increment of a multiplier: ``ev = dg (2p - p_c)``."""
        kt, th = self.kap_t, self.lam_t - self.kap_t
        star = np.log(2.0 * p_tr / pcn) / (1.0 / kt + 1.0 / th)

        def g(ev: np.ndarray, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            pp, pcc = p_tr[i] * np.exp(-ev / kt), pcn[i] * np.exp(ev / th)
            return ev - dg[i] * (2.0 * pp - pcc), 1.0 + dg[i] * (2.0 * pp / kt + pcc / th)

        return bracketed_newton(g, np.minimum(star, 0.0), np.maximum(star, 0.0),
                                np.zeros_like(star), what="Cam Clay volumetric return")

    def _residual(self, dg: np.ndarray, p_tr: np.ndarray, Q: np.ndarray, G: np.ndarray,
                  pcn: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``-f/p_cn^2`` at the multipliers ``dg``, its derivative, and ``ev``."""
        kt, th, M2 = self.kap_t, self.lam_t - self.kap_t, self.m**2
        ev = self._ev(dg, p_tr, pcn)
        p, pc = p_tr * np.exp(-ev / kt), pcn * np.exp(ev / th)
        a = 1.0 / (1.0 + 6.0 * G * dg / M2)
        f = Q * a * a / M2 + p * (p - pc)
        f_ev = -(2.0 * p - pc) * p / kt - p * pc / th
        g_ev = 1.0 + dg * (2.0 * p / kt + pc / th)
        df = -12.0 * G * Q * a**3 / M2**2 + f_ev * (2.0 * p - pc) / g_ev
        return -f / pcn**2, -df / pcn**2, ev

    def _return(self, p_tr: np.ndarray, Q: np.ndarray, G: np.ndarray, pcn: np.ndarray
                ) -> tuple[np.ndarray, ...]:
        """Return of trial states outside the surface: p, a, p_c and d(p, a)/d(p_tr, Q)."""
        kt, th, M2 = self.kap_t, self.lam_t - self.kap_t, self.m**2
        f0 = Q / M2 + p_tr * (p_tr - pcn)
        slope = (12.0 * G * Q / M2**2 + (2.0 * p_tr - pcn) ** 2 * p_tr / kt
                 + np.maximum(p_tr * pcn * (2.0 * p_tr - pcn) / th, 0.0))  # |df/dgamma| at 0
        guess = f0 / np.maximum(slope, 1e-300)
        hi = 2.0 * guess
        for _ in range(200):  # widen until f(hi) < 0
            F_hi = self._residual(hi, p_tr, Q, G, pcn)[0]
            if np.all(F_hi > 0.0):
                break
            hi = np.where(F_hi > 0.0, hi, 4.0 * hi)
        else:  # pragma: no cover - f -> -p^2 as dgamma grows: always found
            raise ConstitutiveError("Cam Clay return: no bracket of the multiplier")

        def F(u: np.ndarray, i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            # in u = dgamma p_cn (dimensionless, of the order of the plastic strain)
            r, dr, _ = self._residual(u / pcn[i], p_tr[i], Q[i], G[i], pcn[i])
            return r, dr / pcn[i]

        u = bracketed_newton(F, np.zeros_like(hi), hi * pcn, np.minimum(guess, hi) * pcn,
                             what="Cam Clay return mapping")
        dg = u / pcn
        ev = self._ev(dg, p_tr, pcn)
        p, pc = p_tr * np.exp(-ev / kt), pcn * np.exp(ev / th)
        a = 1.0 / (1.0 + 6.0 * G * dg / M2)
        # linearised equations R1 = ev - dg (2p - pc), R2 = Q a^2/M^2 + p (p - pc) in (ev, dg)
        J = np.empty((p.size, 2, 2))
        J[:, 0, 0] = 1.0 + dg * (2.0 * p / kt + pc / th)
        J[:, 0, 1] = -(2.0 * p - pc)
        J[:, 1, 0] = -(2.0 * p - pc) * p / kt - p * pc / th
        J[:, 1, 1] = -12.0 * G * Q * a**3 / M2**2
        B = np.zeros((p.size, 2, 2))  # d R / d (p_tr, Q)
        B[:, 0, 0] = -2.0 * dg * p / p_tr
        B[:, 1, 0] = (2.0 * p - pc) * p / p_tr
        B[:, 1, 1] = a * a / M2
        X = -np.linalg.solve(J, B)  # d (ev, dg) / d (p_tr, Q)
        dp = np.column_stack([p / p_tr - p / kt * X[:, 0, 0], -p / kt * X[:, 0, 1]])
        da = -(a * a * 6.0 * G / M2)[:, None] * X[:, 1, :]
        return p, a, pc, dp, da


def mcc_undrained_path(p0: float, eta: np.ndarray, law: ModifiedCamClay) -> np.ndarray:
    """Closed form of the undrained effective stress path from an isotropic NC state.

    ``p'/p'_0 = (M^2/(M^2 + eta^2))^Lambda``, ``Lambda = (lambda - kappa)/lambda`` (Wood 1990:
    constant volume, the state on the yield surface ``p_c = p'(M^2 + eta^2)/M^2``).
    """
    lam_big = (law.lam - law.kappa) / law.lam
    m2 = law.m**2
    return p0 * (m2 / (m2 + np.asarray(eta, dtype=float) ** 2)) ** lam_big

