"""Physical ranges of the scenario's numbers: one table, each range with its source.

A value outside its range is not a foundation on earth (or would make the mesh or the solver
fail far from the input), so the scenario rejects it with a
:class:`~pilegroup.errors.ScenarioError` whose "allowed" text gives the range and its source.
The keys are the TOML paths without list indices (``layers.E_MPa`` covers every layer);
docs/model.md ("Physical ranges of the scenario") lists the same table, and
``tests/model/test_fuzz.py`` checks that every key here is in it.
"""

from __future__ import annotations

from dataclasses import dataclass

from pilegroup.validate import require_in_range


@dataclass(frozen=True)
class Bound:
    """The interval ``lo .. hi`` (closed unless ``lo_open`` / ``hi_open``) in ``unit``."""

    lo: float
    hi: float
    unit: str
    source: str
    lo_open: bool = False
    hi_open: bool = False


_PLAN = "a block a few pile lengths wide; 2 km bounds the zone of influence of any foundation"
_SOIL_E = "very soft clay and peat (~0.1 MPa) to intact rock (~100 GPa)"
_K = ("impervious clay to clean gravel, Terzaghi & Peck: 1e-6 to 1e3 m/day, with 6 decades "
      "below for practically undrained studies")
_DZ = "1 cm resolves any layer the model accepts; 100 m exceeds any layer or block depth"
_DT = "1e-9 day (0.1 ms) to time.end_day's limit"
_NU = "an isotropic elastic solid; 0.5 would be incompressible"
_GROWTH = "element sizes grow away from the piles, at most doubling from one to the next"
_PILE_D = Bound(0.1, 5.0, "m", "bored and driven piles: micropiles 0.1 m to large bored piles 5 m")
_PILE_L = Bound(1.0, 150.0, "m", "bored and driven piles in practice: up to ~150 m")

