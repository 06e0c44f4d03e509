"""Downdrag: the unified method's reading of a pile, its force balance, and pile installation.

Pure functions (numpy and scipy; no mesh, no MPI, no dolfinx) that the outputs of ground that
moves (fills, drawdown, consolidating layers, pile installation) and the verification cases use.
Conventions, those of ``pile_profiles.csv`` and ``settlement_profiles.csv``
(studies/run/pile_probe.py): depth m below the ground surface, positive down, stations from the
head to the toe; axial force kN, compression positive, the force due to the loads; shaft friction
kPa, here a magnitude (>= 0) whose direction the method fixes; settlements m, down positive;
excess pore pressure kPa (above hydrostatic positive); time day; permeability m/day; unit
weights kN/m^3 (``GAMMA_WATER`` of :mod:`pilegroup.model.units`).

* **Neutral plane** (:func:`neutral_plane`), Fellenius' unified method (Fellenius 2004, "Unified
  design of piled foundations with emphasis on settlement analysis", ASCE GSP 125; Fellenius
  2021, "Basics of foundation design"; NCHRP Report 1112, 2024): above the neutral plane the
  soil settles more than the pile and loads it by negative skin friction, below it the pile
  settles more and the friction is positive. The neutral plane is where the axial force is
  largest (force equilibrium) and, ideally, where pile and soil settle alike (settlement
  equilibrium). The dragload is the largest axial force minus the head load; the downdrag the
  pile's settlement at the neutral plane.
* **Force balance** (:func:`force_balance`, :func:`end_bearing_force`,
  :func:`unified_force_profile`): the same method's closed form, ``Q + int_0^zn U f dz =
  int_zn^L U f dz + R_t``, with the shaft friction of the beta method (:func:`beta_friction`,
  ``f = c_a + K sigma'_v tan(delta)``, ``beta = K tan(delta)``; Burland 1973, "Shaft friction
  of piles in clay - a simple fundamental approach", Ground Engineering 6(3):30-42).
* **Radial consolidation around a driven pile** (:func:`radial_series`,
  :func:`radial_excess_pressure`; Randolph & Wroth 1979, "An analytical solution for the
  consolidation around a driven pile", IJNAMG 3:217-229): the excess pore pressure that the
  pile's installation leaves (cylindrical cavity expansion) dissipating by radial flow.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import integrate, optimize, special

from pilegroup.model.units import GAMMA_WATER

#: Shaft friction magnitude (kPa) against depth (m): a vectorised callable ``f(z)``, or the
#: stations ``(z, f)`` of a piecewise-linear profile (held constant beyond its ends).
Friction = Callable[[np.ndarray], np.ndarray] | tuple[Sequence[float], Sequence[float]]


# -- neutral plane of a computed pile ------------------------------------------------------------


@dataclass(frozen=True)
class NeutralPlane:
    """One pile's neutral plane at one time (units in the names)."""

    depth_m: float
    """Depth of the largest axial force, m (the head's station when the force only decreases)."""
    dragload_kN: float
    """Largest axial force minus the head load, kN (>= 0)."""
    downdrag_m: float
    """The pile's settlement at the neutral plane, m."""
    head_load_kN: float
    """The axial force at the head's station, kN."""
    max_force_kN: float
    """The largest axial force, kN."""
    equal_settlement_depth_m: float
    """Where the pile's and the soil's settlements are equal (first crossing from the soil
    settling more to the pile settling more), m; NaN when they do not cross."""


def _vertex(z: np.ndarray, f: np.ndarray, k: int) -> tuple[float, float]:
    """Depth and value of the largest ``f`` near station ``k`` (parabola through k-1, k, k+1).

    The parabola makes the neutral plane independent of where the stations fall (it moves
    continuously with the profile); at the first or last station the station itself is used.
    """
    if k == 0 or k == len(z) - 1:
        return float(z[k]), float(f[k])
    z0, z1, z2 = z[k - 1:k + 2]
    f0, f1, f2 = f[k - 1:k + 2]
    A = np.array([[z0**2, z0, 1.0], [z1**2, z1, 1.0], [z2**2, z2, 1.0]])
    a, b, c = np.linalg.solve(A, np.array([f0, f1, f2]))
    if a >= 0.0:  # not a maximum (flat): keep the station
        return float(z1), float(f1)
    zv = float(np.clip(-b / (2 * a), z0, z2))
    return zv, float(a * zv**2 + b * zv + c)


