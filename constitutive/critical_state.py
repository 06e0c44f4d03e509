"""What the critical-state soil laws share (p–q invariants, elasticity, K0-NC, a root finder).

The p–q invariants, the pressure-dependent elasticity, the tangent of a p–q return, the K0
normally consolidated state and a bracketed scalar Newton.

Used by :mod:`pilegroup.constitutive.cam_clay` (Modified Cam Clay) and
:mod:`pilegroup.constitutive.soft_soil_creep` (Soft Soil Creep). Conventions as in
:mod:`pilegroup.constitutive.base` (Mandel, kPa, tension positive); the invariants of critical
state soil mechanics are written **compression positive**:

* ``p = -tr(sigma)/3`` (mean effective stress, kPa), ``s = sigma + p I`` (deviator of the
  tension-positive stress), ``q = sqrt(3/2 s:s)`` (kPa), ``eta = q/p``;
* ``eps_v = -tr(eps)`` (volumetric strain, compression positive).

Elasticity (both laws): the bulk modulus grows with the pressure, ``K = p/k`` with the modified
swelling index ``k = kappa/(1 + e0)`` (``kappa*``), integrated exactly over a step,
``p = p_n exp(d_eps_v^e / k)``, i.e. an unloading–reloading line straight in ``ln p``
(Wood 1990); the shear modulus is ``G = 3 K_n (1 - 2 nu)/(2 (1 + nu))`` at the pressure
``p_n`` of the start of the step (constant Poisson's ratio) or a given constant ``G``. This is
a hypoelastic law (not derived from an energy: closed stress cycles can create energy,
Zytynski et al. 1978); with ``G`` fixed over a step the deviatoric trial stress is
``s_tr = s_n + 2 G d_e`` and both laws return radially in the deviatoric plane.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from pilegroup.constitutive.base import MANDEL_I, broadcast_state
from pilegroup.errors import ConstitutiveError
from pilegroup.validate import require_in_range

__all__ = [
    "P_DEV", "ElasticTrial", "bracketed_newton", "eta_k0", "eta_k0nc", "k0_stress",
    "m_from_k0nc", "m_from_phi", "pq", "pq_tangent", "preconsolidation_vertical",
    "require_ocr_pop", "shear_ratio", "vertical_effective",
]

#: Deviatoric projector, Mandel 6x6.
P_DEV = np.eye(6) - np.outer(MANDEL_I, MANDEL_I) / 3.0


def pq(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(p, q, s)`` of Mandel stresses ``(n, 6)``: p, q compression positive (kPa), s (n, 6)."""
    p = -(stress[:, 0] + stress[:, 1] + stress[:, 2]) / 3.0
    s = stress + p[:, None] * MANDEL_I
    q = np.sqrt(1.5 * np.einsum("ij,ij->i", s, s))
    return p, q, s


def m_from_phi(phi_deg: float) -> float:
    """Critical-state stress ratio of triaxial compression: ``M = 6 sin phi/(3 - sin phi)``."""
    sf = math.sin(math.radians(phi_deg))
    return 6.0 * sf / (3.0 - sf)


def eta_k0(k0: float) -> float:
    """Stress ratio ``q/p`` of the stress state ``sigma_h = K0 sigma_v``: ``3(1-K0)/(1+2K0)``."""
    return 3.0 * (1.0 - k0) / (1.0 + 2.0 * k0)


def shear_ratio(kappa_t: float, nu: float) -> float:
    """``g = p/(3 G)`` of the pressure-proportional shear modulus, -.

    ``G = 3 K (1 - 2 nu)/(2 (1 + nu))`` with ``K = p/kappa_t``: ``g = 2 kappa_t (1 + nu) /
    (9 (1 - 2 nu))``.
    """
    return 2.0 * kappa_t * (1.0 + nu) / (9.0 * (1.0 - 2.0 * nu))


def _m2_of_eta(eta: float, lam_t: float, kap_t: float, g: float) -> float:
    """``M^2`` for which a constant-``eta`` compression has no lateral strain (or nan)."""
    den = 2.0 * lam_t / 3.0 - eta * g
    return eta * eta + 2.0 * eta * (lam_t - kap_t) / den if den > 0.0 else math.nan


