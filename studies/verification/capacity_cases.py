"""The capacity of a single pile, shaft plus toe, through the whole run pipeline.

``pile-capacity``: a scenario (one pile, d = 1 m, L = 5 m, no cap, in one clay layer) is run by
:func:`~pilegroup.studies.run.job.run_scenario` exactly as ``pilegroup run`` runs it: the
geostatic state, then a capacity stage that raises the head load until the pile fails
(docs/model.md, "Capacity"). Both resistances have a closed form:

* the **shaft**: the clay's interface with phi = 0 has the strength of the default reading of
  Eq. 15, ``tau_f = k = 2 c / sqrt(3)`` at any normal stress (docs/model.md, Item 4); its
  Clough–Duncan spring (``R_f = 0``, ``n = 0``, ``K = 1e4``: 98 MPa/m) mobilises it within
  0.3 mm of slip and it creeps fast above it (``eta`` = 1 kPa·day/m), so the shaft carries
  ``k A_s``;
* the **toe**: the base interface's bearing limit (``layers.interface.base_bearing_kPa``, the
  gross effective pressure ``q_b = N_c c_u + gamma' L``) with Skempton's (1951) ``N_c = 9`` for a
  deep circular base (the Q–z plateau of GROUP and API RP 2GEO, PLAXIS's base resistance of an
  embedded pile). Above the in-situ ``gamma' L A_b``, which balances the pile's buoyant weight
  (the pile's density is the clay's), the toe adds ``N_c c_u A_b``.

The soil is linear elastic and drained over the ramp (k = 1 m/day), so only the interface laws
limit the resistance, and the capacity is ``Q_ult = k A_s + N_c c_u A_b`` with the circle's
areas ``A_s = pi d L``, ``A_b = pi d^2 / 4`` (the meshed polygon has the circle's area, and the
interface scales its shaft's shear by the circle's perimeter over the polygon's). The case
compares the run's ultimate capacity on the head's curve (the applied head load against the head
settlement, as a load test reads it: the smaller of plunging and 10 % d settlement,
``summary.json``'s ``capacity.group`` of this one-pile foundation) with it; tolerance 5 %. The
load step of the ramp (``max_load_kN / 200``, 0.6 % of ``Q_ult``) bounds the resolution of both
criteria. The pile's own curve (``capacity.piles``) reads the head force from
the stress of the pile's top element layer and so misses the shaft friction above that layer's
mid-height (``tau_f`` times the perimeter times ``h``, 3.9 % of ``Q_ult`` at the fast size): it is
reported, not compared.

What this case does not verify: a toe whose resistance comes from the plastic soil below it.
That resistance converges slowly with the element size at the toe's edge and lies near or below
Skempton's 9 c_u at 0.1 d in small strain (docs/results.md, "Capacity").
"""

from __future__ import annotations

import math
import time
from typing import Any

from mpi4py import MPI

from pilegroup.model.units import GAMMA_WATER, G
from pilegroup.studies.results.tables import CAPACITY_CSV
from pilegroup.studies.verification.common import run_pipeline, world
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["capacity_reference", "pile_capacity", "pile_capacity_scenario"]

#: Pile diameter and length (m), clay unit weight (kN/m^3) and undrained strength (kPa).
D, L, GAMMA, C_U = 1.0, 5.0, 18.0, 20.0
#: Skempton's (1951) bearing factor of a deep circular base.
N_C = 9.0
#: The shaft strength of the clay's interface (default Eq. 15, phi = 0): 2 c / sqrt 3.
TAU_F = 2.0 * C_U / math.sqrt(3.0)
#: The ramp's share of the expected capacity, and its number of steps.
OVERLOAD, STEPS = 1.25, 200