def equal_settlement_depth(depth: np.ndarray, pile_settlement: np.ndarray,
                           soil_settlement: np.ndarray) -> float:
    """Depth (m) where ``s_pile - s_soil`` first changes sign from negative to >= 0, or NaN.

    Linear interpolation between the stations; settlements m, down positive.
    """
    z = np.asarray(depth, dtype=float)
    d = np.asarray(pile_settlement, dtype=float) - np.asarray(soil_settlement, dtype=float)
    cross = np.nonzero((d[:-1] < 0.0) & (d[1:] >= 0.0))[0]
    if not cross.size:
        return float("nan")
    j = int(cross[0])
    return float(z[j] + (z[j + 1] - z[j]) * (-d[j]) / (d[j + 1] - d[j]))


def neutral_plane(depth: np.ndarray, force: np.ndarray, pile_settlement: np.ndarray,
                  soil_settlement: np.ndarray, head_load: float | None = None) -> NeutralPlane:
    """The neutral plane of a pile from its profiles at the same stations (Fellenius 2004).

    ``depth`` m (down positive, head to toe), ``force`` kN (compression positive),
    ``pile_settlement`` and ``soil_settlement`` m (down positive). The head load ``Q`` is the
    force at the first station, or ``head_load`` (kN) when given: then a station ``z = 0`` with
    ``N = Q`` is put ahead of the profile when its first station is below the head (the
    settlements there taken as those of the first station).

    Interpolation: the depth of the largest force is the vertex of the parabola through the
    largest station value and its two neighbours (exact when ``N`` is quadratic, i.e. the
    friction linear in depth through zero; within a station spacing at a kink of ``N``, i.e. a
    jump of the friction), so it moves continuously with the profile instead of snapping to a
    station. No negative friction: the neutral plane is at the head, dragload 0. Largest force
    at the last station (an end-bearing pile whose negative friction reaches the toe): the
    neutral plane is that station. The downdrag is the pile's settlement linearly interpolated
    at the neutral plane; :func:`equal_settlement_depth` gives the settlement check.
    """
    z = np.asarray(depth, dtype=float)
    N = np.asarray(force, dtype=float)
    sp = np.asarray(pile_settlement, dtype=float)
    ss = np.asarray(soil_settlement, dtype=float)
    head = float(N[0]) if head_load is None else float(head_load)
    if head_load is not None and z[0] > 0.0:
        z, N = np.r_[0.0, z], np.r_[head, N]
        sp, ss = np.r_[sp[0], sp], np.r_[ss[0], ss]
    k = int(np.argmax(N))
    zn, nmax = _vertex(z, N, k)
    return NeutralPlane(depth_m=zn, dragload_kN=max(nmax - head, 0.0),
                        downdrag_m=float(np.interp(zn, z, sp)), head_load_kN=head,
                        max_force_kN=nmax,
                        equal_settlement_depth_m=equal_settlement_depth(z, sp, ss))


# -- the unified method's force balance (closed form) -------------------------------------------