def m_from_k0nc(k0nc: float, lam_t: float, kap_t: float, nu: float) -> float:
    """``M`` of an ellipse whose associated flow gives ``K0nc`` in one-dimensional compression.

    Oedometric normal compression at the constant ratio ``eta = eta_k0(K0nc)``: elastic
    ``d eps_v = kap_t dp/p``, ``d eps_q = eta g dp/p`` (:func:`shear_ratio`), plastic
    ``d eps_v = (lam_t - kap_t) dp/p``, ``d eps_q = d eps_v 2 eta/(M^2 - eta^2)``; zero lateral
    strain is ``d eps_q = 2/3 d eps_v``. Solved for ``M`` this is the Soft Soil model's
    relation (Brinkgreve 1994; PLAXIS Material Models manual, Soft Soil model):
    ``M = 3 sqrt((1-K0)^2/(1+2K0)^2 + (1-K0)(1-2nu)(l/k - 1)/((1+2K0)(1-2nu) l/k
    - (1-K0)(1+nu)))`` with ``l/k = lam_t/kap_t``.

    Raises:
        ConstitutiveError: no such ``M`` (the elastic shear strain alone exceeds 2/3 of the
            volumetric strain: ``K0nc`` too small for these indices).
    """
    m2 = _m2_of_eta(eta_k0(k0nc), lam_t, kap_t, shear_ratio(kap_t, nu))
    if not m2 > 0.0:
        raise ConstitutiveError.invalid(
            "K0nc", k0nc, "too small for these lambda*, kappa*, nu: the elastic shear strain of "
            "one-dimensional compression alone exceeds the oedometer's; raise K0nc", "-")
    return math.sqrt(m2)


def eta_k0nc(M: float, lam_t: float, kap_t: float, g: float) -> float:
    """The constant ratio ``eta`` of normal one-dimensional compression.

    The inverse of :func:`m_from_k0nc` for a shear ratio ``g = p/(3G)``, by bisection on
    ``(0, M)``.
    """
    lo, hi = 0.0, M
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        m2 = _m2_of_eta(mid, lam_t, kap_t, g)
        if math.isnan(m2) or m2 > M * M:
            hi = mid
        else:
            lo = mid
        if hi - lo <= 1e-15 * M:
            break
    return 0.5 * (lo + hi)


def k0_stress(sigma_v: np.ndarray, k0: float) -> np.ndarray:
    """Mandel stresses ``(n, 6)`` (tension positive) with ``sigma_h = K0 sigma_v``.

    ``sigma_v``: vertical effective stresses (kPa, compression positive); z is vertical.
    """
    sv = np.atleast_1d(np.asarray(sigma_v, dtype=float))
    out = np.zeros((sv.size, 6))
    out[:, 0] = out[:, 1] = -k0 * sv
    out[:, 2] = -sv
    return out