def capacity_reference() -> dict[str, float]:
    """The closed-form capacity (kN) of the circular pile.

    The meshed pile, a polygon, has the circle's area, and the interface scales its shaft's
    shear by the circle's perimeter over the polygon's (``InterfaceCoupling.shaft_factor``).
    """
    perimeter, base = math.pi * D, math.pi * D * D / 4.0
    shaft = TAU_F * perimeter * L
    toe = N_C * C_U * base
    return {"shaft_kN": shaft, "toe_kN": toe, "ultimate_kN": shaft + toe,
            "shaft_area_m2": perimeter * L, "base_area_m2": base}


def pile_capacity_scenario(size: str = "fast") -> dict[str, Any]:
    """The scenario of the case as a TOML document (dict)."""
    h = {"fast": 0.25, "bench": 0.125}[size]
    max_load = OVERLOAD * capacity_reference()["ultimate_kN"]
    clay = {"name": "clay", "gamma_kN_per_m3": GAMMA, "E_MPa": 20.0, "nu": 0.3,
            "phi_deg": 0.0, "c_kPa": C_U, "k_m_per_day": 1.0, "e0": 0.8,
            "interface": {"delta_deg": 10.0, "K": 1.0e4, "n": 0.0, "R_f": 0.0,
                          "eta_MPa_day": 0.001,
                          "base_bearing_kPa": N_C * C_U + (GAMMA - GAMMA_WATER) * L}}
    return {
        "scenario": {"name": "pile_capacity"},
        "site": {"size_x_m": 10.0, "size_y_m": 10.0, "depth_m": 10.0,
                 "water_table_depth_m": 0.0},
        "piles": {"diameter_m": D, "length_in_soil_m": L, "grid": [1, 1]},
        "structure": {"E_MPa": 32300.0, "nu": 0.17,
                      "density_kg_per_m3": GAMMA / G * 1000.0},
        "soil": {"model": "linear_elastic"},
        "interface": {"mode": "viscoplastic"},
        "stages": [{"name": "geostatic", "kind": "geostatic"},
                   {"name": "capacity", "kind": "capacity", "max_load_kN": round(max_load),
                    "duration_day": 1.0}],
        "time": {"end_day": 1.0, "output_days": [0.0, 1.0]},
        "numerics": {"element": "Q1Q1",
                     "mesh": {"size_m": h, "far_field_size_m": 2.0, "n_circ_min": 16,
                              "dz_surface_m": 2 * h, "dz_toe_m": h, "dz_max_m": 1.0,
                              "dz_max_deep_m": 2.0},
                     "time": {"dt_initial_day": 1.0 / STEPS, "dt_max_day": 1.0 / STEPS}},
        "outputs": {"xdmf": False, "plots": False},
        "layers": [clay],
    }


@register("pile-capacity")
def pile_capacity(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """Ultimate capacity of a single pile against ``k A_s + N_c c_u A_b`` (5 %)."""
    comm = comm or world()
    t0 = time.perf_counter()
    _, n = run_pipeline(pile_capacity_scenario(size), comm, (CAPACITY_CSV,))
    ref = capacity_reference()
    cap = n["summary"]["capacity"]
    head, pile = cap["group"], cap["piles"][0]
    got = head["ultimate_kN"]
    err = math.inf if got is None else abs(got - ref["ultimate_kN"]) / ref["ultimate_kN"]
    tol = 0.05
    return CaseResult(
        "pile-capacity", err, tol, bool(err <= tol), time.perf_counter() - t0, n["dofs"],
        n["newton"], n["steps"],
        reference="k A_s + N_c c_u A_b: shaft strength 2 c / sqrt 3 (default Eq. 15, phi = 0), "
                  "toe N_c = 9 (Skempton 1951), the circle's areas",
        details={**ref, "ultimate_kN_run": got, "governing": head["governing"],
                 "plunging_kN": head["plunging"]["load_kN"],
                 "settlement_10pct_d_kN": head["settlement_10pct_d"]["load_kN"],
                 "pile_curve_ultimate_kN": pile["ultimate_kN"], "end": cap["end"],
                 "n_sides": int(n["mesh"]["circumferential_divisions"]), "ranks": comm.size})
