"""Soil laws in Mandel notation: linear elasticity, Mohr–Coulomb, Drucker–Prager.

Conventions: stresses in kPa, strains dimensionless, tension positive. Vectors are Mandel
6-vectors ``(xx, yy, zz, sqrt2*xy, sqrt2*xz, sqrt2*yz)``; tangents are 6x6 Mandel matrices
``d sigma / d eps`` (see :mod:`pilegroup.constitutive.base`). All laws are rate independent: the
``dt`` argument of ``update`` is accepted and ignored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pilegroup.constitutive.base import MANDEL_I, as_points, broadcast_state, check_param

__all__ = ["LinearElastic", "elastic_matrix"]


def elastic_matrix(E: float, nu: float) -> np.ndarray:
    """Isotropic elasticity matrix in Mandel notation (6x6, kPa for E in kPa).

    ``C = lam * I (x) I + 2 G * Id`` with ``lam = E nu / ((1 + nu)(1 - 2 nu))``,
    ``G = E / (2 (1 + nu))``; in Mandel notation the 4th-order identity is the 6x6 identity.
    """
    lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    G = E / (2.0 * (1.0 + nu))
    return lam * np.outer(MANDEL_I, MANDEL_I) + 2.0 * G * np.eye(6)


def _check_elastic(E: float, nu: float) -> None:
    check_param("E", E, "kPa", 0.0, np.inf, lo_open=True, hi_open=True)
    check_param("nu", nu, "-", -1.0, 0.5, lo_open=True, hi_open=True)


@dataclass(frozen=True)
class LinearElastic:
    """Isotropic linear elasticity (no plastic work at all).

    Attributes:
        E: Young's modulus, kPa (> 0).
        nu: Poisson's ratio, - (in (-1, 0.5)).

    State: ``{"stress": (n, 6)}`` (Mandel, kPa, tension positive).

    ``update`` returns the tangent as a **read-only broadcast view** of one 6x6 matrix,
    shape ``(n, 6, 6)`` (no per-point memory); copy it (``np.array(tangent)``) before writing.
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        _check_elastic(self.E, self.nu)

    @property
    def C(self) -> np.ndarray:
        """Elasticity matrix, Mandel 6x6, kPa."""
        return elastic_matrix(self.E, self.nu)

    def state_layout(self) -> dict[str, int]:
        """State name -> components per point."""
        return {"stress": 6}

    def initial_state(self, n: int, stress0: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """Initial state of ``n`` points; ``stress0`` (kPa, Mandel, ``(6,)`` or ``(n, 6)``)."""
        return {"stress": broadcast_state(n, stress0, 6, "stress0")}

    def update(
        self, d_strain: np.ndarray, state_n: dict[str, np.ndarray], dt: float = 0.0
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Stress update ``sigma = sigma_n + C : d_eps``.

        Args:
            d_strain: (n, 6) Mandel strain increment, tension positive.
            state_n: committed state (not mutated).
            dt: time step, day (ignored).

        Returns:
            ``(stress, state_trial, tangent)``: stress (n, 6) kPa; ``{"stress": stress}``;
            tangent (n, 6, 6) kPa, a read-only broadcast view of the constant elastic matrix.
        """
        de = as_points(d_strain, 6, "d_strain")
        C = self.C
        stress = state_n["stress"] + de @ C  # C symmetric
        tangent = np.broadcast_to(C, (de.shape[0], 6, 6))
        return stress, {"stress": stress}, tangent
