"""Common protocol of the pointwise constitutive laws and Mandel-notation helpers.

Conventions (whole package)
---------------------------
* Units: kN, m, day. Stresses in kPa, interface stiffness in kPa/m, viscosity in kPa·day/m.
* Tension positive (compression negative) for stresses and strains.
* Soil tensors in **Mandel notation**, six components ordered
  ``(xx, yy, zz, sqrt2*xy, sqrt2*xz, sqrt2*yz)`` for both stress and strain, so strain
  components 4-6 are ``sqrt2 * eps_ij = gamma_ij / sqrt2``. The tangent is the 6x6 Mandel matrix
  ``d sigma / d eps``; with Mandel notation the double contraction ``A:B`` is the plain dot
  product of the 6-vectors, and a tangent in Mandel notation is symmetric when the 4th-order
  tensor is major-symmetric.

The protocol
------------
Every law is a frozen dataclass built from scalar parameters, checked when it is built
(:mod:`pilegroup.validate` with :class:`~pilegroup.errors.ConstitutiveError`), with

* ``state_layout() -> dict[str, int]``: state name -> components per point (always "stress" or,
  for the interface, "traction");
* ``initial_state(n, ...) -> dict[str, np.ndarray]``: arrays shaped ``(n, k)``;
* ``update(d_strain, state_n, dt) -> (stress, state_trial, tangent)``: vectorised over ``n``
  points; never mutates ``state_n``; the caller commits (adopts ``state_trial``) or rolls back
  (keeps ``state_n``).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from pilegroup.errors import ConstitutiveError

SQRT2 = float(np.sqrt(2.0))

#: Mandel identity vector (second-order identity tensor).
MANDEL_I = np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])


@runtime_checkable
class ConstitutiveLaw(Protocol):
    """Shape of every pointwise law (soil: Mandel 6-vectors; interface: 3-vectors)."""

    def state_layout(self) -> dict[str, int]:
        """Map state name -> number of components per point."""
        ...

    def update(
        self, d_strain: np.ndarray, state_n: dict[str, np.ndarray], dt: float
    ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray]:
        """Return (stress, state_trial, tangent) for the increment ``d_strain`` over ``dt``."""
        ...


def mandel_to_tensor(v: np.ndarray) -> np.ndarray:
    """Convert Mandel 6-vectors ``(..., 6)`` to symmetric 3x3 tensors ``(..., 3, 3)``."""
    v = np.asarray(v, dtype=float)
    t = np.empty(v.shape[:-1] + (3, 3))
    t[..., 0, 0] = v[..., 0]
    t[..., 1, 1] = v[..., 1]
    t[..., 2, 2] = v[..., 2]
    t[..., 0, 1] = t[..., 1, 0] = v[..., 3] / SQRT2
    t[..., 0, 2] = t[..., 2, 0] = v[..., 4] / SQRT2
    t[..., 1, 2] = t[..., 2, 1] = v[..., 5] / SQRT2
    return t


def tensor_to_mandel(t: np.ndarray) -> np.ndarray:
    """Convert symmetric 3x3 tensors ``(..., 3, 3)`` to Mandel 6-vectors ``(..., 6)``."""
    t = np.asarray(t, dtype=float)
    v = np.empty(t.shape[:-2] + (6,))
    v[..., 0] = t[..., 0, 0]
    v[..., 1] = t[..., 1, 1]
    v[..., 2] = t[..., 2, 2]
    v[..., 3] = SQRT2 * 0.5 * (t[..., 0, 1] + t[..., 1, 0])
    v[..., 4] = SQRT2 * 0.5 * (t[..., 0, 2] + t[..., 2, 0])
    v[..., 5] = SQRT2 * 0.5 * (t[..., 1, 2] + t[..., 2, 1])
    return v


def as_points(a: np.ndarray, k: int, name: str) -> np.ndarray:
    """Return ``a`` as a float array of shape ``(n, k)``; a single ``(k,)`` vector gives n = 1."""
    a = np.asarray(a, dtype=float)
    if a.ndim == 1:
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != k:
        raise ConstitutiveError(f"{name} must have shape (n, {k}); got {a.shape}")
    return a


def broadcast_state(n: int, value: np.ndarray | None, k: int, name: str) -> np.ndarray:
    """Return an owned ``(n, k)`` array: zeros, or ``value`` (``(k,)`` or ``(n, k)``) copied."""
    if value is None:
        return np.zeros((n, k))
    v = np.asarray(value, dtype=float)
    if v.shape == (k,):
        return np.tile(v, (n, 1))
    if v.shape == (n, k):
        return v.copy()
    raise ConstitutiveError(f"{name} must have shape ({k},) or ({n}, {k}); got {v.shape}")
