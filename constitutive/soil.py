"""Soil laws in Mandel notation: linear elasticity, Mohr–Coulomb, Drucker–Prager.

Conventions: stresses in kPa, strains dimensionless, tension positive. Vectors are Mandel
6-vectors ``(xx, yy, zz, sqrt2*xy, sqrt2*xz, sqrt2*yz)``; tangents are 6x6 Mandel matrices
``d sigma / d eps`` (see :mod:`pilegroup.constitutive.base`). All laws are rate independent: the
``dt`` argument of ``update`` is accepted and ignored.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pilegroup.constitutive.base import (
    MANDEL_I,
    SQRT2,
    as_points,
    broadcast_state,
    mandel_to_tensor,
)
from pilegroup.constitutive.paper import DruckerPragerCone, dp_outer_cone
from pilegroup.errors import ConstitutiveError
from pilegroup.validate import (
    ErrorClass,
    require_in_range,
    require_non_negative,
    require_positive,
)

__all__ = [
    "DruckerPrager", "LinearElastic", "MohrCoulomb", "elastic_matrix", "principal_stresses",
    "require_elastic_constants",
]

#: codes of the ``"mode"`` state component (which branch of the return mapping was taken)
MODE_ELASTIC, MODE_FACE, MODE_EDGE_A, MODE_EDGE_B, MODE_APEX = 0, 1, 2, 3, 4


def elastic_matrix(E: float, nu: float) -> np.ndarray:
    """Isotropic elasticity matrix in Mandel notation (6x6, kPa for E in kPa).

    ``C = lam * I (x) I + 2 G * Id`` with ``lam = E nu / ((1 + nu)(1 - 2 nu))``,
    ``G = E / (2 (1 + nu))``; in Mandel notation the 4th-order identity is the 6x6 identity.
    """
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    G = E / (2.0 * (1.0 + nu))
    return lam * np.outer(MANDEL_I, MANDEL_I) + 2.0 * G * np.eye(6)


def require_elastic_constants(E: float, nu: float, *,
                              error: ErrorClass = ConstitutiveError) -> None:
    """Raise ``error`` unless ``E`` (kPa) > 0 and ``-1 < nu < 0.5`` (isotropic elasticity)."""
    require_positive("E", E, "kPa", error=error)
    require_in_range("nu", nu, -1.0, 0.5, "-", lo_open=True, hi_open=True, error=error)


@dataclass(frozen=True)
class _Elastic:
    """Isotropic elasticity shared by the soil laws: parameters, checks, elastic predictor."""

    E: float
    nu: float

    def __post_init__(self) -> None:
        require_elastic_constants(self.E, self.nu)

    @property
    def C(self) -> np.ndarray:
        """Elasticity matrix, Mandel 6x6, kPa."""
        return elastic_matrix(self.E, self.nu)

    def update(
        self, d_strain: np.ndarray, state_n: dict[str, np.ndarray], dt: float = 0.0
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Elastic predictor ``sigma_tr = sigma_n + C : d_eps``, then the law's correction.

        Args:
            d_strain: (n, 6) Mandel strain increment, tension positive.
            state_n: committed state (not mutated).
            dt: time step, day (ignored: the soil laws are rate independent).

        Returns:
            ``(stress, state_trial, tangent)``: stress (n, 6) kPa; the trial state; tangent
            (n, 6, 6) kPa, ``d stress / d d_strain`` (the class docstring says which).
        """
        de = as_points(d_strain, 6, "d_strain")
        C = self.C
        return self._correct(state_n["stress"] + de @ C, state_n, C)  # C symmetric

    def _correct(
        self, sig_tr: np.ndarray, state_n: dict[str, np.ndarray], C: np.ndarray
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        raise NotImplementedError


@dataclass(frozen=True)
class LinearElastic(_Elastic):
    """Isotropic linear elasticity (no plastic work at all).

    Attributes:
        E: Young's modulus, kPa (> 0).
        nu: Poisson's ratio, - (in (-1, 0.5)).

    State: ``{"stress": (n, 6)}`` (Mandel, kPa, tension positive).

    ``update`` (``sigma = sigma_n + C : d_eps``) returns the tangent as a **read-only broadcast
    view** of the constant elastic matrix, shape ``(n, 6, 6)`` (no per-point memory); copy it
    (``np.array(tangent)``) before writing.
    """

    def state_layout(self) -> dict[str, int]:
        """State name -> components per point."""
        return {"stress": 6}

    def initial_state(self, n: int, stress0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points; ``stress0`` (kPa, Mandel, ``(6,)`` or ``(n, 6)``)."""
        return {"stress": broadcast_state(n, stress0, 6, "stress0")}

    def _correct(
        self, sig_tr: np.ndarray, state_n: dict[str, np.ndarray], C: np.ndarray
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        tangent = np.broadcast_to(C, (sig_tr.shape[0], 6, 6))
        return sig_tr, {"stress": sig_tr}, tangent


def principal_stresses(sig: np.ndarray) -> np.ndarray:
    """Principal values ``(n, 3)`` in descending order of Mandel vectors ``(n, 6)``.

    Closed form (invariants and Lode angle), vectorised; used for the yield check. Accurate to
    about ``1e-15 * |sigma|`` away from coincident eigenvalues; the return mapping itself uses
    LAPACK (``numpy.linalg.eigh``) on the plastic points.
    """
    p = (sig[:, 0] + sig[:, 1] + sig[:, 2]) / 3.0
    sx, sy, sz = sig[:, 0] - p, sig[:, 1] - p, sig[:, 2] - p
    txy, txz, tyz = sig[:, 3] / SQRT2, sig[:, 4] / SQRT2, sig[:, 5] / SQRT2
    J2 = 0.5 * (sx * sx + sy * sy + sz * sz) + txy * txy + txz * txz + tyz * tyz
    J3 = (sx * (sy * sz - tyz * tyz) - txy * (txy * sz - tyz * txz)
          + txz * (txy * tyz - sy * txz))
    den = J2**1.5
    r = np.zeros_like(J2)
    np.divide(1.5 * math.sqrt(3.0) * J3, den, out=r, where=den > 1e-300)
    np.clip(r, -1.0, 1.0, out=r)
    th = np.arccos(r) / 3.0
    rad = 2.0 * np.sqrt(J2 / 3.0)
    out = np.empty((sig.shape[0], 3))
    out[:, 0] = p + rad * np.cos(th)
    out[:, 1] = p + rad * np.cos(th - 2.0 * math.pi / 3.0)
    out[:, 2] = p + rad * np.cos(th + 2.0 * math.pi / 3.0)
    return out


def _spectral_basis(V: np.ndarray) -> np.ndarray:
    """Orthonormal Mandel basis ``(m, 6, 6)`` from eigenvectors ``V`` (columns, ``(m, 3, 3)``).

    Columns: ``E_i = e_i (x) e_i`` (i = 1..3), then ``M_ij = (e_i (x) e_j + e_j (x) e_i)/sqrt2``
    for (i, j) = (1, 2), (1, 3), (2, 3).
    """
    m = V.shape[0]
    R = np.empty((m, 6, 6))
    for i in range(3):
        a = V[:, :, i]
        R[:, 0, i] = a[:, 0] * a[:, 0]
        R[:, 1, i] = a[:, 1] * a[:, 1]
        R[:, 2, i] = a[:, 2] * a[:, 2]
        R[:, 3, i] = SQRT2 * a[:, 0] * a[:, 1]
        R[:, 4, i] = SQRT2 * a[:, 0] * a[:, 2]
        R[:, 5, i] = SQRT2 * a[:, 1] * a[:, 2]
    for col, (i, j) in zip((3, 4, 5), ((0, 1), (0, 2), (1, 2)), strict=True):
        a, b = V[:, :, i], V[:, :, j]
        R[:, 0, col] = SQRT2 * a[:, 0] * b[:, 0]
        R[:, 1, col] = SQRT2 * a[:, 1] * b[:, 1]
        R[:, 2, col] = SQRT2 * a[:, 2] * b[:, 2]
        R[:, 3, col] = a[:, 0] * b[:, 1] + a[:, 1] * b[:, 0]
        R[:, 4, col] = a[:, 0] * b[:, 2] + a[:, 2] * b[:, 0]
        R[:, 5, col] = a[:, 1] * b[:, 2] + a[:, 2] * b[:, 1]
    return R


@dataclass(frozen=True)
class _ElastoPlastic(_Elastic):
    """Strength parameters and state handling of the perfectly plastic soil laws (Mandel).

    ``update`` returns the stress on or inside the yield surface and the consistent
    (algorithmic) tangent, not symmetric when psi != phi.
    """

    c: float
    phi_deg: float
    psi_deg: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        require_non_negative("c", self.c, "kPa", error=ConstitutiveError)
        require_in_range("phi_deg", self.phi_deg, 0.0, 90.0, "deg", hi_open=True,
                         error=ConstitutiveError)
        require_in_range("psi_deg", self.psi_deg, 0.0, self.phi_deg, "deg",
                         error=ConstitutiveError)
        if self.c == 0.0 and self.phi_deg == 0.0:
            raise ConstitutiveError("c = 0 kPa and phi_deg = 0 deg give no strength; "
                                    "allowed: c > 0 kPa or phi_deg > 0 deg")

    @property
    def K(self) -> float:
        """Bulk modulus, kPa."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu))

    @property
    def G(self) -> float:
        """Shear modulus, kPa."""
        return self.E / (2.0 * (1.0 + self.nu))

    def state_layout(self) -> dict[str, int]:
        """State name -> components per point.

        ``stress`` (Mandel, kPa), ``eps_p`` (plastic strain, Mandel, -), ``mode`` (branch of the
        last return: 0 elastic, 1 face/cone, 2 edge sigma1 = sigma2, 3 edge sigma2 = sigma3,
        4 apex).
        """
        return {"stress": 6, "eps_p": 6, "mode": 1}

    def initial_state(self, n: int, stress0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points; ``stress0`` (kPa, Mandel, ``(6,)`` or ``(n, 6)``).

        The initial stress is not checked against the yield surface; a state outside it is
        returned in the first ``update``.
        """
        return {"stress": broadcast_state(n, stress0, 6, "stress0"), "eps_p": np.zeros((n, 6)),
                "mode": np.zeros((n, 1))}

    def _correct(
        self, sig_tr: np.ndarray, state_n: dict[str, np.ndarray], C: np.ndarray
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Return mapping of the plastic points and their consistent tangent."""
        stress = sig_tr.copy()
        n = sig_tr.shape[0]
        tangent = np.empty((n, 6, 6))
        tangent[:] = C
        eps_p = state_n["eps_p"].copy()
        mode = np.zeros((n, 1))
        plastic = self._trial_plastic(sig_tr)
        if np.any(plastic):
            idx = np.nonzero(plastic)[0]
            s_new, D, md = self._return(sig_tr[idx])
            stress[idx] = s_new
            tangent[idx] = D
            mode[idx, 0] = md
            eps_p[idx] += (sig_tr[idx] - s_new) @ np.linalg.inv(C)
        return stress, {"stress": stress, "eps_p": eps_p, "mode": mode}, tangent

    def _trial_plastic(self, sig_tr: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def _return(self, sig_tr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError


@dataclass(frozen=True)
class MohrCoulomb(_ElastoPlastic):
    """Linear elastic–perfectly plastic Mohr–Coulomb, non-associated (potential with psi).

    ``f = (s1 - s3) + (s1 + s3) sin(phi) - 2 c cos(phi)`` with principal stresses
    ``s1 >= s2 >= s3`` (tension positive), potential ``g = (s1 - s3) + (s1 + s3) sin(psi)``.
    Return mapping in principal space (de Souza Neto, Peric & Owen 2008, Sect. 8.2): one plane
    (face), two planes (edge ``s1 = s2``, the triaxial-compression meridian, or edge
    ``s2 = s3``, the extension meridian), or the apex ``s = c cot(phi)`` (there the stress is
    projected to the apex for any psi, i.e. the apex acts as a tension cut-off; with psi < phi
    no other return exists beyond it). The consistent tangent is assembled from the principal
    tangent and the spin terms ``(h_i - h_j)/(s_i - s_j)`` of the isotropic tensor function.

    Attributes:
        E: Young's modulus, kPa (> 0).
        nu: Poisson's ratio, - (in (-1, 0.5)).
        c: cohesion, kPa (>= 0).
        phi_deg: friction angle, degrees (in [0, 90)).
        psi_deg: dilatancy angle, degrees (in [0, phi_deg]); default 0.

    State: see :meth:`state_layout`.
    """

    def _f_principal(self, s: np.ndarray) -> np.ndarray:
        sf, cf = math.sin(math.radians(self.phi_deg)), math.cos(math.radians(self.phi_deg))
        return (s[:, 0] - s[:, 2]) + (s[:, 0] + s[:, 2]) * sf - 2.0 * self.c * cf

    def yield_function(self, stress: np.ndarray) -> np.ndarray:
        """Mohr–Coulomb f (kPa) of Mandel stresses ``(n, 6)``; f <= 0 is admissible.

        Principal stresses from LAPACK (accurate also at coincident eigenvalues).
        """
        w = np.linalg.eigvalsh(mandel_to_tensor(as_points(stress, 6, "stress")))
        return self._f_principal(w[:, ::-1])

    def _trial_plastic(self, sig_tr: np.ndarray) -> np.ndarray:
        # 1) cheap upper bound from p and J2 only (no trigonometry):
        #    s1 - s3 <= 2 sqrt(J2), s1 + s3 = 2p - (s2 - p) <= 2p + sqrt(J2/3)
        sf, cf = math.sin(math.radians(self.phi_deg)), math.cos(math.radians(self.phi_deg))
        p = sig_tr[:, 0] + sig_tr[:, 1]
        p += sig_tr[:, 2]
        p /= 3.0
        J2 = np.einsum("ij,ij->i", sig_tr, sig_tr)
        J2 -= 3.0 * p * p
        J2 *= 0.5
        q = np.sqrt(np.maximum(J2, 0.0), out=J2)
        f_ub = (2.0 + sf / math.sqrt(3.0)) * q
        f_ub += 2.0 * sf * p
        f_ub -= 2.0 * self.c * cf
        scale = np.abs(p) + q + self.c  # >= |s_i| / 2
        plastic = np.zeros(sig_tr.shape[0], dtype=bool)
        cand = f_ub > -1e-6 * scale
        if not np.any(cand):
            return plastic
        idx = np.nonzero(cand)[0]
        # 2) closed-form principal stresses on the candidates; they lose accuracy (~sqrt(eps))
        #    near coincident eigenvalues, so points within a band are re-checked with LAPACK
        sc = sig_tr[idx]
        s = principal_stresses(sc)
        f = self._f_principal(s)
        sck = np.abs(s).max(axis=1) + self.c
        near = np.abs(f) <= 1e-6 * sck
        if np.any(near):
            f[near] = self.yield_function(sc[near])
        plastic[idx] = f > 1e-12 * sck
        return plastic

    def _return(self, sig_tr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return mapping of trial stresses known to be outside the surface."""
        m = sig_tr.shape[0]
        w, V = np.linalg.eigh(mandel_to_tensor(sig_tr))
        s = w[:, ::-1].copy()  # descending
        V = V[:, :, ::-1]
        K, G, c = self.K, self.G, self.c
        sf, cf = math.sin(math.radians(self.phi_deg)), math.cos(math.radians(self.phi_deg))
        sp = math.sin(math.radians(self.psi_deg))
        Dp = (K - 2.0 * G / 3.0) * np.ones((3, 3)) + 2.0 * G * np.eye(3)
        cc = 2.0 * c * cf
        scale = np.abs(s).max(axis=1) + c
        tol = 1e-12 * scale

        def plane(i, j, sn):  # gradient of (s_i - s_j) + (s_i + s_j) sin
            v = np.zeros(3)
            v[i], v[j] = 1.0 + sn, -(1.0 - sn)
            return v

        h = np.empty((m, 3))
        A = np.empty((m, 3, 3))
        mode = np.full(m, MODE_FACE)
        # -- face (planes of s1 and s3)
        nf, ng = plane(0, 2, sf), plane(0, 2, sp)
        Dng = Dp @ ng
        dg = (s @ nf - cc) / (nf @ Dng)
        h[:] = s - dg[:, None] * Dng
        A[:] = np.eye(3) - np.outer(Dng, nf) / (nf @ Dng)
        bad = (h[:, 1] > h[:, 0] + tol) | (h[:, 2] > h[:, 1] + tol)
        if np.any(bad):
            b = np.nonzero(bad)[0]
            first_a = h[b, 1] > h[b, 0] + tol[b]
            # edge A: s1 = s2 (second plane (s2, s3)); edge B: s2 = s3 (second plane (s1, s2))
            edges = {
                MODE_EDGE_A: (np.column_stack([nf, plane(1, 2, sf)]),
                              np.column_stack([ng, plane(1, 2, sp)])),
                MODE_EDGE_B: (np.column_stack([nf, plane(0, 1, sf)]),
                              np.column_stack([ng, plane(0, 1, sp)])),
            }
            done = np.zeros(b.size, dtype=bool)
            for attempt in range(2):
                for md, (Nf, Ng) in edges.items():
                    want = ~done & ((first_a if md == MODE_EDGE_A else ~first_a) == (attempt == 0))
                    if not np.any(want):
                        continue
                    k = b[want]
                    DNg = Dp @ Ng
                    Minv = np.linalg.inv(Nf.T @ DNg)
                    lam = (s[k] @ Nf - cc) @ Minv.T
                    hk = s[k] - lam @ DNg.T
                    ok = np.all(lam >= -1e-12 * scale[k, None] / (2.0 * G), axis=1)
                    ok &= (hk[:, 0] >= hk[:, 2] - tol[k]) & (hk[:, 1] >= hk[:, 2] - tol[k])
                    ok &= hk[:, 0] >= hk[:, 1] - tol[k]
                    kk = k[ok]
                    h[kk] = hk[ok]
                    A[kk] = np.eye(3) - DNg @ Minv @ Nf.T
                    mode[kk] = md
                    done[np.nonzero(want)[0][ok]] = True
            rest = b[~done]
            if rest.size:
                if sf <= 0.0:  # pragma: no cover - Tresca: an edge always applies
                    raise ConstitutiveError("Mohr–Coulomb return mapping failed (phi = 0)")
                h[rest] = c * cf / sf
                A[rest] = 0.0
                mode[rest] = MODE_APEX
        # -- consistent tangent in the spectral basis: blockdiag(A Dp, 2G (h_i-h_j)/(s_i-s_j))
        B = np.zeros((m, 6, 6))
        B[:, :3, :3] = A @ Dp
        for col, (i, j) in zip((3, 4, 5), ((0, 1), (0, 2), (1, 2)), strict=True):
            ds = s[:, i] - s[:, j]
            close = np.abs(ds) <= 1e-9 * scale
            ratio = np.where(close, A[:, i, i] - A[:, i, j],
                             (h[:, i] - h[:, j]) / np.where(close, 1.0, ds))
            B[:, col, col] = 2.0 * G * ratio
        R = _spectral_basis(V)
        stress = np.einsum("mij,mj->mi", R[:, :, :3], h)
        D = R @ B @ R.transpose(0, 2, 1)
        return stress, D, mode


@dataclass(frozen=True)
class DruckerPrager(_ElastoPlastic, DruckerPragerCone):
    """Linear elastic–perfectly plastic Drucker–Prager matched to Mohr–Coulomb by Eq. 13.

    ``F = sqrt(J2) + alpha I1 - k`` (tension-positive I1), outer cone (coincides with MC on the
    triaxial-compression meridian): ``alpha = 2 sin(phi) / (sqrt3 (3 - sin(phi)))``,
    ``k = 6 c cos(phi) / (sqrt3 (3 - sin(phi)))``; potential ``sqrt(J2) + alpha_psi I1`` with
    alpha_psi from psi by the same formula. Cone return closed form; apex ``I1 = k / alpha``
    (tension cut-off-like projection for psi < phi, as for MohrCoulomb).

    Attributes and state: as :class:`MohrCoulomb`; ``alpha`` and ``k`` are the cone's Eq. 13
    constants.
    """

    def yield_function(self, stress: np.ndarray) -> np.ndarray:
        """Drucker–Prager F (kPa) of Mandel stresses ``(n, 6)``; F <= 0 is admissible."""
        sig = as_points(stress, 6, "stress")
        I1 = sig[:, :3].sum(axis=1)
        dev = sig - (I1 / 3.0)[:, None] * MANDEL_I
        return np.sqrt(0.5 * np.einsum("ij,ij->i", dev, dev)) + self.alpha * I1 - self.k

    def _trial_plastic(self, sig_tr: np.ndarray) -> np.ndarray:
        f = self.yield_function(sig_tr)
        return f > 1e-12 * (np.abs(sig_tr).max(axis=1) + self.c)

    def _return(self, sig_tr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        m = sig_tr.shape[0]
        K, G = self.K, self.G
        al, k = self.alpha, self.k
        ab = dp_outer_cone(self.c, self.psi_deg)[0]
        I1 = sig_tr[:, :3].sum(axis=1)
        dev = sig_tr - (I1 / 3.0)[:, None] * MANDEL_I
        nrm = np.sqrt(np.einsum("ij,ij->i", dev, dev))  # = sqrt(2 J2)
        F = nrm / SQRT2 + al * I1 - k
        H = G + 9.0 * K * al * ab
        dg = F / H
        apex = (nrm / SQRT2 - G * dg < 0.0) & (al > 0.0)
        nvec = dev / np.where(nrm > 0.0, nrm, 1.0)[:, None]
        a_g = SQRT2 * G * nvec + 3.0 * K * ab * MANDEL_I  # C : dG/dsigma
        a_f = SQRT2 * G * nvec + 3.0 * K * al * MANDEL_I  # C : dF/dsigma
        stress = sig_tr - dg[:, None] * a_g
        Pdev = np.eye(6) - np.outer(MANDEL_I, MANDEL_I) / 3.0
        coef = dg * SQRT2 * 2.0 * G * G / np.where(nrm > 0.0, nrm, 1.0)
        D = (self.C[None] - a_g[:, :, None] * a_f[:, None, :] / H
             - coef[:, None, None] * (Pdev[None] - nvec[:, :, None] * nvec[:, None, :]))
        mode = np.full(m, MODE_FACE)
        if np.any(apex):
            stress[apex] = (k / (3.0 * al)) * MANDEL_I
            D[apex] = 0.0
            mode[apex] = MODE_APEX
        return stress, D, mode
