"""Cap actions through the whole run pipeline: lateral pile response, equilibrium, rigid cap.

Every case runs a scenario with :func:`~pilegroup.studies.run.job.run_scenario`, exactly as
``pilegroup run`` does, and reads the run's CSV files (``cap_motion.csv``, ``pile_heads.csv``).
Soil linear elastic and drained (permeable, loaded over a day), piles and cap concrete.

* ``lateral-single-pile``: a flexible pile (d = 0.6 m, L = 15 m, E_p/G* = 6.4e3, critical
  length l_c = 7.3 m < L) in homogeneous soil, tied to it, under a head load H and a moment M
  at the ground surface: the head's deflection and rotation against Randolph (1981, "The
  response of flexible piles to lateral loading", Geotechnique 31(2), 247-259; his Eqs. for
  homogeneous soil, rho_c = 1):
  ``u = (E_p/G*)^(1/7) / G* [0.27 H (l_c/2)^-1 + 0.30 M (l_c/2)^-2]``,
  ``theta = (E_p/G*)^(1/7) / G* [0.30 H (l_c/2)^-2 + 0.80 M (l_c/2)^-3]``, with
  ``G* = G (1 + 3 nu / 4)`` and ``l_c = d (E_p/G*)^(2/7)``; the H–theta and M–u terms share
  their coefficient (Betti's reciprocity). The scenario has no ``[numerics]``: the default
  discretisation (Q2Q1 for horizontal actions, the automatic mesh). Tolerance 5 %: Randolph
  fitted his own finite element runs to about 10 %. The block stands for his half-space: 160 m
  x 160 m, 60 m deep (rollers on the sides, fixed bottom); one of 40 m x 40 m x 30 m is 1.9 %
  stiffer in deflection. With the cells halved at the pile (h = d / 2) Q2Q1 gives 2.4 % less
  deflection and 2.8 % more rotation than his expressions, on the default mesh 4.3 % and 0.7 %
  (docs/model.md, "Cap actions"). The
  details give the pile's head section (``pile_bending.csv`` at depth 0: H and M, statics) and
  its largest moment with its depth.
* ``cap-equilibrium``: a 3 x 3 group under a cap, the piles joined to the soil by the elastic
  interface, under all six actions at once about a point off the cap centre: the pile heads'
  forces and moments, moved to that point, balance the applied actions, every component, to
  1e-6 relative (the cap is free of the soil, so the heads carry everything; the tolerance is
  the Newton residual's order). This checks the head forces' extraction, the action point's
  transfer and the face tractions together.
* ``rigid-cap-moment``: equal end-bearing piles (3 x 3, 5 diameters apart, through 8 m of
  clay into stiffer ground) under a thick cap, loaded vertically and then by a moment My: the
  axial forces the moment adds are linear in the distance from the axis, ``N_i = a x_i``
  (the rigid-cap rule,
  e.g. Fleming et al. 2009, "Piling Engineering", 3rd ed., section 4.6), within 5 % of the
  largest; the share of the moment the axial forces carry (the rest: the piles' own head
  moments) is reported.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.model import scenario_from_dict
from pilegroup.studies.results.tables import BENDING_CSV, CAP_MOTION_CSV, HEADS_CSV, Table
from pilegroup.studies.verification.common import run_pipeline, world
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["cap_equilibrium", "lateral_scenario", "lateral_single_pile", "randolph_head",
           "rigid_cap_moment"]

#: Soil (kPa, -) and pile (kPa) moduli of the cases.
E_SOIL, NU_SOIL, E_PILE = 10.0e3, 0.3, 30.0e6
#: lateral-single-pile: diameter, length (m), head load (kN), moment (kN m).
D_LAT, L_LAT, H_LAT, M_LAT = 0.6, 15.0, 50.0, 20.0
#: The group cases' six actions (kN, kN m) and the point they act about (m).
GROUP_ACTIONS = {"cap_load_kN": 3000.0, "Fx_kN": 200.0, "Fy_kN": -150.0, "Mx_kNm": 300.0,
                 "My_kNm": -250.0, "Mz_kNm": 100.0}
GROUP_POINT = (0.5, -0.3, 3.0)
MOMENT_KNM = 1000.0
#: rigid-cap-moment: the vertical load before the moment (kN), which keeps every pile base in
#: compression; the axial forces due to the moment are the change from day 1 to day 2.
VERTICAL_KN = 3000.0
#: Pile spacing (m) of the group cases: 5 diameters under the rigid cap, where the piles'
#: interaction through the soil (which makes corner piles stiffer than edge piles) is small.
SPACING = {"equilibrium": 2.0, "moment": 3.0}
#: rigid-cap-moment: the piles end in rock (kPa) below 8 m of clay, so that each pile's
#: axial stiffness is its own (shortening and socket), as the rigid-cap rule assumes.
ROCK_E = 2.0e6


def randolph_head(H: float, M: float, d: float, E_p: float, G: float, nu: float
                  ) -> tuple[float, float, float]:
    """(u m, theta rad, l_c m) of a flexible pile head at the ground (Randolph 1981, above)."""
    g = G * (1.0 + 0.75 * nu)
    ratio = E_p / g
    lc = d * ratio ** (2.0 / 7.0)
    a = ratio ** (1.0 / 7.0) / g
    h = lc / 2.0
    return (a * (0.27 * H / h + 0.30 * M / h ** 2), a * (0.30 * H / h ** 2 + 0.80 * M / h ** 3),
            lc)


def _soil(name: str, E_kPa: float = E_SOIL, thickness: float | None = None,
          linear: bool = False) -> dict[str, Any]:
    """A soil layer and its interface (Clough–Duncan springs, far from their strength).

    ``linear``: ``n = 0``, ``R_f = 0``, a constant spring stiffness, so that the response is
    linear in the actions (the rigid-cap case compares forces before and after the moment);
    otherwise the hyperbolic spring of a soft clay (``n = 0.5``, ``R_f = 0.9``).
    """
    n, rf = (0.0, 0.0) if linear else (0.5, 0.9)
    lay = {"name": name, "gamma_kN_per_m3": 18.0, "E_MPa": E_kPa / 1e3, "nu": NU_SOIL,
           "phi_deg": 20.0, "c_kPa": 20.0, "k_m_per_day": 10.0, "e0": 0.8,
           "interface": {"delta_deg": 20.0, "K": 300.0, "n": n, "R_f": rf,
                         "eta_MPa_day": 10.0}}
    return lay | ({"thickness_m": thickness} if thickness is not None else {})


def lateral_scenario(case: str, size: str = "fast") -> dict[str, Any]:
    """The scenario of a case (``single``, ``equilibrium``, ``moment``) as a TOML dict."""
    h = {"fast": 1.0, "bench": 0.5}[size]
    common = {
        "structure": {"E_MPa": E_PILE / 1e3, "nu": 0.2, "density_kg_per_m3": 2500.0},
        "soil": {"model": "linear_elastic"},
        "time": {"end_day": 2.0, "output_days": [0.0, 1.0, 2.0]},
        "outputs": {"xdmf": False, "plots": False},
    }
    if case == "single":  # the default discretisation; bench: half its sizes at the pile
        fine = {"size_m": D_LAT / 2, "dz_surface_m": D_LAT / 2, "dz_toe_m": D_LAT / 2}
        return common | {
            "scenario": {"name": "lateral_single_pile"},
            "site": {"size_x_m": 160.0, "size_y_m": 160.0, "depth_m": 60.0},
            "piles": {"diameter_m": D_LAT, "length_in_soil_m": L_LAT, "grid": [1, 1]},
            "interface": {"mode": "tied"},
            "stages": [{"name": "geostatic", "kind": "geostatic"},
                       {"name": "head", "kind": "load", "cap_load_kN": 0.0, "Fx_kN": H_LAT,
                        "My_kNm": M_LAT, "duration_day": 1.0},
                       {"name": "drained", "kind": "consolidation"}],
            "layers": [_soil("clay")],
        } | ({"numerics": {"mesh": fine}} if size == "bench" else {})
    if case == "equilibrium":
        loads = [{"name": "actions", "kind": "load", "duration_day": 1.0} | GROUP_ACTIONS]
    else:  # the bases stay in compression under the vertical load; the moment comes after
        loads = [{"name": "vertical", "kind": "load", "duration_day": 1.0,
                  "cap_load_kN": VERTICAL_KN},
                 {"name": "moment", "kind": "load", "duration_day": 1.0,
                  "cap_load_kN": VERTICAL_KN, "My_kNm": MOMENT_KNM}]
    s = SPACING[case]
    return common | {
        "scenario": {"name": f"lateral_{case}"},
        "site": {"size_x_m": 8 * s + 8.0, "size_y_m": 8 * s + 8.0, "depth_m": 16.0},
        "piles": {"diameter_m": 0.6, "length_in_soil_m": 10.0, "grid": [3, 3],
                  "spacing_m": [s, s], "embedment_m": 0.5},
        "cap": {"size_x_m": 2 * s + 2.0, "size_y_m": 2 * s + 2.0,
                "thickness_m": 1.5 if case == "equilibrium" else 3.0},
        "interface": {"mode": "elastic"},
        "actions": {"point_m": list(GROUP_POINT)} if case == "equilibrium" else {},
        "stages": [{"name": "geostatic", "kind": "geostatic"}, *loads],
        "numerics": {"element": "Q1Q1",
                     "mesh": {"size_m": h, "far_field_size_m": 4.0, "n_circ_min": 8,
                              "dz_surface_m": 1.0, "dz_toe_m": 1.0, "dz_max_m": 2.0,
                              "dz_max_deep_m": 4.0}},
        "layers": [_soil("clay")] if case == "equilibrium" else
                  [_soil("clay", thickness=8.0, linear=True),
                   _soil("rock", E_kPa=ROCK_E, linear=True)],
    }


def _last(table: Table) -> dict[str, np.ndarray]:
    m = table["t_day"] == table["t_day"].max()
    return {k: v[m] for k, v in table.items()}


@register("lateral-single-pile", options=("pair",))
def lateral_single_pile(size: str = "fast", comm: MPI.Comm | None = None,
                        pair: str | None = None) -> CaseResult:
    """Head deflection and rotation of a flexible pile against Randolph (1981), 5 %.

    ``pair``: the element pair instead of the default discretisation's (a benchmark's option).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    doc = lateral_scenario("single", size)
    if pair is not None:
        doc.setdefault("numerics", {})["element"] = pair
    tables, n = run_pipeline(doc, comm, (CAP_MOTION_CSV, BENDING_CSV))
    motion = _last(tables[CAP_MOTION_CSV])
    u, theta = float(motion["ux_m"][0]), float(motion["ry_rad"][0])
    prof = _last(tables[BENDING_CSV])
    top = int(np.argmax(np.abs(prof["My_kNm"])))
    G = E_SOIL / (2.0 * (1.0 + NU_SOIL))
    u_ref, t_ref, lc = randolph_head(H_LAT, M_LAT, D_LAT, E_PILE, G, NU_SOIL)
    err_u, err_t = abs(u - u_ref) / u_ref, abs(theta - t_ref) / t_ref
    tol = 0.05
    return CaseResult(
        "lateral-single-pile", max(err_u, err_t), tol, bool(max(err_u, err_t) <= tol),
        time.perf_counter() - t0, n["dofs"], n["newton"], n["steps"],
        reference="Randolph (1981), flexible pile in homogeneous elastic soil: head deflection "
                  "and rotation under H and M at the ground surface",
        details={"u_m": u, "u_ref_m": u_ref, "theta_rad": theta, "theta_ref_rad": t_ref,
                 "u_error": err_u, "theta_error": err_t, "critical_length_m": lc,
                 "head_section": {"depth_m": float(prof["depth_m"][0]),
                                  "Vx_kN": float(prof["Vx_kN"][0]),
                                  "My_kNm": float(prof["My_kNm"][0])},
                 "largest_moment": {"My_kNm": float(prof["My_kNm"][top]),
                                    "depth_m": float(prof["depth_m"][top])},
                 "stiffer_by": {"u": 1.0 - u / u_ref, "theta": 1.0 - theta / t_ref},
                 "element": scenario_from_dict(doc).numerics.element, "ranks": comm.size})


