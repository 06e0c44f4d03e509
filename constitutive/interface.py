"""Elastic–viscoplastic pile–soil interface (paper Section 3, Eqs. 4–17), vectorised.

Zero-thickness Goodman interface with

* a **normal** penalty spring in compression and no tension: ``sigma_n = k_normal * min(g, 0)``
  where ``g`` is the normal opening measured from the zero-traction position (state ``"gap"``);
  ``g > 0`` means detached: all three tractions are exactly zero and ``"detached" = 1``;
* an **elastic shear** law after Clough & Duncan (Eqs. 5–8): with ``p = max(-sigma_n, p_floor)``
  the compressive normal stress magnitude, ``a = 1 / (K r_w (p/P_a)^n)`` and
  ``b = R_f / (p tan(delta))``, the shear traction is ``tau = gamma_e / (a + b |gamma_e|)``
  (isotropic in the interface plane, ``gamma_e`` = elastic slip vector, m). Along a monotonic
  path at constant ``p`` this is exactly Eq. 5, and its tangent is exactly Eq. 8;
* a **viscoplastic slip** after Perzyna on a Drucker–Prager surface (Eqs. 9–15) with
  ``alpha, k`` of Eq. 13 (outer cone):
  ``d gamma_vp / dt = (F0 / eta) <F / F0>^N dF/dtau`` (N = 1: ``<F>/eta dF/dtau``), eta in
  kPa·day/m so that the slip rate is in m/day, ``F0 = k`` (``P_a`` when ``k = 0``, i.e. c = 0).
  Variants of the yield function ``F`` (sigma_n tension positive, ``t = |tau|``):

  - ``"default"``: in-plane normal stresses equal sigma_n, so ``I1 = 3 sigma_n`` and
    ``J2 = t^2``: ``F = t + 3 alpha sigma_n - k``;
  - ``"seed"``: the paper's literal Eq. 15, ``I1 = sigma_n``, ``J2 = sigma_n^2/3 + t^2``:
    ``F = sqrt(sigma_n^2/3 + t^2) + alpha sigma_n - k`` (yields under normal pressure alone).

  As in the paper (Eq. 16) only the tangential components of ``dF/dsigma`` produce
  viscoplastic slip; the normal response stays the elastic penalty.

Per point, the kinematic input is the increment of ``[g, s1, s2]`` (m: normal opening,
positive = gap opening; two slips) and the output the traction ``[sigma_n, tau1, tau2]`` (kPa,
tension positive so compression is negative) and the 3x3 consistent tangent (kPa/m).

Integrators: ``"implicit"`` (backward Euler; radial return in the shear plane, scalar Newton per
point, consistent tangent) and ``"explicit"`` (the paper's forward update of Section 4: the
viscoplastic slip of the step is evaluated from the committed traction; conditionally stable).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pilegroup.constitutive.base import ConstitutiveError, as_points, check_param

__all__ = ["PileSoilInterface", "delta_eq17", "dp_outer_cone"]

_TINY = 1e-300


def delta_eq17(phi_deg: float) -> float:
    """Interface friction angle of Eq. 17, degrees: ``atan(sin phi cos phi / (1 + sin^2 phi))``."""
    ph = math.radians(phi_deg)
    return math.degrees(math.atan(math.sin(ph) * math.cos(ph) / (1.0 + math.sin(ph) ** 2)))


def dp_outer_cone(c: float, phi_deg: float) -> tuple[float, float]:
    """Drucker–Prager ``(alpha, k)`` of Eq. 13 (outer cone, compression meridian), k in kPa.

    ``alpha = 2 sin phi / (sqrt3 (3 - sin phi))``, ``k = 6 c cos phi / (sqrt3 (3 - sin phi))``
    for ``F = sqrt(J2) + alpha I1 - k`` with tension-positive ``I1``.
    """
    ph = math.radians(phi_deg)
    den = math.sqrt(3.0) * (3.0 - math.sin(ph))
    return 2.0 * math.sin(ph) / den, 6.0 * c * math.cos(ph) / den


@dataclass(frozen=True)
class PileSoilInterface:
    """Elastic–viscoplastic pile–soil interface law (see the module docstring).

    Attributes:
        K: hyperbolic stiffness number, - (> 0).
        n: stiffness exponent, - (>= 0).
        R_f: failure ratio, - (in [0, 1); 0 gives linear shear springs ``K r_w (p/P_a)^n``).
        c: cohesion of the adjacent soil, kPa (>= 0).
        phi_deg: friction angle of the adjacent soil, degrees (in [0, 90)).
        eta: viscosity, kPa·day/m (> 0); Table 1's "MPa·d" times 1000.
        k_normal: normal penalty stiffness in compression, kPa/m (> 0).
        delta_deg: interface friction angle, degrees (in (0, 90)); None -> Eq. 17 from phi.
        N: Perzyna exponent, - (> 0; 1 for geomaterials).
        r_w: unit weight of water in Eq. 6, kN/m3 (> 0).
        P_a: atmospheric pressure, kPa (> 0).
        variant: ``"default"`` or ``"seed"`` (literal Eq. 15).
        integrator: ``"implicit"`` (backward Euler, default) or ``"explicit"`` (paper).
        p_floor: floor of the compressive normal stress used in the hyperbola (Eqs. 6–7) so that
            the stiffness stays positive as sigma_n -> 0, kPa (> 0). It does not enter the yield
            function, which uses the actual sigma_n.
        viscous: ``False`` drops the viscoplastic slip (the "elastic" interface: hyperbolic
            shear springs and the normal penalty only; no yield surface, no creep).

    State (arrays ``(n, k)``): ``traction`` (3, kPa), ``slip_e`` (2, elastic slip, m),
    ``slip_vp`` (2, viscoplastic slip, m), ``gap`` (1, normal opening from the zero-traction
    position, m; negative in contact, ``sigma_n = k_normal * gap``), ``detached`` (1, 0/1).
    While detached the elastic slip is reset to zero (no shear memory across a separation) and
    tangential motion is free (it is not added to ``slip_vp``).
    """

    K: float
    n: float
    R_f: float
    c: float
    phi_deg: float
    eta: float
    k_normal: float
    delta_deg: float | None = None
    N: float = 1.0
    r_w: float = 10.0
    P_a: float = 101.0
    variant: str = "default"
    integrator: str = "implicit"
    p_floor: float = 1.0
    viscous: bool = True

    def __post_init__(self) -> None:
        inf = math.inf
        check_param("K", self.K, "-", 0.0, inf, lo_open=True, hi_open=True)
        check_param("n", self.n, "-", 0.0, inf, hi_open=True)
        check_param("R_f", self.R_f, "-", 0.0, 1.0, hi_open=True)
        check_param("c", self.c, "kPa", 0.0, inf, hi_open=True)
        check_param("phi_deg", self.phi_deg, "deg", 0.0, 90.0, hi_open=True)
        check_param("eta", self.eta, "kPa·day/m", 0.0, inf, lo_open=True, hi_open=True)
        check_param("k_normal", self.k_normal, "kPa/m", 0.0, inf, lo_open=True, hi_open=True)
        if self.delta_deg is not None:
            check_param("delta_deg", self.delta_deg, "deg", 0.0, 90.0, lo_open=True,
                        hi_open=True)
        elif self.phi_deg <= 0.0:
            raise ConstitutiveError(
                "delta_deg = None needs phi_deg > 0 deg for Eq. 17; give delta_deg in (0, 90) deg"
            )
        check_param("N", self.N, "-", 0.0, inf, lo_open=True, hi_open=True)
        check_param("r_w", self.r_w, "kN/m3", 0.0, inf, lo_open=True, hi_open=True)
        check_param("P_a", self.P_a, "kPa", 0.0, inf, lo_open=True, hi_open=True)
        check_param("p_floor", self.p_floor, "kPa", 0.0, inf, lo_open=True, hi_open=True)
        if self.variant not in ("default", "seed"):
            raise ConstitutiveError(
                f"variant = {self.variant!r} is not allowed; allowed: 'default', 'seed'")
        if self.integrator not in ("implicit", "explicit"):
            raise ConstitutiveError(
                f"integrator = {self.integrator!r} is not allowed; allowed: 'implicit', 'explicit'")

    # ------------------------------------------------------------------ derived parameters
    @cached_property
    def delta(self) -> float:
        """Interface friction angle, degrees (given, or Eq. 17)."""
        return float(self.delta_deg) if self.delta_deg is not None else delta_eq17(self.phi_deg)

    @cached_property
    def alpha(self) -> float:
        """Drucker–Prager alpha of Eq. 13, -."""
        return dp_outer_cone(self.c, self.phi_deg)[0]

    @cached_property
    def k(self) -> float:
        """Drucker–Prager k of Eq. 13, kPa."""
        return dp_outer_cone(self.c, self.phi_deg)[1]

    @cached_property
    def F0(self) -> float:
        """Perzyna reference stress, kPa: ``k`` (= Eq. 12 with 3 for sqrt3), or P_a if k = 0."""
        return self.k if self.k > 0.0 else self.P_a

    # ------------------------------------------------------------------ pointwise pieces
    def hyperbola(self, sigma_n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Hyperbola coefficients ``(a, b)`` of Eqs. 6–7: a in m/kPa, b in 1/kPa.

        ``sigma_n`` in kPa, tension positive; the compressive magnitude is floored at
        ``p_floor``.
        """
        p = np.maximum(-np.asarray(sigma_n, dtype=float), self.p_floor)
        a = 1.0 / (self.K * self.r_w * (p / self.P_a) ** self.n)
        b = self.R_f / (p * math.tan(math.radians(self.delta)))
        return a, b

    def yield_function(self, traction: np.ndarray) -> np.ndarray:
        """Drucker–Prager F (kPa) of tractions ``(n, 3)`` ``[sigma_n, tau1, tau2]`` (variant)."""
        tr = as_points(traction, 3, "traction")
        t = np.hypot(tr[:, 1], tr[:, 2])
        return self._F(t, tr[:, 0])[0]

    def _F(self, t: np.ndarray, s: np.ndarray):
        """Return F, dF/dt, dF/ds, g = dF/dt, dg/dt, dg/ds (flow magnitude factor g)."""
        al, k = self.alpha, self.k
        if self.variant == "default":
            F = t + 3.0 * al * s - k
            one = np.ones_like(t)
            zero = np.zeros_like(t)
            return F, one, 3.0 * al * one, one, zero, zero
        J = np.sqrt(s * s / 3.0 + t * t)
        Js = np.maximum(J, _TINY)
        F = J + al * s - k
        g = t / Js
        g_t = (s * s / 3.0) / Js**3
        g_s = -t * (s / 3.0) / Js**3
        return F, g, s / (3.0 * Js) + al, g, g_t, g_s

    def _rate(self, F: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Perzyna increment factor ``phi = dt F0/eta <F/F0>^N`` (m/kPa·kPa) and dphi/dF."""
        x = np.maximum(F, 0.0) / self.F0
        if self.N == 1.0:
            phi = dt / self.eta * self.F0 * x
            dphi = np.where(F > 0.0, dt / self.eta, 0.0)
        else:
            phi = dt / self.eta * self.F0 * x**self.N
            dphi = np.where(F > 0.0, dt / self.eta * self.N * x ** (self.N - 1.0), 0.0)
        return phi, dphi

    # ------------------------------------------------------------------ protocol
    def state_layout(self) -> dict[str, int]:
        """State name -> components per point."""
        return {"traction": 3, "slip_e": 2, "slip_vp": 2, "gap": 1, "detached": 1}

    def initial_state(self, n: int, traction0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points.

        Args:
            n: number of points.
            traction0: initial ``[sigma_n, tau1, tau2]`` in kPa, ``(3,)`` or ``(n, 3)``;
                sigma_n <= 0 (the in-situ horizontal effective stress, compression negative);
                the shear must lie below the hyperbola's asymptote ``p tan(delta) / R_f``.
                None: all zero.

        Returns:
            The state dict (see the class docstring); the elastic slip is the one that
            produces the given shear traction on the hyperbola at the given sigma_n.
        """
        tr = np.zeros((n, 3))
        if traction0 is not None:
            t0 = np.asarray(traction0, dtype=float)
            if t0.shape not in ((3,), (n, 3)):
                raise ConstitutiveError(
                    f"traction0 must have shape (3,) or ({n}, 3); got {t0.shape}")
            tr[:] = t0
        if np.any(tr[:, 0] > 0.0):
            raise ConstitutiveError(
                "traction0 sigma_n must be <= 0 kPa (no tension; compression negative); got max "
                f"{tr[:, 0].max()!r} kPa")
        a, b = self.hyperbola(tr[:, 0])
        t = np.hypot(tr[:, 1], tr[:, 2])
        if np.any(b * t >= 1.0):
            raise ConstitutiveError(
                "traction0 shear must be below the hyperbola asymptote p tan(delta)/R_f (kPa)")
        slip_e = (a / (1.0 - b * t))[:, None] * tr[:, 1:]
        return {
            "traction": tr,
            "slip_e": slip_e,
            "slip_vp": np.zeros((n, 2)),
            "gap": tr[:, :1] / self.k_normal,
            "detached": np.zeros((n, 1)),
        }

    def update(
        self, d_jump: np.ndarray, state_n: dict[str, np.ndarray], dt: float
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Integrate the interface law over one step.

        Args:
            d_jump: (n, 3) increment of ``[normal opening, slip1, slip2]``, m
                (opening positive).
            state_n: committed state (not mutated).
            dt: time step, day (>= 0; 0 gives an instantaneous, purely elastic response).

        Returns:
            ``(traction, state_trial, tangent)``: traction (n, 3) ``[sigma_n, tau1, tau2]`` kPa
            (tension positive); the trial state; tangent (n, 3, 3) ``d traction / d jump``
            in kPa/m (consistent with the chosen integrator; not symmetric in general).
        """
        if not dt >= 0.0:
            raise ConstitutiveError(f"dt = {dt!r} day must be >= 0")
        dj = as_points(d_jump, 3, "d_jump")
        nq = dj.shape[0]
        kn = self.k_normal

        gap = state_n["gap"][:, 0] + dj[:, 0]
        contact = gap <= 0.0
        s = np.where(contact, kn * gap, 0.0)
        a, b = self.hyperbola(s)
        p = np.maximum(-s, self.p_floor)
        # derivatives with respect to the normal jump increment
        s_n = np.where(contact, kn, 0.0)
        p_n = np.where(contact & (-s > self.p_floor), -kn, 0.0)
        cmask = contact[:, None]

        slip_e_n = np.where(state_n["detached"] > 0.5, 0.0, state_n["slip_e"])
        slip_vp = state_n["slip_vp"].copy()

        if self.integrator == "explicit" and self.viscous:
            tr_n = state_n["traction"]
            t_old = np.hypot(tr_n[:, 1], tr_n[:, 2])
            F_old, _, _, g_old, _, _ = self._F(t_old, tr_n[:, 0])
            act = (state_n["detached"][:, 0] < 0.5) & (F_old > 0.0) & (t_old > 0.0) & (dt > 0)
            dvp = np.zeros((nq, 2))
            if np.any(act):
                phi, _ = self._rate(F_old[act], dt)
                dvp[act] = (phi * g_old[act] / t_old[act])[:, None] * tr_n[act, 1:]
            ge_tr = np.where(cmask, slip_e_n + dj[:, 1:] - dvp, 0.0)
            slip_vp = np.where(cmask, slip_vp + dvp, slip_vp)
        else:
            ge_tr = np.where(cmask, slip_e_n + dj[:, 1:], 0.0)

        r_tr = np.hypot(ge_tr[:, 0], ge_tr[:, 1])
        pos = r_tr > 0.0
        e = np.where(pos[:, None], ge_tr / np.where(pos, r_tr, 1.0)[:, None], 0.0)
        r = r_tr.copy()
        dr_drtr = np.ones(nq)
        dr_dn = np.zeros(nq)

        if self.integrator == "implicit" and self.viscous and dt > 0.0:
            t_tr = r_tr / (a + b * r_tr)
            plastic = contact & pos & (self._F(t_tr, s)[0] > 0.0)
            if np.any(plastic):
                idx = np.nonzero(plastic)[0]
                rr, Rr, Rn = self._return(r_tr[idx], a[idx], b[idx], s[idx], p[idx],
                                          s_n[idx], p_n[idx], dt)
                r[idx] = rr
                dr_drtr[idx] = 1.0 / Rr
                dr_dn[idx] = -Rn / Rr
                slip_vp[idx] += (r_tr[idx] - rr)[:, None] * e[idx]

        den = a + b * r
        t = r / den
        t_r = a / den**2
        t_p = r * (self.n * a + b * r) / (p * den**2)
        dt_dn = t_r * dr_dn + t_p * p_n
        c_perp = np.where(pos, t / np.where(pos, r_tr, 1.0), 1.0 / a)
        c_par = np.where(pos, t_r * dr_drtr, 1.0 / a)
        c_perp = np.where(contact, c_perp, 0.0)
        c_par = np.where(contact, c_par, 0.0)

        traction = np.empty((nq, 3))
        traction[:, 0] = s
        traction[:, 1:] = t[:, None] * e
        tangent = np.zeros((nq, 3, 3))
        tangent[:, 0, 0] = s_n
        tangent[:, 1:, 0] = dt_dn[:, None] * e
        ee = e[:, :, None] * e[:, None, :]
        eye = np.eye(2)[None]
        tangent[:, 1:, 1:] = c_par[:, None, None] * ee + c_perp[:, None, None] * (eye - ee)

        state = {
            "traction": traction,
            "slip_e": r[:, None] * e,
            "slip_vp": slip_vp,
            "gap": gap[:, None],
            "detached": (~contact).astype(float)[:, None],
        }
        return traction, state, tangent

    def _return(self, r_tr, a, b, s, p, s_n, p_n, dt):
        """Backward-Euler radial return: solve ``R(r) = r - r_tr + phi(F) g = 0`` per point.

        Bracketed Newton on ``r`` in ``[0, r_tr]`` (R(0) < 0 < R(r_tr)); returns ``r``,
        ``dR/dr`` and ``dR/d(normal jump)`` at fixed ``r`` for the consistent tangent.
        """
        lo = np.zeros_like(r_tr)
        hi = r_tr.copy()
        r = r_tr.copy()
        for _ in range(100):
            den = a + b * r
            t = r / den
            F, F_t, _, g, g_t, _ = self._F(t, s)
            phi, dphi = self._rate(F, dt)
            R = r - r_tr + phi * g
            Rr = 1.0 + (dphi * F_t * g + phi * g_t) * a / den**2
            lo = np.where(R < 0.0, r, lo)
            hi = np.where(R > 0.0, r, hi)
            rn = r - R / Rr
            out = (rn < lo) | (rn > hi)
            rn = np.where(out, 0.5 * (lo + hi), rn)
            done = np.abs(rn - r) <= 1e-15 * r_tr
            r = rn
            if np.all(done):
                break
        else:  # pragma: no cover - safeguarded Newton converges well before
            raise ConstitutiveError("interface return mapping did not converge in 100 iterations")
        den = a + b * r
        t = r / den
        F, F_t, F_s, g, g_t, g_s = self._F(t, s)
        phi, dphi = self._rate(F, dt)
        t_r = a / den**2
        t_p = r * (self.n * a + b * r) / (p * den**2)
        A = dphi * F_t * g + phi * g_t
        Rr = 1.0 + A * t_r
        Rn = A * t_p * p_n + (dphi * F_s * g + phi * g_s) * s_n
        return r, Rr, Rn