def initial_stress(n: int, stress0: np.ndarray | None, law: str
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(stress, p, q)`` of ``n`` points at rest; raises unless ``p' > 0`` at every point.

    ``stress0``: effective stress (Mandel, kPa, ``(6,)`` or ``(n, 6)``); ``law`` names the law
    that needs it in the message.
    """
    if stress0 is None:
        raise ConstitutiveError(f"{law} needs an initial effective stress with p' > 0 "
                                "(stress0 is None)")
    s0 = broadcast_state(n, stress0, 6, "stress0")
    p0, q0, _ = pq(s0)
    if np.any(~(p0 > 0.0)):
        raise ConstitutiveError(f"initial p' = {float(p0.min()):g} kPa: {law} needs p' > 0 at "
                                "every point")
    return s0, p0, q0


def vertical_effective(stress: np.ndarray) -> np.ndarray:
    """Vertical effective stress ``-sigma_zz`` (kPa, compression positive) of Mandel stresses."""
    return -stress[:, 2]


def preconsolidation_vertical(sigma_v0: np.ndarray, ocr: float, pop: float) -> np.ndarray:
    """Vertical pre-consolidation stress ``OCR sigma_v0 + POP`` (kPa; one of the two given)."""
    return ocr * np.asarray(sigma_v0, dtype=float) + pop


def require_ocr_pop(ocr: float, pop: float) -> None:
    """Raise unless ``OCR`` in [1, 100] and ``POP`` (kPa) >= 0, and not both given."""
    require_in_range("OCR", ocr, 1.0, 100.0, "-", why="OCR < 1 is not a pre-consolidated state",
                     error=ConstitutiveError)
    require_in_range("POP", pop, 0.0, 1e5, "kPa", error=ConstitutiveError)
    if ocr != 1.0 and pop != 0.0:
        raise ConstitutiveError(f"give OCR or POP, not both (OCR = {ocr}, POP = {pop} kPa)")


class ElasticTrial:
    """The elastic predictor of a step: trial invariants and the step's shear modulus.

    ``p_tr = p_n exp(-tr(d_eps)/kappa_t)``, ``s_tr = s_n + 2 G P_dev d_eps``, ``Q = q_tr^2``
    with ``G`` from ``p_n`` (``shear`` = ``("nu", nu)`` or ``("G", G)``).
    """

    def __init__(self, d_eps: np.ndarray, stress_n: np.ndarray, kappa_t: float,
                 shear: tuple[str, float]) -> None:
        self.p_n, _, self.s_n = pq(stress_n)
        if np.any(~(self.p_n > 0.0)):
            bad = float(self.p_n[~(self.p_n > 0.0)][0])
            raise ConstitutiveError(f"mean effective stress p' = {bad:g} kPa: the "
                                    "pressure-dependent elasticity needs p' > 0")
        self.kappa_t = kappa_t
        kind, value = shear
        if kind == "nu":
            self.G = 1.5 * (1.0 - 2.0 * value) / (1.0 + value) * self.p_n / kappa_t
        else:
            self.G = np.full(self.p_n.shape, value)
        self.eps_v = -(d_eps[:, 0] + d_eps[:, 1] + d_eps[:, 2])
        self.p_tr = self.p_n * np.exp(self.eps_v / kappa_t)
        self.s_tr = self.s_n + 2.0 * self.G[:, None] * (d_eps @ P_DEV)
        self.Q = 1.5 * np.einsum("ij,ij->i", self.s_tr, self.s_tr)

    def elastic_part(self, p: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Elastic strain increment (Mandel, tension positive) that leads to ``(p, s)``."""
        ev = -self.kappa_t * np.log(p / self.p_n)
        return ev[:, None] * MANDEL_I / 3.0 + (s - self.s_n) / (2.0 * self.G[:, None])


def pq_tangent(tr: ElasticTrial, p: np.ndarray, a: np.ndarray, dp: np.ndarray,
               da: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stress ``-p I + a s_tr`` and its tangent ``d sigma/d d_eps`` (Mandel 6x6, kPa).

    ``dp``, ``da`` ``(n, 2)``: derivatives of ``p`` and ``a`` with respect to ``(p_tr, Q)``
    (``Q = q_tr^2``); ``d p_tr/d eps = -(p_tr/kappa_t) I``, ``d Q/d eps = 6 G s_tr``.
    """
    dptr = -(tr.p_tr / tr.kappa_t)
    six_g = 6.0 * tr.G
    dp_de = (dp[:, 0] * dptr)[:, None] * MANDEL_I + (dp[:, 1] * six_g)[:, None] * tr.s_tr
    da_de = (da[:, 0] * dptr)[:, None] * MANDEL_I + (da[:, 1] * six_g)[:, None] * tr.s_tr
    stress = -p[:, None] * MANDEL_I + a[:, None] * tr.s_tr
    D = (-MANDEL_I[None, :, None] * dp_de[:, None, :]
         + (2.0 * tr.G * a)[:, None, None] * P_DEV[None]
         + tr.s_tr[:, :, None] * da_de[:, None, :])
    return stress, D


def bracketed_newton(fun: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
                     lo: np.ndarray, hi: np.ndarray, x0: np.ndarray, *, xtol: float = 1e-14,
                     ftol: float = 1e-10, max_iter: int = 300,
                     what: str = "return mapping") -> np.ndarray:
    """Roots of scalar functions, one per point, with a sign change on ``[lo, hi]``.

    ``fun(x, idx) -> (F, dF/dx)`` for the points ``idx`` (``F`` scaled to order one);
    ``F(lo) <= 0 <= F(hi)`` is assumed (``lo`` and ``hi`` are moved as the signs are seen).
    A Newton step is replaced by bisection when it leaves the bracket or when the last one did
    not halve ``|F|`` (the safeguard of ``rtsafe``, Press et al. 2007, *Numerical Recipes*).
    Converged when ``F = 0``, the bracket is narrower than ``xtol (1 + |x|)``, or the Newton step is
    below that with ``|F| <= ftol`` (a tiny step of a very steep function is not a root).

    Raises:
        ConstitutiveError: a point did not converge in ``max_iter`` iterations.
    """
    lo, hi = lo.astype(float).copy(), hi.astype(float).copy()
    x = np.clip(x0.astype(float), lo, hi)
    f_prev = np.full(x.size, np.inf)
    idx = np.arange(x.size)
    for _ in range(max_iter):
        if idx.size == 0:
            return x
        xi = x[idx]
        F, dF = fun(xi, idx)
        lo[idx] = np.where(F < 0.0, xi, lo[idx])
        hi[idx] = np.where(F > 0.0, xi, hi[idx])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            step = F / dF
        new = xi - step
        tol = xtol * (1.0 + np.abs(xi))
        done = ((F == 0.0) | (hi[idx] - lo[idx] <= tol)
                | ((np.abs(step) <= tol) & (np.abs(F) <= ftol)))
        bad = (~np.isfinite(new) | (new <= lo[idx]) | (new >= hi[idx])
               | (np.abs(F) > 0.5 * f_prev[idx]))
        new = np.where(bad, 0.5 * (lo[idx] + hi[idx]), new)
        x[idx] = np.where(done & bad, xi, new)
        f_prev[idx] = np.abs(F)
        idx = idx[~done]
    raise ConstitutiveError(f"{what} did not converge in {max_iter} iterations at "
                            f"{idx.size} point(s)")