def _layer_bounds(thickness_m: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """Tops and thicknesses of the layers (m); the last layer extends downwards without end."""
    h = np.asarray(thickness_m, dtype=float)
    if h.ndim != 1 or not h.size or np.any(h <= 0.0):
        raise ValueError("thickness_m: one positive thickness per layer, top down")
    tops = np.r_[0.0, np.cumsum(h)[:-1]]
    return tops, np.r_[h[:-1], np.inf]


def effective_vertical_stress(z: np.ndarray, thickness_m: Sequence[float],
                              unit_weight: Sequence[float], surcharge_kPa: float = 0.0
                              ) -> np.ndarray:
    """Vertical effective stress ``sigma'_v(z) = q + sum_j gamma'_j dz_j`` (kPa) at depths ``z``.

    ``thickness_m``: the layers top down (m; the last continues below its bottom);
    ``unit_weight``: each layer's effective unit weight (kN/m^3), buoyant ``gamma - gamma_w``
    below the water table, total above it; ``surcharge_kPa``: a wide fill on the surface
    (one-dimensional loading, drained: the long-term stress).
    """
    tops, h = _layer_bounds(thickness_m)
    g = np.broadcast_to(np.asarray(unit_weight, dtype=float), tops.shape)
    zz = np.asarray(z, dtype=float)[..., None]
    return surcharge_kPa + np.sum(g * np.clip(zz - tops, 0.0, h), axis=-1)


def beta_friction(z: np.ndarray, thickness_m: Sequence[float], unit_weight: Sequence[float],
                  K: float | Sequence[float], delta_deg: float | Sequence[float],
                  adhesion_kPa: float | Sequence[float] = 0.0, surcharge_kPa: float = 0.0
                  ) -> np.ndarray:
    """Shaft friction ``f = c_a + K sigma'_v tan(delta)`` (kPa, a magnitude) at depths ``z`` (m).

    The beta method (Burland 1973; Fellenius 2004/2021: ``beta = K tan(delta)``, ``c_a = 0``
    for effective-stress design) with the Coulomb limit of the interface: ``c_a`` adhesion
    (kPa), ``K`` the ratio of horizontal to vertical effective stress on the shaft, ``delta``
    the interface friction angle (degrees); each a scalar or one value per layer. A depth on a
    layer boundary belongs to the layer below. ``sigma'_v`` from
    :func:`effective_vertical_stress` (same layers, unit weights and surcharge).
    """
    tops, _ = _layer_bounds(thickness_m)
    zz = np.asarray(z, dtype=float)
    i = np.clip(np.searchsorted(tops, zz, side="right") - 1, 0, tops.size - 1)

    def per_layer(v: float | Sequence[float]) -> np.ndarray:
        return np.broadcast_to(np.asarray(v, dtype=float), tops.shape)[i]

    sv = effective_vertical_stress(zz, thickness_m, unit_weight, surcharge_kPa)
    return per_layer(adhesion_kPa) + per_layer(K) * sv * np.tan(np.radians(per_layer(delta_deg)))


def friction_integral(friction: Friction, z: np.ndarray, breaks: Sequence[float] = ()
                      ) -> np.ndarray:
    """``F(z) = int_0^z f dz`` (kN/m: kPa times m) at depths ``z`` (m, >= 0).

    Station arrays ``(zs, fs)``: exact for the piecewise-linear profile (constant beyond its
    ends). A callable: adaptive quadrature (scipy ``quad``, relative 1e-12) with ``breaks`` (m),
    the depths where ``f`` jumps or kinks (layer boundaries), passed as break points.
    """
    zz = np.asarray(z, dtype=float)
    if callable(friction):
        def one(b: float) -> float:
            pts = [p for p in breaks if 0.0 < p < b] or None
            return integrate.quad(lambda s: float(friction(np.asarray(s))), 0.0, b, points=pts,
                                  limit=400, epsabs=0.0, epsrel=1e-12)[0]
        return np.vectorize(one, otypes=[float])(zz)
    zs, fs = (np.asarray(a, dtype=float) for a in friction)
    end = max(float(zs[-1]), float(np.max(zz, initial=0.0))) + 1.0
    zs, fs = np.r_[0.0, zs, end], np.r_[fs[0], fs, fs[-1]]
    cum = np.r_[0.0, np.cumsum(0.5 * (fs[1:] + fs[:-1]) * np.diff(zs))]
    j = np.clip(np.searchsorted(zs, zz, side="right") - 1, 0, zs.size - 2)
    return cum[j] + 0.5 * (fs[j] + np.interp(zz, zs, fs)) * (zz - zs[j])


@dataclass(frozen=True)
class ForceBalance:
    """The unified method's force balance of one pile (units in the names)."""

    depth_m: float
    """Neutral plane: negative friction above it, positive below, m."""
    max_force_kN: float
    """Axial force at the neutral plane, ``Q + U int_0^zn f dz``, kN."""
    dragload_kN: float
    """``max_force_kN`` minus the head load, kN."""
    toe_force_kN: float
    """Axial force at the toe: ``R_t``, or less when the neutral plane reaches the toe, kN."""
    positive_shaft_kN: float
    """Positive shaft resistance below the neutral plane, ``U int_zn^L f dz``, kN."""


def force_balance(length_m: float, perimeter_m: float, friction: Friction,
                  head_load_kN: float, toe_resistance_kN: float,
                  breaks: Sequence[float] = ()) -> ForceBalance:
    """Neutral plane ``zn`` of ``Q + int_0^zn U f dz = int_zn^L U f dz + R_t`` (Fellenius 2004).

    A pile of length ``L`` (m) and perimeter ``U`` (m) whose whole shaft mobilises the friction
    magnitude ``f(z)`` (kPa; :data:`Friction`, e.g. :func:`beta_friction`), negative above the
    neutral plane and positive below it, with the head load ``Q`` (kN) and the toe resistance
    ``R_t`` (kN). With ``F(z) = int_0^z f dz`` the balance is ``F(zn) = (F(L) + (R_t - Q)/U)/2``
    (monotone in ``zn``: Brent's method). Uniform ``f``: ``zn = (L - (Q - R_t)/(U f))/2``. When
    ``R_t > Q + U F(L)`` the neutral plane is the toe and the toe takes ``Q + U F(L)`` only; when
    ``Q > R_t + U F(L)`` there is no equilibrium (``ValueError``).
    """
    U, Q, Rt = float(perimeter_m), float(head_load_kN), float(toe_resistance_kN)
    F_L = float(friction_integral(friction, length_m, breaks))
    target = 0.5 * (F_L + (Rt - Q) / U)
    if target < 0.0:
        raise ValueError(f"head load {Q:g} kN exceeds the shaft ({U * F_L:g} kN) and the toe "
                         f"({Rt:g} kN): no equilibrium")
    if target >= F_L:
        zn, F_n = float(length_m), F_L
    else:
        zn = float(optimize.brentq(
            lambda s: float(friction_integral(friction, s, breaks)) - target, 0.0, length_m,
            xtol=1e-13 * max(length_m, 1.0), rtol=4 * np.finfo(float).eps))
        F_n = target
    n_max = Q + U * F_n
    return ForceBalance(depth_m=zn, max_force_kN=n_max, dragload_kN=n_max - Q,
                        toe_force_kN=n_max - U * (F_L - F_n), positive_shaft_kN=U * (F_L - F_n))


def end_bearing_force(head_load_kN: float, perimeter_m: float, friction: Friction,
                      thickness_m: float, breaks: Sequence[float] = ()) -> float:
    """Largest axial force (kN) of an end-bearing pile: ``Q + int_0^H U f dz``.

    Negative friction ``f`` (kPa, magnitude) over the whole soft layer of thickness ``H`` (m)
    that settles past the pile, whose toe rests on a layer that does not (Fellenius 2004): the
    neutral plane is at the bottom of the soft layer.
    """
    return float(head_load_kN + perimeter_m * friction_integral(friction, thickness_m, breaks))


def unified_force_profile(z: np.ndarray, perimeter_m: float, friction: Friction,
                          head_load_kN: float, neutral_depth_m: float,
                          breaks: Sequence[float] = ()) -> np.ndarray:
    """Axial force (kN) of the unified method at depths ``z`` (m).

    ``N = Q + U F(z)`` above the neutral plane ``zn`` and ``Q + U (2 F(zn) - F(z))`` below it,
    ``F(z) = int_0^z f dz`` (:func:`friction_integral`).
    """
    zz = np.asarray(z, dtype=float)
    F = friction_integral(friction, zz, breaks)
    F_n = float(friction_integral(friction, neutral_depth_m, breaks))
    return head_load_kN + perimeter_m * np.where(zz <= neutral_depth_m, F, 2.0 * F_n - F)


# -- radial consolidation around a driven pile (Randolph & Wroth 1979) ---------------------------


def cavity_expansion_pressure(c_u_kPa: float, G_kPa: float, r0_m: float) -> tuple[float, float]:
    """Excess pore pressure at the shaft (kPa) and plastic radius ``R`` (m) of a driven pile.

    Cylindrical cavity expansion in undrained clay (Randolph & Wroth 1979, after Randolph,
    Carter & Wroth 1979): ``du = 2 c_u ln(R/r)`` for ``r0 <= r <= R``, ``R = r0 sqrt(G/c_u)``,
    so ``du_max = 2 c_u ln(R/r0) = c_u ln(G/c_u)``.
    """
    R = r0_m * np.sqrt(G_kPa / c_u_kPa)
    return float(2.0 * c_u_kPa * np.log(R / r0_m)), float(R)


def initial_excess_pressure(r_m: np.ndarray, r0_m: float, du_max_kPa: float, R_m: float
                            ) -> np.ndarray:
    """``u0 = du_max ln(R/r) / ln(R/r0)`` for ``r0 <= r <= R``, 0 beyond (kPa)."""
    r = np.asarray(r_m, dtype=float)
    return np.where(r <= R_m, du_max_kPa * np.log(R_m / r) / np.log(R_m / r0_m), 0.0)


def radial_consolidation_coefficient(k_m_per_day: float, E_kPa: float, nu: float,
                                     gamma_w: float = GAMMA_WATER) -> float:
    """``c_h = k (lambda + 2G) / gamma_w = k E (1-nu) / ((1+nu)(1-2nu) gamma_w)`` (m^2/day).

    Radial flow in plane strain with the constrained modulus (Randolph & Wroth 1979): ``k``
    m/day, ``E`` kPa, ``gamma_w`` kN/m^3.
    """
    m = E_kPa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))
    return float(k_m_per_day * m / gamma_w)


