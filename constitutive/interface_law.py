"""Elastic–viscoplastic pile–soil interface (paper Section 3, Eqs. 4–17), vectorised.

Zero-thickness Goodman interface with

* a **normal** penalty spring in compression and no tension: ``sigma_n = k_normal * min(g, 0)``
  where ``g`` is the normal opening measured from the zero-traction position (state ``"gap"``).
  An opening point's shear fades out, ``|tau| = t (1 - k_f g / max(t, F))`` (``t`` what its
  slip gives, ``F`` = :data:`SHEAR_FADE_KPA`, ``k_f`` = ``fade_stiffness``), zero from ``g =
  max(t, F) / k_f``: the traction stays continuous (with cohesion the full strength acts at zero
  normal stress; a sudden drop made Newton switch points between open and closed); then the
  point is detached: all three tractions exactly zero, ``"detached" = 1``. With a bearing limit
  ``q_b`` (``bearing``, pile bases) ``sigma_n >= -q_b``, the corner rounded over ``(1 -+ w)
  q_b`` (:func:`bearing_curve`, ``w`` = :data:`BEARING_ROUNDING`); a closure beyond ``-(1 + w)
  q_b / k_normal`` is permanent penetration (the zero-traction position moves), and an opening
  from there unloads along the curve (a Q–z curve's plateau);
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
from typing import NamedTuple

import numpy as np

from pilegroup.constitutive.base import as_points
from pilegroup.constitutive.paper import DruckerPragerCone, delta_eq17, dp_outer_cone
from pilegroup.errors import ConstitutiveError
from pilegroup.validate import (
    require_in_range,
    require_non_negative,
    require_one_of,
    require_positive,
)

# delta_eq17 and dp_outer_cone are defined in constitutive.paper; callers of this law import
# them from here too.
__all__ = ["PileSoilInterface", "delta_eq17", "dp_outer_cone"]

_TINY = 1e-300

#: The stress scale of the shear's fade at an opening, kPa (module docstring).
SHEAR_FADE_KPA = 10.0

#: Half-width of the rounded corner of the bearing limit, a fraction of ``q_b``.
BEARING_ROUNDING = 0.05


def bearing_curve(x: np.ndarray, w: float = BEARING_ROUNDING) -> tuple[np.ndarray, np.ndarray]:
    """Compression under a bearing limit, ``q_b h(x)``, and ``h'(x)``; ``x``: the penalty's / q_b.

    ``h(x) = x`` up to ``1 - w``, ``1`` from ``1 + w``, and between them the parabola
    ``x - (x - 1 + w)^2 / (4 w)``, which meets both with their slopes (a continuous
    derivative, for Newton: the ``pile-capacity`` case took 361 Newton iterations with an
    exact corner and 294 with this one, same capacity).
    """
    lo = 1.0 - w
    u = np.clip(x - lo, 0.0, 2.0 * w)
    h = np.where(x <= lo, x, np.where(x >= 1.0 + w, 1.0, lo + u - u * u / (4.0 * w)))
    return h, 1.0 - u / (2.0 * w)


def bearing_curve_inverse(y: np.ndarray, w: float = BEARING_ROUNDING) -> np.ndarray:
    """The ``x`` of :func:`bearing_curve` with ``h(x) = y`` (``y <= 1``; 1 -> ``1 + w``)."""
    lo = 1.0 - w
    v = np.clip(y - lo, 0.0, w)
    return np.minimum(y, lo) + 2.0 * w - 2.0 * np.sqrt(w * w - w * v)


class _Normal(NamedTuple):
    """Normal response of one step, per point (penalty in contact, free when detached)."""

    gap: np.ndarray  #: normal opening after the step, m (> 0: no normal stress)
    contact: np.ndarray  #: bool, ``gap <= 0``
    s: np.ndarray  #: sigma_n, kPa (tension positive)
    a: np.ndarray  #: hyperbola coefficient a of Eq. 6, m/kPa
    b: np.ndarray  #: hyperbola coefficient b of Eq. 7, 1/kPa
    p: np.ndarray  #: compressive normal stress floored at p_floor, kPa
    s_n: np.ndarray  #: d sigma_n / d opening, kPa/m
    p_n: np.ndarray  #: d p / d opening, kPa/m


class _Shear(NamedTuple):
    """Elastic slip magnitude after the step and its derivatives, per point."""

    r_tr: np.ndarray  #: magnitude of the trial elastic slip, m
    e: np.ndarray  #: (n, 2) unit direction of the trial elastic slip (0 where it is 0)
    pos: np.ndarray  #: bool, ``r_tr > 0``
    r: np.ndarray  #: magnitude of the elastic slip after the return, m
    dr_drtr: np.ndarray  #: dr / dr_tr, -
    dr_dn: np.ndarray  #: dr / d opening at fixed trial slip, -


@dataclass(frozen=True)
class PileSoilInterface(DruckerPragerCone):
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
        bearing: bearing limit ``q_b`` of the normal compression, kPa (> 0; ``None``: none):
            ``sigma_n >= -q_b``, the rest of a closure being permanent penetration.
        fade_stiffness: ``k_f`` of the shear's fade at an opening, kPa/m (> 0; ``None``:
            ``k_normal``); too steep, it makes Newton cycle (docs/solver.md, "Newton").

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
    bearing: float | None = None
    fade_stiffness: float | None = None

    def __post_init__(self) -> None:
        err = ConstitutiveError
        require_positive("K", self.K, "-", error=err)
        require_non_negative("n", self.n, "-", error=err)
        require_in_range("R_f", self.R_f, 0.0, 1.0, "-", hi_open=True, error=err)
        require_non_negative("c", self.c, "kPa", error=err)
        require_in_range("phi_deg", self.phi_deg, 0.0, 90.0, "deg", hi_open=True, error=err)
        require_positive("eta", self.eta, "kPa·day/m", error=err)
        require_positive("k_normal", self.k_normal, "kPa/m", error=err)
        if self.delta_deg is not None:
            require_in_range("delta_deg", self.delta_deg, 0.0, 90.0, "deg", lo_open=True,
                             hi_open=True, error=err)
        elif self.phi_deg <= 0.0:
            raise ConstitutiveError(
                "delta_deg = None needs phi_deg > 0 deg for Eq. 17; give delta_deg in (0, 90) deg"
            )
        for key, unit in (("N", "-"), ("r_w", "kN/m3"), ("P_a", "kPa"), ("p_floor", "kPa")):
            require_positive(key, getattr(self, key), unit, error=err)
        require_one_of("variant", self.variant, ("default", "seed"), error=err)
        require_one_of("integrator", self.integrator, ("implicit", "explicit"), error=err)
        if self.bearing is not None:
            require_positive("bearing", self.bearing, "kPa", error=err)
        if self.fade_stiffness is not None:
            require_positive("fade_stiffness", self.fade_stiffness, "kPa/m", error=err)

    # ------------------------------------------------------------------ derived parameters
    @cached_property
    def delta(self) -> float:
        """Interface friction angle, degrees (given, or Eq. 17)."""
        return float(self.delta_deg) if self.delta_deg is not None else delta_eq17(self.phi_deg)

    @cached_property
    def k_fade(self) -> float:
        """Stiffness of the shear's fade at an opening, kPa/m (``fade_stiffness`` or k_normal)."""
        return self.k_normal if self.fade_stiffness is None else float(self.fade_stiffness)

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

    def creep_rate(self, traction: np.ndarray) -> np.ndarray:
        """Viscoplastic slip rate (m/day) at tractions ``(n, 3)`` held constant.

        ``(F0/eta) <F/F0>^N dF/d|tau|``: at constant ``sigma_n`` and ``tau`` the yield function
        is constant, so the slip of a creep test grows at this rate (both integrators integrate
        it exactly, docs/model.md). Zero without viscosity (``viscous=False``).
        """
        tr = as_points(traction, 3, "traction")
        t = np.hypot(tr[:, 1], tr[:, 2])
        F, _, _, g, _, _ = self._F(t, tr[:, 0])
        phi, _ = self._rate(F, 1.0)
        return phi * g if self.viscous else np.zeros_like(t)

    def _F(self, t: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, ...]:
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
                sigma_n <= 0 (the in-situ horizontal effective stress, compression negative;
                with a bearing limit, a larger compression starts at ``-bearing``);
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
        gap = tr[:, 0] / self.k_normal
        if self.bearing is not None:  # a point beyond the limit starts at it
            tr[:, 0] = np.maximum(tr[:, 0], -self.bearing)
            gap = -self.bearing * bearing_curve_inverse(-tr[:, 0] / self.bearing) / self.k_normal
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
            "gap": gap[:, None],
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
        nc = self._normal(state_n["gap"][:, 0] + dj[:, 0])
        ge_tr, slip_vp = self._trial_slip(dj, state_n, nc, dt)
        sh = self._shear(ge_tr, nc, slip_vp, dt)
        traction, tangent, held = self._traction_tangent(nc, sh)
        free = ~held[:, None]  # detached: no shear memory, open sliding is not viscoplastic
        state = {
            "traction": traction,
            "slip_e": np.where(free, 0.0, sh.r[:, None] * sh.e),
            "slip_vp": np.where(free, state_n["slip_vp"], slip_vp),
            "gap": nc.gap[:, None],
            "detached": free.astype(float),
        }
        return traction, state, tangent

    def _normal(self, gap: np.ndarray) -> _Normal:
        """Normal penalty response at the opening ``gap`` after the step, with derivatives.

        With a bearing limit the compression follows :func:`bearing_curve`; beyond its plateau's
        start the opening is held there (the rest of the closure is penetration).
        """
        kn = self.k_normal
        qb = self.bearing
        if qb is not None:  # penetration: the opening stays where the plateau starts
            gap = np.maximum(gap, -(1.0 + BEARING_ROUNDING) * qb / kn)
        closed = gap <= 0.0
        s = np.where(closed, kn * gap, 0.0)
        s_n = np.where(closed, kn, 0.0)
        if qb is not None:
            h, dh = bearing_curve(-s / qb)
            s, s_n = -qb * h, s_n * dh
        a, b = self.hyperbola(s)
        p = np.maximum(-s, self.p_floor)
        p_n = np.where(closed & (-s > self.p_floor), -s_n, 0.0)
        return _Normal(gap, closed, s, a, b, p, s_n, p_n)

    def _trial_slip(
        self, dj: np.ndarray, state_n: dict[str, np.ndarray], nc: _Normal, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Trial elastic slip ``(n, 2)`` and the viscoplastic slip so far.

        The elastic slip restarts from zero after a separation. The explicit integrator takes
        the step's viscoplastic slip from the committed traction here; the implicit one leaves
        it to :meth:`_shear`.
        """
        slip_e_n = np.where(state_n["detached"] > 0.5, 0.0, state_n["slip_e"])
        slip_vp = state_n["slip_vp"].copy()
        if not (self.integrator == "explicit" and self.viscous):
            return slip_e_n + dj[:, 1:], slip_vp
        tr_n = state_n["traction"]
        t_old = np.hypot(tr_n[:, 1], tr_n[:, 2])
        F_old, _, _, g_old, _, _ = self._F(t_old, tr_n[:, 0])
        act = (state_n["detached"][:, 0] < 0.5) & (F_old > 0.0) & (t_old > 0.0) & (dt > 0)
        dvp = np.zeros((dj.shape[0], 2))
        if np.any(act):
            phi, _ = self._rate(F_old[act], dt)
            dvp[act] = (phi * g_old[act] / t_old[act])[:, None] * tr_n[act, 1:]
        return slip_e_n + dj[:, 1:] - dvp, slip_vp + dvp

    def _shear(self, ge_tr: np.ndarray, nc: _Normal, slip_vp: np.ndarray, dt: float) -> _Shear:
        """Implicit radial return of the trial elastic slip; adds the return to ``slip_vp``."""
        nq = ge_tr.shape[0]
        r_tr = np.hypot(ge_tr[:, 0], ge_tr[:, 1])
        pos = r_tr > 0.0
        e = np.where(pos[:, None], ge_tr / np.where(pos, r_tr, 1.0)[:, None], 0.0)
        r = r_tr.copy()
        dr_drtr = np.ones(nq)
        dr_dn = np.zeros(nq)
        if self.integrator == "implicit" and self.viscous and dt > 0.0:
            a, b, s = nc.a, nc.b, nc.s
            t_tr = r_tr / (a + b * r_tr)
            plastic = pos & (self._F(t_tr, s)[0] > 0.0)
            if np.any(plastic):
                idx = np.nonzero(plastic)[0]
                rr, Rr, Rn = self._return(r_tr[idx], a[idx], b[idx], s[idx], nc.p[idx],
                                          nc.s_n[idx], nc.p_n[idx], dt)
                r[idx] = rr
                dr_drtr[idx] = 1.0 / Rr
                dr_dn[idx] = -Rn / Rr
                slip_vp[idx] += (r_tr[idx] - rr)[:, None] * e[idx]
        return _Shear(r_tr, e, pos, r, dr_drtr, dr_dn)

    def _traction_tangent(self, nc: _Normal, sh: _Shear
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Traction ``(n, 3)``, consistent tangent ``(n, 3, 3)``, and which points hold.

        A point holds (is not detached) while closed or while its shear survives the opening.
        """
        a, p, contact, pos, e = nc.a, nc.p, nc.contact, sh.pos, sh.e
        r = sh.r
        den = a + nc.b * r
        t = r / den
        t_r = a / den**2
        t_p = r * (self.n * a + nc.b * r) / (p * den**2)
        dt_dn = t_r * sh.dr_dn + t_p * nc.p_n
        # an opening point's shear fades out (module docstring): t (1 - k_f g / max(t, F))
        m = np.maximum(t, SHEAR_FADE_KPA)
        kg = self.k_fade * np.maximum(nc.gap, 0.0)
        t_eff = np.maximum(t - kg * t / m, 0.0)
        held = contact | (t_eff > 0.0)
        d_t = np.where(t < SHEAR_FADE_KPA, 1.0 - kg / m, 1.0)  # d t_eff / d t
        d_g = np.where(contact, 0.0, -self.k_fade * t / m)  # d t_eff / d opening
        c_perp = np.where(pos, t_eff / np.where(pos, sh.r_tr, 1.0), 1.0 / a)
        c_par = np.where(pos, d_t * t_r * sh.dr_drtr, 1.0 / a)
        c_perp = np.where(held, c_perp, 0.0)
        c_par = np.where(held, c_par, 0.0)
        dt_dn = np.where(held, d_t * dt_dn + d_g, 0.0)

        nq = r.shape[0]
        traction = np.empty((nq, 3))
        traction[:, 0] = nc.s
        traction[:, 1:] = t_eff[:, None] * e
        tangent = np.zeros((nq, 3, 3))
        tangent[:, 0, 0] = nc.s_n
        tangent[:, 1:, 0] = dt_dn[:, None] * e
        ee = e[:, :, None] * e[:, None, :]
        eye = np.eye(2)[None]
        tangent[:, 1:, 1:] = c_par[:, None, None] * ee + c_perp[:, None, None] * (eye - ee)
        return traction, tangent, held

    def _return(
        self, r_tr: np.ndarray, a: np.ndarray, b: np.ndarray, s: np.ndarray, p: np.ndarray,
        s_n: np.ndarray, p_n: np.ndarray, dt: float,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
            # a bracket's end is never the root: a step onto it bisects (else it alternates)
            out = (rn <= lo) | (rn >= hi)
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
