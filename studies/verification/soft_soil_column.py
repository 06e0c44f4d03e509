"""A fine one-dimensional reference of consolidation with Soft Soil Creep (``ssc-oedometer``).

A column of height ``H`` under its own weight, drained at the top, impermeable at the bottom,
with no lateral strain, loaded at once by ``q`` on the top and left to consolidate. The
reference is written here, independently of the finite-element solver: the method of lines
with finite volumes in depth and backward Euler in time, the same pointwise law
(:class:`~pilegroup.constitutive.soft_soil_creep.SoftSoilCreep`) at the centre of each cell.

Unknowns per cell ``i`` (depth ``d_i`` of its centre, size ``h``): the excess pore pressure
``p_i`` (kPa) and the vertical strain increment of the step ``de_i`` (tension positive; the
lateral strains are zero). Per step of size ``dt``:

* equilibrium: the total vertical stress is the weight above plus the load,
  ``sigma'_zz(de_i) - p_i = -(gamma' d_i + q)`` (``gamma' = gamma_sat - gamma_w``, the
  hydrostatic pore pressure balanced by the buoyancy);
* mass balance (Biot with a compressible fluid, the solver's storage ``S = n/K_w``),
  ``S (p_i - p_i^n) + de_i - dt (k/gamma_w) (d^2 p/dz^2)_i = 0``, the second derivative the
  three-point difference, ``p = 0`` at the top face (half a cell from the first centre),
  no flux through the bottom;
* Newton on both together: with ``D_i = d sigma'_zz/d eps_zz`` (the law's consistent tangent)
  the strain is eliminated cell by cell and the pressure correction solves a tridiagonal
  system.

A zero step (``dt = 0``) is the undrained load step (no flow, the law without time). The
settlement of the top is ``-sum_i eps_i h``. Errors: second order in ``h`` and first order in
the step (backward Euler); the steps grow geometrically from ``dt0`` by ``growth`` and land
on every requested time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

from pilegroup.constitutive.critical_state import k0_stress
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.errors import ConstitutiveError
from pilegroup.model.units import GAMMA_WATER, K_WATER

__all__ = ["ColumnCells", "CreepColumn", "column_settlement"]

#: Newton's tolerance: equilibrium against the largest vertical stress, the mass balance
#: against the step's largest strain.
RTOL = 1e-10


@dataclass(frozen=True)
class CreepColumn:
    """The loaded column: geometry (m), load (kPa), soil (kN/m^3, m/day) and its law."""

    law: SoftSoilCreep
    H: float = 4.0
    q: float = 50.0
    gamma_sat: float = 17.0
    k_m_per_day: float = 1e-3
    porosity: float = 0.5

    @property
    def gamma_b(self) -> float:
        """Buoyant unit weight, kN/m^3."""
        return self.gamma_sat - GAMMA_WATER

    @property
    def storage(self) -> float:
        """Storage ``n/K_w`` of the pore water, 1/kPa (the solver's ``SoilMaterial.storage``)."""
        return self.porosity / K_WATER


class ColumnCells:
    """The column's cells and their state during a run (:func:`column_settlement`)."""

    def __init__(self, col: CreepColumn, cells: int) -> None:
        self.col, self.n = col, cells
        self.h = col.H / cells
        self.depth = (np.arange(cells) + 0.5) * self.h
        self.state = col.law.initial_state(cells, k0_stress(col.gamma_b * self.depth,
                                                             col.law.k0nc))
        self.p = np.zeros(cells)
        self.eps = np.zeros(cells)
        self.de_last = np.zeros(cells)
        self.iterations = 0
        # the difference operator's diagonal (top: the drained face half a cell up) and bands
        self.diag = np.full(cells, 2.0)
        self.diag[0], self.diag[-1] = 3.0, 1.0

    def laplacian(self, p: np.ndarray) -> np.ndarray:
        """``h^2 d^2 p/dz^2`` of the cells' pressures (top face p = 0, bottom no flux)."""
        out = -self.diag * p
        out[:-1] += p[1:]
        out[1:] += p[:-1]
        return out

    def step(self, dt: float, q: float) -> None:
        """One backward-Euler step of size ``dt`` (day; 0: undrained) under the load ``q``."""
        col, law, n = self.col, self.col.law, self.n
        c = dt * col.k_m_per_day / GAMMA_WATER / self.h**2
        load = col.gamma_b * self.depth + q
        de, p = self.de_last * (dt > 0.0), self.p.copy()  # the last step's strain: a guess
        d6 = np.zeros((n, 6))
        band = np.zeros((3, n))
        band[0, 1:] = band[2, :-1] = -c
        for it in range(60):
            d6[:, 2] = de
            stress, trial, D = law.update(d6, self.state, dt)
            r1 = stress[:, 2] - p + load
            r2 = col.storage * (p - self.p) + de - c * self.laplacian(p)
            if it and np.abs(r1).max() <= RTOL * load.max() \
                    and np.abs(r2).max() <= RTOL * max(np.abs(de).max(), 1e-12):
                break
            Dzz = D[:, 2, 2]
            band[1] = col.storage + 1.0 / Dzz + c * self.diag
            dp = solve_banded((1, 1), band, -r2 + r1 / Dzz)
            p, de = p + dp, de + (dp - r1) / Dzz
        else:
            raise ConstitutiveError(f"1D Soft Soil Creep column: Newton did not converge in a"
                                    f" step of {dt:g} day")
        self.iterations += it
        self.state, self.p, self.eps, self.de_last = trial, p, self.eps + de, de

    @property
    def settlement(self) -> float:
        """Settlement of the top, m (downward positive)."""
        return -float(self.eps.sum()) * self.h


def column_settlement(col: CreepColumn, times: np.ndarray, cells: int = 200,
                      dt0: float = 1e-6, growth: float = 1.02) -> tuple[np.ndarray, int]:
    """Settlement (m) of the column at ``times`` (day, increasing, > 0) after the load at 0.

    The undrained load step at ``t = 0``, then steps from ``dt0`` growing by ``growth`` that
    land on every time of ``times``. Returns the settlements and the number of steps.
    """
    times = np.asarray(times, dtype=float)
    run = ColumnCells(col, cells)
    run.step(0.0, col.q)
    out, t, dt, steps = [], 0.0, dt0, 1
    for target in times:
        while t < target * (1.0 - 1e-12):
            h = min(dt, target - t)
            if target - t - h < 1e-3 * h:  # land on the time
                h = target - t
            run.step(h, col.q)
            t, steps = t + h, steps + 1
            if h >= dt:  # a whole step: the next one grows (a landing step keeps the size)
                dt *= growth
        out.append(run.settlement)
    return np.array(out), steps
