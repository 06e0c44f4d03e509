"""Downdrag of a single pile in consolidating ground, through the whole run pipeline.

A scenario (one pile, d = 1 m, L = 12 m, no cap) is run by
:func:`~pilegroup.studies.run.job.run_scenario` exactly as ``pilegroup run`` runs it: head load
Q = 300 kN, then a site-wide surcharge that consolidates the soft clay, which settles past the
upper shaft. The soft clay's interface is built to be fully mobilised by a slip of about a
millimetre (Clough–Duncan spring with ``R_f = 0``, ``n = 0``, ``K = 1000``: 9.8 MPa/m) and to
creep fast above its strength (``eta`` = 1 kPa·day/m), so the shaft friction is the strength of
the default reading of Eq. 15 with phi = 0: ``tau_f = k = 2 c / sqrt(3)`` (docs/model.md,
Item 4). The soil is linear elastic, so the interface alone limits the friction.

* ``downdrag-end-bearing``: 10 m of soft clay on a stiff layer (E = 1 GPa) that holds the toe:
  the largest axial force is ``Q + pi d tau_f H_soft`` (negative friction over the whole soft
  layer; Fellenius 2004, "Unified design of piled foundations with emphasis on settlement
  analysis", ASCE GSP 125; NCHRP Report 1112, 2024), tolerance 5 %.
* ``downdrag-floating``: the pile floats in 24 m of the soft clay: the neutral plane against the
  unified method's force balance with the same mobilised friction and the model's toe force
  ``R_t``, ``Q + U f z_n = U f (L - z_n) + R_t``, i.e. ``z_n = (L - (Q - R_t) / (U f)) / 2``
  (tolerance 10 % of L); and, at the neutral plane, the pile's settlement against the
  settlement of the soil beside it over the last output interval (tolerance 5 %).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.studies.results.downdrag import end_bearing_force, force_balance
from pilegroup.studies.results.tables import (
    NEUTRAL_PLANE_CSV,
    SETTLEMENT_PROFILES_CSV,
    Table,
)
from pilegroup.studies.verification.common import run_pipeline, world
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["downdrag_end_bearing", "downdrag_floating", "downdrag_scenario"]

#: Head load (kN), surcharge (kPa), pile diameter and length (m), soft clay's cohesion (kPa).
Q_KN, Q_SURCHARGE, D, L, C_SOFT = 300.0, 100.0, 1.0, 12.0, 10.0
#: The shaft strength of the soft clay's interface (default Eq. 15, phi = 0): 2 c / sqrt 3.
TAU_F = 2.0 * C_SOFT / math.sqrt(3.0)
#: The mobilised shaft friction of the unified method (kPa): the strength at every depth.
SHAFT_FRICTION = (np.array([0.0, L]), np.array([TAU_F, TAU_F]))
_SOFT = {"name": "soft_clay", "gamma_kN_per_m3": 17.0, "E_MPa": 2.0, "nu": 0.3, "phi_deg": 0.0,
         "c_kPa": C_SOFT, "k_m_per_day": 1e-3, "e0": 1.2,
         "interface": {"delta_deg": 10.0, "K": 1000.0, "n": 0.0, "R_f": 0.0,
                       "eta_MPa_day": 0.001}}
_STIFF = {"name": "stiff", "gamma_kN_per_m3": 20.0, "E_MPa": 1000.0, "nu": 0.3, "phi_deg": 0.0,
          "c_kPa": 200.0, "k_m_per_day": 1e-3, "e0": 0.5,
          "interface": {"delta_deg": 10.0, "K": 1000.0, "n": 0.0, "R_f": 0.0,
                        "eta_MPa_day": 0.001}}


def downdrag_scenario(end_bearing: bool, size: str = "fast") -> dict[str, Any]:
    """The scenario of the case as a TOML document (dict)."""
    h = {"fast": 0.5, "bench": 0.25}[size]
    layers = [dict(_SOFT, thickness_m=10.0), dict(_STIFF)] if end_bearing else [dict(_SOFT)]
    days = [0.0, 0.1, 1.1, 30.0, 300.0, 1000.0, 2000.0, 3000.0]
    return {
        "scenario": {"name": "downdrag_" + ("end_bearing" if end_bearing else "floating")},
        "site": {"size_x_m": 16.0, "size_y_m": 16.0, "depth_m": 24.0,
                 "water_table_depth_m": 0.0},
        "piles": {"diameter_m": D, "length_in_soil_m": L, "grid": [1, 1]},
        "structure": {"E_MPa": 32300.0, "nu": 0.17, "density_kg_per_m3": 2500.0},
        "soil": {"model": "linear_elastic"},
        "interface": {"mode": "viscoplastic"},
        "stages": [{"name": "geostatic", "kind": "geostatic"},
                   {"name": "head_load", "kind": "load", "cap_load_kN": Q_KN,
                    "duration_day": 0.1},
                   {"name": "fill", "kind": "surcharge", "surcharge_kPa": Q_SURCHARGE,
                    "duration_day": 1.0},
                   {"name": "consolidation", "kind": "consolidation"}],
        "time": {"end_day": days[-1], "output_days": days},
        "numerics": {"element": "Q1Q1",
                     "mesh": {"size_m": h, "far_field_size_m": 4.0, "n_circ_min": 16,
                              "dz_surface_m": 2 * h, "dz_toe_m": h, "dz_max_m": 1.0,
                              "dz_max_deep_m": 3.0},
                     "time": {"dt_initial_day": 0.05, "dt_max_day": 200.0}},
        "outputs": {"xdmf": False, "plots": False},
        "layers": layers,
    }


def _last(table: Table, pile: int) -> dict[str, np.ndarray]:
    """The rows of ``pile`` at the last output time."""
    m = (table["t_day"] == table["t_day"].max()) & (table["pile"] == pile)
    return {k: v[m] for k, v in table.items()}


@register("downdrag-end-bearing")
def downdrag_end_bearing(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """Largest axial force of an end-bearing pile against ``Q + pi d tau_f H_soft`` (5 %)."""
    comm = comm or world()
    t0 = time.perf_counter()
    tables, n = run_pipeline(downdrag_scenario(True, size), comm,
                             (NEUTRAL_PLANE_CSV, SETTLEMENT_PROFILES_CSV))
    plane = _last(tables[NEUTRAL_PLANE_CSV], 1)
    n_max = float(plane["max_axial_force_kN"][0])
    ref = end_bearing_force(Q_KN, math.pi * D, SHAFT_FRICTION, 10.0)
    err = abs(n_max - ref) / ref
    tol = 0.05
    return CaseResult(
        "downdrag-end-bearing", err, tol, bool(err <= tol), time.perf_counter() - t0, n["dofs"],
        n["newton"], n["steps"],
        reference="Q + pi d tau_f H (negative friction fully mobilised over the soft layer; "
                  "Fellenius 2004, NCHRP Report 1112)",
        details={"max_axial_force_kN": n_max, "reference_kN": ref, "tau_f_kPa": TAU_F,
                 "neutral_plane_depth_m": float(plane["neutral_plane_depth_m"][0]),
                 "dragload_kN": float(plane["dragload_kN"][0]), "ranks": comm.size})


@register("downdrag-floating")
def downdrag_floating(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """Neutral plane of a floating pile against the unified method's force balance.

    Two errors, each with its tolerance: the neutral plane's depth against the force balance
    (10 % of L) and, at the neutral plane, the pile's settlement against the settlement of the
    soil beside it (5 %) over the last output interval (2000 to 3000 days). The neutral plane
    moves down while the clay consolidates (0.5, 4.1, 8.0, 9.6, 10.3, 10.4 m at 1, 30, 300,
    1000, 2000, 3000 days), so a depth it passes late has slipped before, while it was below
    the plane; the settlement equilibrium of the unified method holds for the settlement the
    ground causes while the plane is there. The case's error is the larger of the two as a
    fraction of its tolerance (tolerance 1).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    tables, n = run_pipeline(downdrag_scenario(False, size), comm,
                             (NEUTRAL_PLANE_CSV, SETTLEMENT_PROFILES_CSV))
    plane = _last(tables[NEUTRAL_PLANE_CSV], 1)
    prof = tables[SETTLEMENT_PROFILES_CSV]
    t_a, t_b = np.unique(prof["t_day"])[-2:]
    zn = float(plane["neutral_plane_depth_m"][0])

    def at(t: float, column: str) -> float:
        m = (prof["t_day"] == t) & (prof["pile"] == 1)
        o = np.argsort(prof["depth_m"][m])
        return float(np.interp(zn, prof["depth_m"][m][o], prof[column][m][o]))

    last = _last(prof, 1)
    toe = float(last["axial_force_kN"][np.argmax(last["depth_m"])])  # the toe's share
    zn_ref = force_balance(L, math.pi * D, SHAFT_FRICTION, Q_KN, toe).depth_m
    ds_pile = at(t_b, "pile_settlement_m") - at(t_a, "pile_settlement_m")
    ds_soil = at(t_b, "soil_settlement_m") - at(t_a, "soil_settlement_m")
    err_zn = abs(zn - zn_ref) / L
    err_s = abs(ds_pile - ds_soil) / abs(ds_soil)
    err = max(err_zn / 0.10, err_s / 0.05)
    return CaseResult(
        "downdrag-floating", err, 1.0, bool(err <= 1.0), time.perf_counter() - t0, n["dofs"],
        n["newton"], n["steps"],
        reference="unified method force balance Q + U f z_n = U f (L - z_n) + R_t and "
                  "settlement equilibrium at z_n (Fellenius 2004)",
        details={"neutral_plane_depth_m": zn, "reference_depth_m": zn_ref,
                 "error_of_L": err_zn, "toe_force_kN": toe,
                 "interval_day": [float(t_a), float(t_b)], "pile_settlement_increment_m":
                 ds_pile, "soil_settlement_increment_m": ds_soil, "settlement_error": err_s,
                 "dragload_kN": float(plane["dragload_kN"][0]), "ranks": comm.size})