def head_resultant(heads: dict[str, np.ndarray], point: tuple[float, float, float]
                   ) -> np.ndarray:
    """The pile heads' actions summed and moved to ``point``: ``[F, M_point]`` (kN, kN m)."""
    F = np.column_stack([heads["Vx_kN"], heads["Vy_kN"], -heads["N_kN"]])
    M = np.column_stack([heads["Mx_kNm"], heads["My_kNm"], heads["T_kNm"]])
    arm = np.column_stack([heads["x_m"], heads["y_m"], np.zeros_like(heads["x_m"])]) \
        - np.asarray(point)
    return np.concatenate([F.sum(axis=0), (M + np.cross(arm, F)).sum(axis=0)])


@register("cap-equilibrium")
def cap_equilibrium(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """The pile heads balance all six cap actions, every component, to 1e-6 relative."""
    comm = comm or world()
    t0 = time.perf_counter()
    tables, n = run_pipeline(lateral_scenario("equilibrium", size), comm, (HEADS_CSV,))
    got = head_resultant(_last(tables[HEADS_CSV]), GROUP_POINT)
    a = GROUP_ACTIONS
    applied = np.array([a["Fx_kN"], a["Fy_kN"], -a["cap_load_kN"], a["Mx_kNm"], a["My_kNm"],
                        a["Mz_kNm"]])
    errs = np.abs(got - applied) / np.abs(applied)
    tol = 1e-6
    return CaseResult(
        "cap-equilibrium", float(errs.max()), tol, bool(errs.max() <= tol),
        time.perf_counter() - t0, n["dofs"], n["newton"], n["steps"],
        reference="statics: the sum of the pile head actions about the action point equals "
                  "the applied actions (the cap is free of the soil)",
        details={"applied": applied.tolist(), "heads": got.tolist(),
                 "errors": errs.tolist(), "ranks": comm.size})


@register("rigid-cap-moment")
def rigid_cap_moment(size: str = "fast", comm: MPI.Comm | None = None) -> CaseResult:
    """Axial forces linear in x under a rigid cap and a moment My (5 % of the largest)."""
    comm = comm or world()
    t0 = time.perf_counter()
    tables, n = run_pipeline(lateral_scenario("moment", size), comm, (HEADS_CSV,))
    heads = tables[HEADS_CSV]
    before, after = (heads["t_day"] == 1.0), (heads["t_day"] == 2.0)
    x, N = heads["x_m"][after], heads["N_kN"][after] - heads["N_kN"][before]
    a = float(N @ x / (x @ x))
    err = float(np.max(np.abs(N - a * x)) / np.max(np.abs(N)))
    tol = 0.05
    return CaseResult(
        "rigid-cap-moment", err, tol, bool(err <= tol), time.perf_counter() - t0, n["dofs"],
        n["newton"], n["steps"],
        reference="rigid cap on equal piles under a moment: N_i = a x_i (Fleming et al. 2009)",
        details={"x_m": x.tolist(), "N_kN": N.tolist(), "slope_kN_per_m": a,
                 "axial_share_of_moment": float(N @ x) / MOMENT_KNM,
                 "rigid_cap_rule_kN_per_m": MOMENT_KNM / float(x @ x), "ranks": comm.size})