#: Every bounded scenario key -> its range.
BOUNDS: dict[str, Bound] = {
    "site.size_x_m": Bound(1.0, 2000.0, "m", _PLAN),
    "site.size_y_m": Bound(1.0, 2000.0, "m", _PLAN),
    "site.depth_m": Bound(1.0, 500.0, "m",
                          "the longest piles (~150 m) plus 2-3 pile lengths below the toes"),
    "layers.thickness_m": Bound(0.05, 500.0, "m",
                                "a thinner stratum is a lens, not a layer; at most site.depth_m"),
    "layers.gamma_kN_per_m3": Bound(10.0, 25.0, "kN/m^3",
                                    "saturated soils: peat ~10-12, dense gravel and rockfill ~23"),
    "layers.gamma_unsat_kN_per_m3": Bound(5.0, 25.0, "kN/m^3",
                                          "soils above the water table: dry peat ~5-10, dry"
                                          " or moist sand and clay ~14-20, dense gravel ~22"),
    "layers.K0": Bound(0.0, 3.0, "-", "normally consolidated sand ~0.4 to heavily"
                       " over-consolidated clay ~2-3, near its passive limit", lo_open=True),
    "layers.OCR": Bound(1.0, 100.0, "-", "normally consolidated (1) to heavily"
                        " over-consolidated clays (~30-50)"),
    "layers.piezometric_depth_m": Bound(-100.0, 500.0, "m", "artesian heads up to tens of"
                                        " metres above the ground; at most site.depth_m's"
                                        " limit below it"),
    "layers.POP_kPa": Bound(0.0, 1000.0, "kPa", "aged or eroded soft clays ~10-100 kPa; 1 MPa"
                            " bounds any pre-loading of a soil the model's laws are for"),
    "layers.lam": Bound(0.0, 2.0, "-", "lambda = Cc/ln 10: stiff clays ~0.05 to peats ~1.5"
                        " (Wood 1990)", lo_open=True),
    "layers.kappa": Bound(0.0, 1.0, "-", "kappa ~ lambda/10 to lambda/3 (Wood 1990)",
                          lo_open=True),
    "layers.M": Bound(0.0, 3.0, "-", "critical-state q/p' of soils ~0.6-1.8; 3 is"
                      " phi = 90 degrees in triaxial compression", lo_open=True, hi_open=True),
    "layers.phi_cs_deg": Bound(0.0, 60.0, "degree", "critical-state friction angles: clays"
                               " ~15-35, sands ~30-40 degrees", lo_open=True, hi_open=True),
    "layers.lambda_star": Bound(0.0, 1.0, "-", "lambda* = lambda/(1 + e): stiff clays ~0.02 to"
                                " peats ~0.3 (PLAXIS Material Models manual)", lo_open=True),
    "layers.kappa_star": Bound(0.0, 0.5, "-", "kappa* ~ lambda*/10 to lambda*/3 (PLAXIS"
                               " Material Models manual)", lo_open=True),
    "layers.mu_star": Bound(0.0, 0.1, "-", "mu* ~ lambda*/25 to lambda*/15: ~1e-3 to 2e-2 in"
                            " soft clays and peats (Vermeer & Neher 1999)", lo_open=True),
    "layers.nu_ur": Bound(0.0, 0.5, "-", _NU, lo_open=True, hi_open=True),
    "layers.tau_ref_day": Bound(1e-3, 1e3, "day", "the duration of the oedometer's load steps"
                                " lambda* and mu* come from: 1 day for the standard 24 h test"),
    "layers.E_MPa": Bound(0.1, 1.0e5, "MPa", _SOIL_E),
    "layers.c_kPa": Bound(0.0, 1000.0, "kPa", "clean sand (0) to hard clay and weak rock (~1 MPa)"),
    "layers.k_m_per_day": Bound(1.0e-12, 1.0e3, "m/day", _K),
    "layers.k_h_m_per_day": Bound(1.0e-12, 1.0e3, "m/day", _K),
    "layers.e0": Bound(0.1, 5.0, "-",
                       "dense sand and gravel (~0.3) to very soft clay and peat (~5)"),
    "layers.excess_pore_pressure_ratio": Bound(0.0, 1.0, "-",
                                               "1 would leave the soil without effective stress",
                                               hi_open=True),
    "layers.excess_pore_pressure_kPa": Bound(0.0, 1000.0, "kPa",
                                             "fills up to ~50 m high leave at most ~1000 kPa"),
    "piles.installation.radius_ratio": Bound(1.0, 100.0, "-",
                                             "cavity expansion: R/r0 = sqrt(G/c_u), ~5-20 in"
                                             " soft clay", lo_open=True),
    "piles.installation.excess_pore_pressure_ratio": Bound(0.0, 1.0, "-",
                                                           "1 would leave the soil without"
                                                           " effective stress", hi_open=True),
    "layers.interface.K": Bound(1.0, 1.0e5, "-",
                                "Clough-Duncan modulus numbers of soils ~50-5000 (paper: 296-820)"),
    "layers.interface.n": Bound(0.0, 2.0, "-", "Clough-Duncan exponents ~0.2-1 (paper: 0.28-0.52)"),
    "layers.interface.eta_MPa_day": Bound(1.0e-3, 1.0e6, "MPa·day/m",
                                          "paper Table 1: 6-53; four decades either side"),
    "layers.interface.base_bearing_kPa": Bound(1.0, 1.0e5, "kPa",
                                               "9 c_u of very soft clay (~50 kPa) to the end"
                                               " bearing of piles on rock (~20 MPa)"),
    "piles.diameter_m": _PILE_D,
    "piles.length_in_soil_m": _PILE_L,
    "piles.layout.diameter_m": _PILE_D,
    "piles.layout.length_in_soil_m": _PILE_L,
    "cap.size_x_m": Bound(0.1, 2000.0, "m", "at least a pile diameter; at most the block"),
    "cap.size_y_m": Bound(0.1, 2000.0, "m", "at least a pile diameter; at most the block"),
    "cap.thickness_m": Bound(0.2, 20.0, "m",
                             "pile caps and rafts: 0.2 m slabs to 20 m caisson-like caps"),
    "structure.E_MPa": Bound(1.0e3, 3.0e5, "MPa",
                             "timber (~10 GPa), concrete (25-45 GPa), steel (210 GPa)"),
    "structure.density_kg_per_m3": Bound(300.0, 10000.0, "kg/m^3",
                                         "timber (~400) to steel (7850)"),
    "interface.N": Bound(0.0, 20.0, "-", "Perzyna exponents of soils ~1-10 (paper: 1)",
                         lo_open=True),
    "interface.normal_stiffness_factor": Bound(1.0, 1.0e6, "-",
                                               "a penalty softer than the soil opens gaps; "
                                               "above 1e6 the system loses ~6 digits"),
    "stages.cap_load_kN": Bound(0.0, 1.0e9, "kN",
                                "the largest foundations carry ~1e6 kN; 1e9 is a typo guard",
                                hi_open=True),
    "stages.force_kN": Bound(-1.0e9, 1.0e9, "kN", "horizontal and vertical cap forces; the"
                             " largest foundations carry ~1e6 kN; 1e9 is a typo guard",
                             lo_open=True, hi_open=True),
    "stages.moment_kNm": Bound(-1.0e10, 1.0e10, "kN m", "cap moments: ~1e6 kN x ~10 m levers;"
                               " 1e10 is a typo guard", lo_open=True, hi_open=True),
    "stages.surcharge_kPa": Bound(-1000.0, 1000.0, "kPa",
                                  "fills and embankments up to ~50 m high (~1000 kPa); negative:"
                                  " a fill removed"),
    "stages.drawdown_m": Bound(-100.0, 100.0, "m",
                               "pumping lowers the water table by metres to tens of metres;"
                               " negative: it rises"),
    "stages.duration_day": Bound(1.0e-9, 1.0e5, "day", _DT),
    "stages.until_day": Bound(-1.0e5, 1.0e5, "day", "a day of the analysis, like time.end_day;"
                              " before the piles (time.start_day < 0) it may be negative"),
    "time.end_day": Bound(1.0e-9, 1.0e5, "day",
                          "design lives are <= ~120 years; 1e5 days is 274 years"),
    "time.start_day": Bound(-1.0e5, 0.0, "day",
                            "fills and drawdown before the piles: up to ~274 years earlier"),
    "numerics.time.dt_initial_day": Bound(1.0e-9, 1.0e5, "day", _DT),
    "numerics.time.dt_min_day": Bound(1.0e-9, 1.0e5, "day", _DT),
    "numerics.time.dt_max_day": Bound(1.0e-9, 1.0e5, "day", _DT),
    "numerics.time.grow_factor": Bound(1.0, 10.0, "-",
                                       "faster growth skips the consolidation it should follow"),
    "numerics.time.max_newton": Bound(1, 1000, "-", "Newton converges in ~5-20 iterations or not"),
    "numerics.newton_rtol": Bound(1.0e-14, 0.1, "-",
                                  "above machine precision; below 10 % of the first residual"),
    "numerics.solver.krylov_forcing": Bound(
        0.0, 0.5, "-", "the linear residual a fraction of what Newton accepts; 0: the preset's"),
    "numerics.newton_atol": Bound(0.0, 1.0e3, "-", "residual units kN and m^3", lo_open=True),
    "numerics.mesh.size_m": Bound(0.01, 10.0, "m",
                                  "the paper's mesh study uses 0.1-1 m; also <= 5 x pile diameter"),
    "numerics.mesh.far_field_size_m": Bound(0.01, 200.0, "m",
                                            "at least 10 elements across the largest block"),
    "numerics.mesh.dz_surface_m": Bound(0.01, 100.0, "m", _DZ),
    "numerics.mesh.dz_toe_m": Bound(0.01, 100.0, "m", _DZ),
    "numerics.mesh.dz_max_m": Bound(0.01, 100.0, "m", _DZ),
    "numerics.mesh.dz_max_deep_m": Bound(0.01, 100.0, "m", _DZ),
    "numerics.mesh.dz_cap_m": Bound(0.01, 100.0, "m", _DZ),
    "numerics.mesh.n_circ_min": Bound(8, 256, "-",
                                      "8 edges: 10 % area error; 256: 0.01 %, finer is waste"),
    "numerics.mesh.min_layer_divisions": Bound(1, 100, "-",
                                               "more elements per layer come from dz_* instead"),
    # intervals the physics or the method gives
    "layers.nu": Bound(0.0, 0.5, "-", _NU, lo_open=True, hi_open=True),
    "structure.nu": Bound(0.0, 0.5, "-", _NU, lo_open=True, hi_open=True),
    "layers.phi_deg": Bound(0.0, 60.0, "degree", "undrained clay (0) to dense gravel and"
                            " rockfill (~50)", hi_open=True),
    "layers.interface.delta_deg": Bound(0.0, 60.0, "degree", "an interface without friction"
                                        " carries no shear; at most a soil's friction angle",
                                        lo_open=True, hi_open=True),
    "layers.interface.R_f": Bound(0.0, 1.0, "-", "Clough-Duncan failure ratios ~0.5-0.9"
                                  " (paper: 0.08-0.28); 0: linear shear springs", hi_open=True),
    "numerics.mesh.growth": Bound(1.0, 2.0, "-", _GROWTH, lo_open=True),
    "numerics.mesh.dz_growth": Bound(1.0, 2.0, "-", _GROWTH, lo_open=True),
    "numerics.mesh.scale": Bound(0.2, 5.0, "-", "a refinement study: five times finer to five"
                                 " times coarser than the automatic mesh"),
    "numerics.time.cut_factor": Bound(0.0, 1.0, "-", "a failed step is tried again smaller",
                                      lo_open=True, hi_open=True),
    "stages.plunging_stiffness_ratio": Bound(0.0, 1.0, "-", "a fraction of the initial"
                                             " stiffness", lo_open=True, hi_open=True),
}


def check_bound(path: str, value: object, key: str | None = None) -> None:
    """Raise :class:`~pilegroup.errors.ScenarioError` unless ``value`` is in ``BOUNDS[path]``.

    The error names ``key`` (default: the last part of ``path``, which the loader prefixes
    with the table's dotted path).
    """
    b = BOUNDS[path]
    require_in_range(key or path.rsplit(".", 1)[-1], value, b.lo, b.hi, b.unit,
                     lo_open=b.lo_open, hi_open=b.hi_open, why=b.source)


__all__ = ["BOUNDS", "Bound", "check_bound"]
