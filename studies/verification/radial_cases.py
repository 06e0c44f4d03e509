"""Radial consolidation around a driven pile, through the whole run pipeline.

``radial-consolidation``: a single pile (d = 0.8 m, L = 12 m, tied to the soil) in linear
elastic clay starts with the installation excess pore pressure of ``piles.installation``
(cylindrical cavity expansion, ``u = u_s ln(R/r) / ln(R/r0)`` for ``r0 <= r <= R = 5 r0``,
``u_s = 0.3 sigma'_v``; docs/model.md, "Installation pore pressures"), run by
:func:`~pilegroup.studies.run.job.run_scenario` as ``pilegroup run`` runs it. The water flows
horizontally (``k_h = 1000 k_v``), so at mid-shaft the pressure dissipates as in Randolph &
Wroth's (1979) plane-strain solution: ``du/dt = c_h (1/r) d/dr (r du/dr)``, impermeable shaft,
``c_h = k_h (lambda + 2G) / gamma_w``, here with an impermeable outer radius of the block's
area (``r* = 16 m / sqrt(pi)``, the block's sides have no flow). Compared: the excess pore
pressure at the shaft (``settlement_profiles.csv``, the element layer nearest 6 m depth)
against the series of :func:`~pilegroup.studies.results.downdrag.radial_series` at the
output times ``T = c_h t / r0^2 = 0.01 ... 10``; error: the largest difference over
``u_s``; tolerance 5 % (Randolph, M. F. and Wroth, C. P. 1979, "An analytical solution for the
consolidation around a driven pile", Int. J. Numer. Anal. Methods Geomech. 3(3):217-229).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.model.units import GAMMA_WATER
from pilegroup.studies.results.downdrag import (
    radial_consolidation_coefficient,
    radial_excess_pressure,
    radial_series,
    time_factor,
)
from pilegroup.studies.results.tables import SETTLEMENT_PROFILES_CSV
from pilegroup.studies.verification.common import run_pipeline, world
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["radial_consolidation", "radial_scenario"]

#: Pile radius (m), disturbed zone R / r0, shaft ratio u_s / sigma'_v, depth compared (m).
R0, RADIUS_RATIO, RATIO, DEPTH = 0.4, 5.0, 0.3, 6.0
#: Clay: E (kPa), nu, unit weight (kN/m^3), horizontal and vertical conductivity (m/day).
E_KPA, NU, GAMMA, K_H, K_V = 5000.0, 0.3, 18.0, 1e-3, 1e-6
#: Block plan size (m): its area's radius is the outer radius of the reference.
SIZE = 16.0
#: Time factors of the output times.
T_OUT = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0)


def c_h() -> float:
    """The radial consolidation coefficient of the clay (m^2/day)."""
    return radial_consolidation_coefficient(K_H, E_KPA, NU)


def radial_scenario(size: str = "fast") -> dict[str, Any]:
    """The scenario of the case as a TOML document (dict)."""
    h = {"fast": 0.1, "bench": 0.05}[size]
    days = [0.0] + [T * R0**2 / c_h() for T in T_OUT]
    return {
        "scenario": {"name": "radial_consolidation"},
        "site": {"size_x_m": SIZE, "size_y_m": SIZE, "depth_m": 20.0,
                 "water_table_depth_m": 0.0},
        "piles": {"diameter_m": 2 * R0, "length_in_soil_m": 12.0, "grid": [1, 1],
                  "installation": {"excess_pore_pressure_ratio": RATIO,
                                   "radius_ratio": RADIUS_RATIO}},
        "structure": {"E_MPa": 32300.0, "nu": 0.17, "density_kg_per_m3": 2500.0},
        "soil": {"model": "linear_elastic"},
        "interface": {"mode": "tied"},
        "stages": [{"name": "geostatic", "kind": "geostatic"},
                   {"name": "dissipation", "kind": "consolidation"}],
        "time": {"end_day": days[-1], "output_days": days},
        "numerics": {"element": "Q1Q1",
                     "mesh": {"size_m": h, "far_field_size_m": 3.0, "n_circ_min": 16,
                              "dz_surface_m": 1.0, "dz_toe_m": 1.0, "dz_max_m": 2.0,
                              "dz_max_deep_m": 4.0},
                     "time": {"dt_initial_day": 0.05 * days[1], "dt_max_day": 0.5}},
        "outputs": {"xdmf": False, "plots": False},
        "layers": [{"name": "clay", "gamma_kN_per_m3": GAMMA, "E_MPa": E_KPA / 1000.0,
                    "nu": NU, "phi_deg": 0.0, "c_kPa": 20.0, "k_m_per_day": K_V,
                    "k_h_m_per_day": K_H, "e0": 1.0}],
    }


@register("radial-consolidation")
def radial_consolidation(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """Excess pore pressure at the shaft against Randolph & Wroth (1979) (5 % of ``u_s``)."""
    comm = comm or world()
    t0 = time.perf_counter()
    tables, n = run_pipeline(radial_scenario(size), comm, (SETTLEMENT_PROFILES_CSV,))
    prof = tables[SETTLEMENT_PROFILES_CSV]
    pile = prof["pile"] == 1
    depths = np.unique(prof["depth_m"][pile])
    depth = float(depths[np.argmin(np.abs(depths - DEPTH))])
    m = pile & (prof["depth_m"] == depth)
    t, u = prof["t_day"][m], prof["excess_pore_pressure_kPa"][m]
    u_s = RATIO * (GAMMA - GAMMA_WATER) * depth  # the closed form's shaft value, kPa
    series = radial_series(R0, SIZE / math.sqrt(math.pi), 1.0, RADIUS_RATIO * R0,
                           drained=False, n_terms=400)
    later = t > 0.0
    T = time_factor(c_h(), t[later], R0)
    ref = u_s * radial_excess_pressure(series, np.full(T.size, R0), T)
    err = float(np.max(np.abs(u[later] - ref)) / u_s)
    tol = 0.05
    return CaseResult(
        "radial-consolidation", err, tol, bool(err <= tol), time.perf_counter() - t0,
        n["dofs"], n["newton"], n["steps"],
        reference="Randolph & Wroth (1979): radial consolidation around a driven pile, "
                  "impermeable shaft, c_h = k_h (lambda + 2G) / gamma_w",
        details={"depth_m": depth, "u_s_kPa": u_s, "u_start_kPa": float(u[~later][0]),
                 "T": T.tolist(), "u_over_us": (u[later] / u_s).tolist(),
                 "reference_over_us": (ref / u_s).tolist(), "c_h_m2_per_day": c_h(),
                 "ranks": comm.size})
