"""Verification cases of the pile–soil interface (separate pile and soil fields).

Registered into :data:`pilegroup.studies.verification.CASES`, so ``pilegroup verify
shaft-capacity interface-patch tied-limit`` runs them (also under ``mpirun -n 2``):

* ``shaft-capacity``: a single pile pushed down to failure in elastic, drained soil; the plateau
  of the head load against the Drucker–Prager shaft capacity ``sum tau_f A``;
* ``interface-patch``: two one-cell blocks joined by a horizontal (``base_*``) interface under
  mixed control (normal closure and transverse slip prescribed, shear force ramped then held:
  creep), against the same law driven pointwise with the same history;
* ``tied-limit``: a single pile in two-layer soil with a very stiff, non-yielding interface
  against the tied model (one displacement field): head settlement.

Each case runs the real pipeline (mesh, :class:`~pilegroup.solver.biot.BiotProblem` with
:class:`~pilegroup.solver.inputs.InterfaceCoupling`, :func:`~pilegroup.solver.stepping.run_stages`)
and returns a :class:`~pilegroup.studies.verification.CaseResult`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["INTERFACE_CASES", "interface_patch", "shaft_capacity", "tied_limit"]


# ---------------------------------------------------------------------------- helpers
def _allsum(comm: Any, x: Any) -> Any:
    from mpi4py import MPI

    return comm.allreduce(x, op=MPI.SUM)


def _interior_facet_area(md: Any, name: str) -> float:
    import ufl
    from dolfinx import fem

    dS = ufl.Measure("dS", domain=md.mesh, subdomain_data=md.facet_tags)
    return _allsum(md.mesh.comm, fem.assemble_scalar(
        fem.form(ufl.avg(fem.Constant(md.mesh, 1.0)) * dS(md.facet_tag(name)))))


def _pile_mesh(comm: Any, layers: tuple[tuple[str, float | None], ...], length: float,
               size: str) -> Any:
    """A single pile (d = 1 m, head on the ground, no cap) in a small block, by gmsh."""
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.geometry.spec import BlockSpec, GeometrySpec, LayerSpec, MeshSizing, PileSpec

    h = {"fast": 0.5, "bench": 0.25}[size]
    spec = GeometrySpec(
        block=BlockSpec(6.0, 6.0, length + 3.0),
        layers=tuple(LayerSpec(n, t) for n, t in layers),
        piles=(PileSpec(0.0, 0.0, 1.0, length, 0.0),),
        cap=None,
        sizing=MeshSizing(h_pile=h, n_circ_min=8 if size == "fast" else 16,
                          near_field_margin=1.0, h_far=1.5, dz_surface=h, dz_toe=h,
                          dz_max=2 * h, dz_max_deep=1.5, dz_growth=1.3))
    return build_mesh(spec, comm, cache_dir=False)


def shaft_profile_oscillation(itf: Any, comm: Any) -> dict[str, float]:
    """Roughness of the shaft tractions along the pile (committed state, all shaft groups).

    The material points (nodes or Gauss points) are averaged per height level (m, rounded to
    1e-6; on a polygonal shaft every level is one ring), giving profiles ``sigma_n(z)`` and
    ``tau1(z)`` (kPa). For each: ``tv_ratio`` = total variation ``sum |s_k+1 - s_k|`` over the
    range ``max s - min s`` (1 for a monotonic profile, 2 for one extremum, large for a
    zig-zag) and ``sign_changes`` of the level-to-level differences larger than 1e-6 of the
    range.
    """
    L = itf.split.n_layers
    loc = [np.zeros((0, 3))]
    for m in range(L):
        p = itf.material_points(m)
        if p["state"] is None:
            continue
        own = p["weight"] > 0.0
        loc.append(np.column_stack([p["x"][own, 2], p["state"]["traction"][own, :2]]))
    a = np.concatenate(comm.allgather(np.concatenate(loc)))
    z = np.round(a[:, 0], 6)
    levels, inv = np.unique(z, return_inverse=True)
    out: dict[str, float] = {"levels": float(levels.size)}
    for k, name in ((1, "sigma_n"), (2, "tau1")):
        prof = np.bincount(inv, a[:, k]) / np.bincount(inv)
        d = np.diff(prof)
        rng = float(prof.max() - prof.min()) if prof.size else 0.0
        big = d[np.abs(d) > 1e-6 * rng] if rng > 0 else d[:0]
        out[f"{name}_tv_ratio"] = float(np.abs(d).sum() / rng) if rng > 0 else 1.0
        out[f"{name}_sign_changes"] = float(np.sum(np.diff(np.sign(big)) != 0))
    return out


def _box_bcs(DisplacementBC: Any) -> list[Any]:
    return [DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
            DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
            *(DisplacementBC("bottom", c) for c in range(3))]


# ---------------------------------------------------------------------------- shaft capacity
def shaft_capacity(size: str = "fast", pair: str = "Q1Q1", preset: str = "direct",
                   comm: Any = None, quadrature: str = "nodal",
                   k_normal_factor: float = 1.0) -> Any:
    """Axial push of a single pile to failure of the shaft interface (drained, elastic soil).

    Pile d = 1 m (meshed as a regular polygon of 8 sides, fast size), L = 4 m in one soil layer
    (block 6 x 6 x 7 m), E_pile = 30 GPa; soil linear elastic E = 20 MPa, nu = 0.3,
    gamma_sat = 18 kN/m3, K0 = 0.8; every pressure dof fixed (drained). Stages: geostatic
    (K0 stresses, in-situ interface tractions ``sigma_n = K0 sigma'_v``), then the head facets
    ``head_p1`` pushed down 3 cm (displacement control, ramped over 1 day).

    ``quadrature``: the interface quadrature (``"nodal"``/``"gauss"``); ``k_normal_factor``
    multiplies the shaft's normal penalty (for the quadrature study, docs/solver.md); the
    details carry the roughness of the shaft traction profiles
    (:func:`shaft_profile_oscillation`) after the first output (3 mm) and at the end.

    Shaft law: :class:`PileSoilInterface` with ``viscous=True``, implicit, ``variant="default"``,
    c = 10 kPa, phi = 20 deg, ``R_f = 0`` (linear elastic slip springs, no hyperbola asymptote, so
    the Drucker–Prager limit governs), ``K r_w = 1e6`` kPa/m (stiff), eta = 1e-2 kPa·day/m
    (overstress ``eta * slip rate`` <= 3e-4 kPa: the rate-independent limit). Shear strength
    (docs/model.md, Eq. 13/15 "default"): ``tau_f = k - 3 alpha sigma_n`` with ``(alpha, k) =
    dp_outer_cone(c, phi)``. Base: normal penalty 1 kPa/m (soft), no viscoplastic slip, so the
    base carries its in-situ ``sigma'_v A_b`` (which balances the pile's buoyant weight) plus
    ``1 kPa/m x 3 cm x A_b`` = 0.02 kN.

    Reference (closed form): ``Q_s = sum_shaft tau_f A``. With the in-situ normal stress, ``Q_s0
    = P_h (k L + 3 alpha K0 gamma' L^2 / 2)`` (``P_h`` the meshed polygon perimeter, ``gamma' =
    gamma_sat - gamma_w``; the nodal weights, and the 2 x 2 Gauss rule with
    ``quadrature="gauss"``, make the sum exact for the linear in-situ ``sigma_n(z)``). Pushing
    the pile changes sigma_n at the shaft's end rings (elastic soil, the shear traction stops
    abruptly at the ground surface and at the toe): measured -1.1 -> -32 kPa at the head ring,
    -25 -> -13 kPa at the toe ring, so the plateau is 5.0 % above ``Q_s0``. The error is
    therefore the larger of (a) the plateau (head reaction increase at the last of 10 outputs)
    against ``sum_i W_i tau_f(sigma_n,i)`` over the interface's material points (nodes, or Gauss
    points) with their sigma_n at the end, and (b) the same sum with the geostatic sigma_n
    against ``Q_s0``. Tolerance 2 %; the case also requires every shaft point on the yield
    surface. Measured:
    (a) 1.0e-4 (the soft base spring, 0.02 kN), (b) 6e-16.
    """
    from pilegroup.constitutive.interface import PileSoilInterface, dp_outer_cone
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.solver import (
        GAMMA_W,
        BiotProblem,
        Discretisation,
        DisplacementBC,
        ElasticSolid,
        InterfaceCoupling,
        PressureBC,
        SoilMaterial,
        SolverOptions,
        Stage,
        TimeStepping,
        run_stages,
    )
    from pilegroup.studies.verification import CaseResult, _comm

    comm = comm or _comm()
    t0 = time.perf_counter()
    L, push = 4.0, 0.03
    c, phi, K0, gamma = 10.0, 20.0, 0.8, 18.0
    md = _pile_mesh(comm, (("soil", None),), L, size)
    soil = SoilMaterial(LinearElastic(2.0e4, 0.3), 1e-3, 0.4, gamma_sat=gamma, K0=K0)
    shaft = PileSoilInterface(K=1.0e5, n=0.0, R_f=0.0, c=c, phi_deg=phi, eta=1e-2,
                              k_normal=4.0e6 * k_normal_factor, delta_deg=30.0, viscous=True,
                              integrator="implicit", variant="default")
    base = PileSoilInterface(K=1.0e3, n=0.0, R_f=0.0, c=c, phi_deg=phi, eta=1.0, k_normal=1.0,
                             delta_deg=30.0, viscous=False)
    pb = BiotProblem(
        md, {"soil_layer_01": soil, "pile_1": ElasticSolid(3.0e7, 0.2)},
        Discretisation(pair=pair),
        displacement_bcs=[*_box_bcs(DisplacementBC), DisplacementBC("head_p1", 2, -push)],
        pressure_bcs=[PressureBC(None)],
        options=SolverOptions(preset=preset, prefix=f"shaftcap_{pair}_"),
        interface=InterfaceCoupling((shaft, base), quadrature=quadrature))
    rows: list[dict[str, float]] = []
    osc_first: dict[str, float] = {}
    R0 = [0.0]
    sn0 = [0.0]

    def _shaft_capacity_now(p: Any) -> float:
        pts = p.interface.material_points(0)
        if pts["state"] is None:  # no shaft point on this rank
            return _allsum(comm, 0.0)
        sn = pts["state"]["traction"][:, 0]
        return _allsum(comm, float(np.sum(pts["weight"] * (k - 3.0 * alpha * sn))))

    def record(p: Any, t: float, stage: str) -> None:
        R = p.reaction("head_p1", 2)
        if stage == "geostatic":
            R0[0] = R
            sn0[0] = _shaft_capacity_now(p)
            return
        rows.append({"t": t, "head_displacement_m": -push * t, "head_load_kN": -(R - R0[0])})
        if len(rows) == 1:  # 3 mm push: the shaft partly elastic
            osc_first.update(shaft_profile_oscillation(p.interface, comm))

    alpha, k = dp_outer_cone(c, phi)
    ts = TimeStepping(dt0=0.05, dt_max=0.05, dt_min=1e-4,
                      milestones=tuple(np.round(np.arange(0.1, 1.0, 0.1), 12)))
    log = run_stages(pb, [Stage("geostatic", "geostatic"), Stage("push", "load", 1.0, 1.0)], ts,
                     on_milestone=record, geostatic_tol=1e-4)
    pts = pb.interface.material_points(0)
    own = pts["weight"] > 0.0
    area = _allsum(comm, float(pts["weight"].sum()))
    perim = area / L
    Q_ref = perim * (k * L + 3.0 * alpha * K0 * (gamma - GAMMA_W) * L**2 / 2.0)
    Q_act = _shaft_capacity_now(pb)
    F = shaft.yield_function(pts["state"]["traction"][own]) if pts["state"] is not None \
        else np.zeros(0)
    n_yield = _allsum(comm, int(np.sum(F > -1e-9 * k)))
    n_points = _allsum(comm, int(own.sum()))
    Q_fe = rows[-1]["head_load_kN"]
    err_plateau = abs(Q_fe - Q_act) / Q_act
    err_insitu = abs(sn0[0] - Q_ref) / Q_ref
    err = max(err_plateau, err_insitu)
    tol = 0.02
    return CaseResult(
        "shaft-capacity", err, tol, bool(err <= tol and n_yield == n_points),
        time.perf_counter() - t0, pb.num_dofs, log.newton_total, len(log.steps),
        reference="Drucker-Prager shaft capacity sum tau_f A, tau_f = k - 3 alpha sigma_n "
                  "(docs/model.md, constitutive/interface.py); in situ sigma_n = K0 sigma'_v",
        details={"pair": pair, "quadrature": quadrature, "head_load_kN": Q_fe,
                 "capacity_actual_sigma_n_kN": Q_act,
                 "err_plateau": err_plateau, "capacity_insitu_sum_kN": sn0[0],
                 "capacity_closed_form_kN": Q_ref, "err_insitu": err_insitu,
                 "head_load_vs_closed_form": (Q_fe - Q_ref) / Q_ref,
                 "shaft_points_at_yield": n_yield, "shaft_points": n_points,
                 "shaft_area_m2": area, "perimeter_m": perim, "circle_perimeter_m": math.pi,
                 "alpha": alpha, "k_kPa": k, "head_reaction_geostatic_kN": R0[0],
                 "geostatic_max_u_m": log.geostatic_max_u, "rows": rows,
                 "k_normal_kPa_per_m": shaft.k_normal,
                 "oscillation_first": osc_first,
                 "oscillation_end": shaft_profile_oscillation(pb.interface, comm),
                 "rejected": log.rejected, "ranks": comm.size, "cells": md.info["num_cells"]})


# ---------------------------------------------------------------------------- patch test
def _two_blocks(comm: Any) -> Any:
    """Two unit cubes stacked: ``pile_1`` (z in [0, 1]) on ``soil_layer_01`` (z in [-1, 0]).

    Facet groups: ``top`` (z = 1), ``struct_side`` and ``soil_side`` (the vertical faces of each
    block), ``bottom`` (z = -1) and the interior ``base_1`` (z = 0). One cell per block.
    """
    from dolfinx import mesh as dmesh

    from pilegroup.geometry.box import build_box
    from pilegroup.geometry.meshdata import MeshData

    md0 = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.array([-1.0, 0.0, 1.0]), 1, 1,
                    layer_tops=[0.0])
    msh = md0.mesh
    tdim = msh.topology.dim
    fdim = tdim - 1
    msh.topology.create_entities(fdim)
    msh.topology.create_connectivity(fdim, tdim)
    names = {"top": 1, "struct_side": 2, "soil_side": 3, "bottom": 4, "base_1": 5}
    imap = msh.topology.index_map(fdim)
    facets = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
    mid = dmesh.compute_midpoints(msh, fdim, facets)
    tol = 1e-9
    side = (np.isclose(mid[:, 0], 0.0, atol=tol) | np.isclose(mid[:, 0], 1.0, atol=tol)
            | np.isclose(mid[:, 1], 0.0, atol=tol) | np.isclose(mid[:, 1], 1.0, atol=tol))
    vals = np.zeros(facets.size, dtype=np.int32)
    vals[np.isclose(mid[:, 2], 1.0, atol=tol)] = names["top"]
    vals[np.isclose(mid[:, 2], -1.0, atol=tol)] = names["bottom"]
    vals[np.isclose(mid[:, 2], 0.0, atol=tol) & ~side] = names["base_1"]
    vals[side & (mid[:, 2] > 0)] = names["struct_side"]
    vals[side & (mid[:, 2] < 0)] = names["soil_side"]
    keep = vals > 0
    ft = dmesh.meshtags(msh, fdim, facets[keep], vals[keep])
    # build_box numbers layers from the top: 1 = z > 0 (the structure), 2 = z < 0 (the soil)
    return MeshData(msh, md0.cell_tags, ft, {"pile_1": 1, "soil_layer_01": 2}, names,
                    {"builder": "verification_interface._two_blocks"})


def _solve_mixed(law: Any, state: dict[str, np.ndarray], dj: np.ndarray, target: float,
                 dt: float) -> tuple[np.ndarray, dict[str, np.ndarray], float]:
    """Law update with ``dj[0, 0], dj[0, 2]`` given and ``tau1 = target`` (Newton on dj[0, 1])."""
    dj = dj.copy()
    for _ in range(60):
        t, trial, D = law.update(dj, state, dt)
        r = t[0, 1] - target
        if abs(r) <= 1e-14 * max(abs(target), 1.0):
            break
        dj[0, 1] -= r / D[0, 1, 1]
    else:  # pragma: no cover
        raise RuntimeError("pointwise mixed-control Newton did not converge")
    return t, trial, float(dj[0, 1])


def interface_patch(size: str = "fast", pair: str = "Q1Q1", preset: str = "direct",
                    comm: Any = None, quadrature: str = "nodal") -> Any:
    """Horizontal interface patch under mixed control, with creep, against the pointwise law.

    Two unit cubes, one Q1 cell each (the case always uses Q1Q1: with one cell per block every
    soil node and every non-interface structure node lies on a constrained face, which makes the
    discrete solution exactly homogeneous); the upper block is the structure (``pile_1``,
    E = 1 GPa), the lower the soil (drained, all pressure dofs fixed), joined on the interior
    facet group ``base_1`` (local frame n = -z, t1 = x, t2 = y; 1 m^2). The soil block is fixed
    on all its faces. The structure: z prescribed on all its faces (closure g = 1 mm from the
    first step), y prescribed (transverse slip ramped to 10 mm over day 0–1, then held), x of
    the top face a rigid plate under force control: the shear force is ramped to 32 kN over day
    0–1 and then held for 4 days (creep, the Perzyna slip rate at constant shear). The bottom x
    dofs of the structure are free, so its simple shear is part of the solution.

    Law: ``PileSoilInterface(K=200, n=0.5, R_f=0.8, c=5 kPa, phi=10 deg, delta=20 deg,
    eta=500 kPa·day/m, k_normal=1e5 kPa/m)``, implicit, default variant: at sigma_n = -100 kPa
    the hyperbola asymptote is 45.5 kPa and tau_f = 27.4 kPa, so the interface yields during the
    ramp and creeps at constant load, with a slip vector that rotates (tau2 relaxes at fixed y
    slip while tau1 is held).

    Reference: the same law's ``update`` driven pointwise with the same steps (dt, load factor of
    every accepted step): normal and t2 jump increments given, the t1 jump increment solved so
    that ``tau1`` equals the applied shear stress (scalar Newton to 1e-14). Error: the largest,
    over all steps, of the differences in sigma_n, tau1, tau2, slip1 (FE jump), both
    viscoplastic slips and the soil reactions (x and z: the assembled interface force), each
    relative to the largest magnitude of its reference history. Tolerance 1e-6.
    """
    from pilegroup.constitutive.interface import PileSoilInterface
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.solver import (
        BiotProblem,
        Discretisation,
        DisplacementBC,
        ElasticSolid,
        InterfaceCoupling,
        PressureBC,
        RigidPlate,
        SoilMaterial,
        SolverOptions,
        Stage,
        TimeStepping,
        run_stages,
    )
    from pilegroup.studies.verification import CaseResult, _comm

    comm = comm or _comm()
    t0 = time.perf_counter()
    pair = "Q1Q1"
    gap, s2, tau1 = 1.0e-3, 1.0e-2, 32.0
    md = _two_blocks(comm)
    law = PileSoilInterface(K=200.0, n=0.5, R_f=0.8, c=5.0, phi_deg=10.0, eta=500.0,
                            k_normal=1.0e5, delta_deg=20.0, viscous=True, integrator="implicit",
                            variant="default")
    soil = SoilMaterial(LinearElastic(1.0e4, 0.3), 1e-3, 0.4)
    bcs = [DisplacementBC(f, cpt) for f in ("bottom", "soil_side") for cpt in range(3)]
    bcs += [DisplacementBC(f, 2, -gap, ramp=False) for f in ("top", "struct_side")]
    bcs += [DisplacementBC(f, 1, s2) for f in ("top", "struct_side")]
    pb = BiotProblem(
        md, {"soil_layer_01": soil, "pile_1": ElasticSolid(1.0e6, 0.2)},
        Discretisation(pair=pair), displacement_bcs=bcs, pressure_bcs=[PressureBC(None)],
        plates=[RigidPlate("top", 0, -tau1 * 1.0)],
        options=SolverOptions(preset=preset, prefix="patch_"), self_weight=False,
        interface=InterfaceCoupling((None, law), quadrature=quadrature))
    area = _interior_facet_area(md, "base_1")
    itf = pb.interface
    fe: list[np.ndarray] = []
    steps: list[tuple[float, float, float]] = []
    last_t = [0.0]

    def on_step(p: Any, t: float, stage: str) -> None:
        pts = itf.material_points(1)
        st = pts["state"]
        vals = np.column_stack([st["traction"], pts["jump_local"], st["slip_vp"]])[
            pts["weight"] > 0.0] if st is not None else np.zeros((0, 8))
        n = _allsum(comm, vals.shape[0])
        mean = _allsum(comm, vals.sum(axis=0)) / n
        spread = comm.allreduce(float(np.abs(vals - mean).max(initial=0.0)), op=_mpi_max())
        rx = p.reaction("soil_side", 0)
        rz = p.reaction("soil_side", 2)
        fe.append(np.concatenate([mean, [rx / area, rz / area, spread]]))
        steps.append((t, t - last_t[0], p.load_factor))
        last_t[0] = t

    ts = TimeStepping(dt0=0.05, dt_max=0.5, dt_min=1e-5, grow=1.5,
                      milestones=(0.25, 0.5, 0.75, 2.0, 3.0, 4.0))
    log = run_stages(pb, [Stage("shear", "load", 1.0, 1.0),
                          Stage("creep", "consolidation", 4.0)], ts, on_step=on_step)
    # pointwise reference with the same steps
    state = law.initial_state(1)
    s1_prev = 0.0
    ref = []
    jn_prev, j2_prev = 0.0, 0.0
    for _t, dt, lam in steps:
        jn, j2 = -gap, -s2 * lam
        dj = np.array([[jn - jn_prev, 0.0, j2 - j2_prev]])
        tr, state, ds1 = _solve_mixed(law, state, dj, tau1 * lam, dt)
        s1_prev += ds1
        jn_prev, j2_prev = jn, j2
        ref.append(np.concatenate([tr[0], [jn, s1_prev, j2], state["slip_vp"][0]]))
    F = np.array(fe)
    Rf = np.array(ref)
    # FE columns: sigma_n tau1 tau2 | opening s1 s2 | vp1 vp2 | rx/A rz/A | spread
    pairs = {"sigma_n": (F[:, 0], Rf[:, 0]), "tau1": (F[:, 1], Rf[:, 1]),
             "tau2": (F[:, 2], Rf[:, 2]), "opening": (F[:, 3], Rf[:, 3]),
             "slip1": (F[:, 4], Rf[:, 4]), "slip2": (F[:, 5], Rf[:, 5]),
             "slip_vp1": (F[:, 6], Rf[:, 6]), "slip_vp2": (F[:, 7], Rf[:, 7]),
             # the soil's reaction is the interface force on the soil: +t A (global x = t1,
             # global z = -sigma_n)
             "reaction_x": (F[:, 8], Rf[:, 1]), "reaction_z": (F[:, 9], -Rf[:, 0])}
    errs = {k: float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))
            for k, (a, b) in pairs.items()}
    err = max(errs.values())
    tol = 1e-6
    i1 = next(i for i, s in enumerate(steps) if s[0] >= 1.0 - 1e-12)
    rows = [{"t": s[0], "sigma_n": f[0], "tau1": f[1], "tau2": f[2], "slip1": f[4],
             "slip_vp1": f[6], "slip_vp2": f[7], "sigma_n_ref": r[0], "tau1_ref": r[1],
             "tau2_ref": r[2], "slip1_ref": r[4], "slip_vp1_ref": r[6], "slip_vp2_ref": r[7]}
            for s, f, r in zip(steps, F, Rf, strict=True)]
    return CaseResult(
        "interface-patch", err, tol, bool(err <= tol), time.perf_counter() - t0, pb.num_dofs,
        log.newton_total, len(log.steps),
        reference="PileSoilInterface.update driven pointwise with the same history",
        details={"pair": pair, "quadrature": quadrature, "errors": errs,
                 "node_spread_max": float(F[:, 10].max()),
                 "interface_area_m2": area, "creep_slip_vp_m": float(np.hypot(
                     Rf[-1, 6], Rf[-1, 7]) - np.hypot(Rf[i1, 6], Rf[i1, 7])),
                 "tau_f_kPa": float(law.k - 3 * law.alpha * Rf[-1, 0]),
                 "rows": rows, "rejected": log.rejected, "ranks": comm.size})


def _mpi_max() -> Any:
    from mpi4py import MPI

    return MPI.MAX


# ---------------------------------------------------------------------------- tied limit
def tied_limit(size: str = "fast", pair: str = "Q1Q1", preset: str = "direct",
               comm: Any = None, quadrature: str = "nodal",
               k_normal_factor: float = 1.0) -> Any:
    """Very stiff elastic interface against tied piles: head settlement of a single pile.

    Pile d = 1 m, L = 4 m (E = 30 GPa) through two layers (0–2 m: E = 5 MPa, gamma_sat = 17,
    K0 = 0.7; below: E = 20 MPa, gamma_sat = 19, K0 = 0.6; nu = 0.3, linear elastic), block
    6 x 6 x 7 m, all pressure dofs fixed (drained: no consolidation, so the two models are
    compared at the same, steady state). Stages: geostatic, then 300 kN on the head facets
    ``head_p1`` (one step). Interface (all shaft and base groups):
    ``PileSoilInterface(viscous=False, K = 1e8 (K r_w = 1e9 kPa/m), n = 0, R_f = 0,
    k_normal = 1e9 kPa/m)``: linear springs 2e4 times stiffer than E_soil / h.

    Reference: the same problem with ``interface=None`` (one displacement field). Error: the
    relative difference of the mean head settlements. Tolerance 1 %. The interface has no
    tensile strength: the shaft nodes of the toe ring open (by ~3e-8 m, 8 nodes at z = -4 m,
    measured) where the tied soil carries radial tension at the toe corner; their number and
    elevations are in the details. ``quadrature``: the interface quadrature;
    ``k_normal_factor`` multiplies k_normal (quadrature study, docs/solver.md); the details
    carry the roughness of the shaft traction profiles (:func:`shaft_profile_oscillation`).
    """
    from pilegroup.constitutive.interface import PileSoilInterface
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.solver import (
        BiotProblem,
        Discretisation,
        DisplacementBC,
        ElasticSolid,
        InterfaceCoupling,
        PressureBC,
        SoilMaterial,
        SolverOptions,
        Stage,
        SurfaceLoad,
        TimeStepping,
        run_stages,
    )
    from pilegroup.solver.probes import SettlementProbe, facet_area
    from pilegroup.studies.verification import CaseResult, _comm

    comm = comm or _comm()
    t0 = time.perf_counter()
    L, Q = 4.0, 300.0
    md = _pile_mesh(comm, (("upper", 2.0), ("lower", None)), L, size)
    mats = {"soil_layer_01": SoilMaterial(LinearElastic(5.0e3, 0.3), 1e-3, 0.5, 17.0, K0=0.7),
            "soil_layer_02": SoilMaterial(LinearElastic(2.0e4, 0.3), 1e-3, 0.4, 19.0, K0=0.6),
            "pile_1": ElasticSolid(3.0e7, 0.2)}
    stiff = PileSoilInterface(K=1.0e8, n=0.0, R_f=0.0, c=0.0, phi_deg=20.0, eta=1.0,
                              k_normal=1.0e9 * k_normal_factor, delta_deg=30.0, viscous=False)
    q = Q / facet_area(md, ["head_p1"])
    out: dict[str, Any] = {}
    for mode, coupling in (("tied", None), ("interface", InterfaceCoupling(
            (stiff,) * 4, quadrature=quadrature))):
        pb = BiotProblem(
            md, mats, Discretisation(pair=pair), displacement_bcs=_box_bcs(DisplacementBC),
            pressure_bcs=[PressureBC(None)], loads=[SurfaceLoad("head_p1", q)],
            options=SolverOptions(preset=preset, prefix=f"tied_{mode}_{pair}_"),
            interface=coupling)
        probe = SettlementProbe(pb, ["head_p1"])
        log = run_stages(pb, [Stage("geostatic", "geostatic"), Stage("load", "load", 0.0, 1.0)],
                         TimeStepping(), geostatic_tol=1e-4)
        det, det_z = 0, []
        if pb.interface is not None:
            for m in range(len(pb.interface.groups)):
                pts = pb.interface.material_points(m)
                if pts["state"] is None:
                    continue
                d = (pts["state"]["detached"][:, 0] > 0.5) & (pts["weight"] > 0.0)
                det += int(d.sum())
                det_z += [float(z) for z in pts["x"][d, 2]]
            det = _allsum(comm, det)
            det_z = sorted({round(z, 9) for zs in comm.allgather(det_z) for z in zs})
        osc = shaft_profile_oscillation(pb.interface, comm) if pb.interface is not None else {}
        out[mode] = {"settlement_m": probe(), "dofs": pb.num_dofs, "newton": log.newton_total,
                     "oscillation": osc,
                     "steps": len(log.steps), "detached_nodes": det,
                     "detached_z_m": det_z,
                     "geostatic_max_u_m": log.geostatic_max_u}
    s_t, s_i = out["tied"]["settlement_m"], out["interface"]["settlement_m"]
    err = abs(s_i - s_t) / abs(s_t)
    tol = 0.01
    passed = bool(err <= tol)
    return CaseResult(
        "tied-limit", err, tol, passed, time.perf_counter() - t0, out["interface"]["dofs"],
        out["tied"]["newton"] + out["interface"]["newton"],
        out["tied"]["steps"] + out["interface"]["steps"],
        reference="tied model (interface=None), same mesh and loads",
        details={"pair": pair, **{f"{m}_{k}": v for m, d in out.items() for k, v in d.items()},
                 "quadrature": quadrature,
                 "rows": [{"settlement_tied_m": s_t, "settlement_interface_m": s_i}],
                 "ranks": comm.size, "cells": md.info["num_cells"]})


INTERFACE_CASES: dict[str, Callable[..., Any]] = {
    "shaft-capacity": shaft_capacity,
    "interface-patch": interface_patch,
    "tied-limit": tied_limit,
}