def time_factor(c_h_m2_per_day: float, t_day: np.ndarray, r0_m: float) -> np.ndarray:
    """Time factor ``T = c_h t / r0^2`` (``c_h`` m^2/day, ``t`` day, ``r0`` m)."""
    return c_h_m2_per_day * np.asarray(t_day, dtype=float) / r0_m**2


@dataclass(frozen=True)
class RadialSeries:
    """The Bessel series of :func:`radial_series` (radii m, pressures kPa)."""

    r0_m: float
    """Pile radius (impermeable shaft)."""
    r_out_m: float
    """Outer radius ``r*`` of the flow domain."""
    drained: bool
    """``u = 0`` at ``r*`` (else ``du/dr = 0``)."""
    roots: np.ndarray
    """Eigenvalues ``x_n = a_n r0`` (increasing)."""
    coefficients_kPa: np.ndarray
    """``A_n``: ``u = A_0 + sum_n A_n phi_n(r) exp(-x_n^2 T)``."""
    mean_kPa: float
    """``A_0``: the non-decaying mode, the area-weighted mean of ``u0`` (0 when drained)."""


def _characteristic(x: np.ndarray, rho: float, drained: bool) -> np.ndarray:
    """Drained: ``J1(x) Y0(rho x) - Y1(x) J0(rho x)``; impermeable: the J1/Y1 pair."""
    if drained:
        return special.j1(x) * special.y0(rho * x) - special.y1(x) * special.j0(rho * x)
    return special.j1(x) * special.y1(rho * x) - special.y1(x) * special.j1(rho * x)


def _eigenvalues(rho: float, drained: bool, n: int) -> np.ndarray:
    """The first ``n`` positive roots of :func:`_characteristic` (sign changes, then Brent)."""
    step = np.pi / (rho - 1.0) / 16.0  # the roots are about pi / (rho - 1) apart
    roots: list[float] = []
    lo = 1e-3 * step
    while len(roots) < n:
        x = lo + step * np.arange(16 * (n - len(roots) + 2) + 1)
        c = _characteristic(x, rho, drained)
        for j in np.nonzero(np.sign(c[:-1]) * np.sign(c[1:]) < 0.0)[0]:
            roots.append(optimize.brentq(_characteristic, x[j], x[j + 1], args=(rho, drained),
                                         xtol=1e-15, rtol=4 * np.finfo(float).eps))
        lo = float(x[-1])
    return np.array(roots[:n])


def _mode(x: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``phi(s) = J0(x s) Y1(x) - Y0(x s) J1(x)``: ``phi'(1) = 0`` (the impermeable shaft)."""
    return special.j0(x * s) * special.y1(x) - special.y0(x * s) * special.j1(x)


def _gauss(edges: Sequence[float], per_unit: float, order: int = 12
           ) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss-Legendre nodes and weights on ``[edges[0], edges[-1]]``.

    Panels never straddle an edge; ``per_unit`` panels per unit length (at least 8 a segment).
    """
    g, w = np.polynomial.legendre.leggauss(order)
    nodes, weights = [], []
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        e = np.linspace(a, b, max(8, int(np.ceil(per_unit * (b - a)))) + 1)
        mid, half = 0.5 * (e[1:] + e[:-1]), 0.5 * np.diff(e)
        nodes.append((mid[:, None] + half[:, None] * g).ravel())
        weights.append((half[:, None] * w).ravel())
    return np.concatenate(nodes), np.concatenate(weights)


def radial_series(r0_m: float, r_out_m: float, du_max_kPa: float, R_m: float,
                  drained: bool = True, n_terms: int = 200) -> RadialSeries:
    """The series of ``du/dt = c_h (1/r) d/dr (r du/dr)`` on ``r0 <= r <= r*`` (Randolph & Wroth).

    Impermeable shaft (``du/dr = 0`` at ``r0``); at ``r* = r_out_m`` ``u = 0`` (``drained``) or
    ``du/dr = 0``; ``u0`` of :func:`initial_excess_pressure` (``du_max``, ``R``). In ``s = r/r0``
    and ``T`` (:func:`time_factor`): ``u = A_0 + sum_n A_n phi_n(s) exp(-x_n^2 T)``,
    ``phi_n = J0(x_n s) Y1(x_n) - Y0(x_n s) J1(x_n)``, ``x_n`` the roots of
    ``J1(x) Y0(rho x) - Y1(x) J0(rho x)`` (drained) or ``J1(x) Y1(rho x) - Y1(x) J1(rho x)``,
    ``rho = r*/r0``; ``A_n = int s u0 phi_n ds / int s phi_n^2 ds`` by composite Gauss-Legendre
    quadrature (panels split at ``R``, about two per half-wave of the last mode); ``A_0``, kept
    only for the impermeable outer radius, is the area-weighted mean of ``u0``. The truncation
    error is largest at ``T = 0`` at the shaft, where the slope of ``u0`` defies the shaft's zero
    flux: 0.8 % of ``du_max`` there and 0.05 % in the area-weighted L2 norm with 200 terms
    (``r*/r0 = 20``, ``R/r0 = 10``; it falls as 1/n_terms; at ``T >= 0.1``, 100 terms converge).
    """
    if not 0.0 < r0_m < r_out_m or R_m <= r0_m:
        raise ValueError("need 0 < r0 < r_out and R > r0")
    rho, rho_R = r_out_m / r0_m, min(R_m / r0_m, r_out_m / r0_m)
    x = _eigenvalues(rho, drained, n_terms)
    edges = [1.0, rho_R] + ([rho] if rho_R < rho else [])
    s, w = _gauss(edges, per_unit=2.0 * x[-1] / np.pi)
    u0 = initial_excess_pressure(s * r0_m, r0_m, du_max_kPa, R_m)
    phi = _mode(x[:, None], s[None, :])
    A = (phi * (w * s * u0)).sum(axis=1) / (phi**2 * (w * s)).sum(axis=1)
    mean = 0.0 if drained else float(np.sum(w * s * u0) / np.sum(w * s))
    return RadialSeries(r0_m=float(r0_m), r_out_m=float(r_out_m), drained=drained, roots=x,
                        coefficients_kPa=A, mean_kPa=mean)


def radial_excess_pressure(series: RadialSeries, r_m: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Excess pore pressure ``u(r, T)`` (kPa) of a :class:`RadialSeries`.

    ``r_m`` (m, within ``[r0, r*]``) and ``T`` (:func:`time_factor`, >= 0) broadcast against each
    other (``r[None, :]`` and ``T[:, None]`` give a table of times by radii).
    """
    s, TT = np.broadcast_arrays(np.asarray(r_m, dtype=float) / series.r0_m,
                                np.asarray(T, dtype=float))
    if np.any(s < 1.0 - 1e-12) or np.any(s > series.r_out_m / series.r0_m + 1e-12):
        raise ValueError("r outside [r0, r_out]")
    if np.any(TT < 0.0):
        raise ValueError("T < 0")
    u = np.full(s.shape, series.mean_kPa)
    for lo in range(0, series.roots.size, 64):  # blocks of modes: bounded memory
        x = series.roots[lo:lo + 64]
        A = series.coefficients_kPa[lo:lo + 64]
        u += np.sum(A * _mode(x, s[..., None]) * np.exp(-x**2 * TT[..., None]), axis=-1)
    return u
