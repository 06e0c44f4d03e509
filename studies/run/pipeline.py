"""A scenario as a coupled Biot problem, and the one way a scenario's stages are run.

The one place that maps :class:`~pilegroup.model.Scenario` onto the solver's inputs. Piles and
cap are elastic solids, tied to the soil (``interface.mode = "tied"``: one field, the cap bonded
to the ground) or on their own field joined to the soil by each layer's interface law.
Boundaries (docs/model.md): bottom fixed, sides roller, ground surface (or the water table
below it) drained; the rest impermeable. The cap load: a pressure on the cap top (pile heads).
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from tqdm import tqdm

from pilegroup.constitutive.base import ConstitutiveLaw
from pilegroup.constitutive.cam_clay import ModifiedCamClay
from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.constitutive.soil import DruckerPrager, LinearElastic, MohrCoulomb
from pilegroup.errors import StepFailure
from pilegroup.geometry import groups
from pilegroup.geometry.adapter import ResolvedGeometry
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.plan import meshed_radii, shaft_factor
from pilegroup.geometry.symmetry import PLANES
from pilegroup.model import Scenario, Stage
from pilegroup.model.analysis import InterfaceOptions
from pilegroup.model.insitu import own_levels, seepage
from pilegroup.model.soil_models import k0nc, layer_model
from pilegroup.solver import (
    GAMMA_W,
    BiotProblem,
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    Export,
    InstallationExcess,
    InterfaceCoupling,
    NewtonOptions,
    PressureBC,
    RunLog,
    SoilMaterial,
    SolverOptions,
    SolverStage,
    StepControl,
    SummaryWriter,
    SurfaceLoad,
    XDMFSeries,
    run_stages,
    run_summary,
)
from pilegroup.solver.presets import get_preset
from pilegroup.solver.probes import facet_area
from pilegroup.studies.results.records import SOLVER_SUMMARY_JSON, RunSummary
from pilegroup.studies.results.tables import GAUGES_CSV, STIFFNESS_CSV
from pilegroup.studies.run.auto_preset import scenario_preset
from pilegroup.studies.run.cap_loads import (
    face_actions,
    first_slot,
    loaded_facets,
    stage_amplitudes,
    used_components,
)
from pilegroup.studies.run.capacity_probe import CapacityProbe
from pilegroup.studies.run.checkpoint import Checkpoints
from pilegroup.studies.run.gauge_probe import GaugeProbe
from pilegroup.studies.run.ground_probe import GroundProbe
from pilegroup.studies.run.pile_probe import LoadSettlementCurve, PileProbe, SettlementSeries
from pilegroup.studies.run.section_probe import CapMotion, PileSections
from pilegroup.studies.run.stiffness import cap_stiffness, write_cap_stiffness

log = logging.getLogger(__name__)

#: Largest displacement (m) the geostatic equilibrium check accepts: with the interface, the
#: nodal in-situ tractions balance the Gauss-integrated soil stress only to 2.7e-6 m (single
#: pile) and 1.1e-5 m (pier667), a residual not yet explained; tied piles < 1e-9 m.
GEOSTATIC_TOL_M = 1e-4

#: A capacity stage's steps are at most its duration over this many: the load–settlement curve
#: (and the plunging criterion's tangent) gets as many points (docs/model.md, "Capacity").
CAPACITY_STEPS = 50

#: The shear's fade at an opening (``PileSoilInterface.fade_stiffness``) follows the penalty up
#: to ``FADE_FACTOR * E / FADE_LENGTH_M``, the default penalty at h = 1 m: steeper, Newton
#: cycles (docs/solver.md, "Newton").
FADE_FACTOR, FADE_LENGTH_M = InterfaceOptions.normal_stiffness_factor, 1.0

def band_layers(h: float, width_m: float) -> int:
    """Cell layers of soil in the exact block of ``fieldsplit_pier`` at pile mesh size ``h``.

    Enough layers of the size ``h`` (m, at the pile surfaces) for the band's width ``width_m``
    (``Preset.band_width_m``). On the full Pier 667 the iterations follow the band's width, not
    its layer count: two layers at h = 1 m and six at 0.3 m need about the same, two at 0.3 m
    60 % more (docs/benchmarks.md).
    """
    return max(1, math.ceil(width_m / h - 1e-9))


def soil_law(sc: Scenario, j: int) -> ConstitutiveLaw:
    """The constitutive law of soil layer ``j`` (kPa, degrees, days) by its soil model.

    The layer's ``model``, else ``soil.model``; the critical-state laws' pre-consolidation from
    the layer's ``OCR`` or ``POP_kPa`` at each point's geostatic stress, Cam Clay's ``K0nc``
    that of the layer's K0 (docs/model.md, "Soil models per layer").
    """
    lay = sc.layers[j]
    model = layer_model(lay, sc.soil)
    pre = {"OCR": 1.0 if lay.OCR is None else lay.OCR,
           "POP": 0.0 if lay.POP_kPa is None else lay.POP_kPa}
    if model == "modified_cam_clay":
        return ModifiedCamClay(lay.lam, lay.kappa, lay.e0, M=lay.M,  # type: ignore[arg-type]
                               phi_cs_deg=lay.phi_cs_deg, nu=lay.nu, K0nc=k0nc(lay), **pre)
    if model == "soft_soil_creep":
        return SoftSoilCreep(lay.lambda_star, lay.kappa_star,  # type: ignore[arg-type]
                             lay.mu_star, lay.phi_deg, c=lay.c_kPa or 0.0, nu_ur=lay.nu_ur,
                             tau=lay.tau_ref_day, **pre)
    if model == "linear_elastic":
        return LinearElastic(lay.E, lay.nu)
    cls = MohrCoulomb if model == "mohr_coulomb" else DruckerPrager
    return cls(lay.E, lay.nu, lay.c_kPa, lay.phi_deg, lay.psi_deg)


def build_problem(sc: Scenario, geo: ResolvedGeometry, md: MeshData, preset: str | None = None
                  ) -> BiotProblem:
    """The :class:`~pilegroup.solver.problem.BiotProblem` of scenario ``sc`` on mesh ``md``.

    ``geo`` is the scenario's resolved geometry (the part of the model ``md`` holds).
    """
    materials: dict[str, SoilMaterial | ElasticSolid] = {}
    for j, lay in enumerate(sc.layers):
        materials[groups.soil_layer(j + 1)] = SoilMaterial(
            soil_law(sc, j), lay.k_m_per_day, lay.porosity, lay.gamma_kN_per_m3, K0=lay.k0,
            excess_ratio=lay.excess_pore_pressure_ratio, excess_kPa=lay.excess_pore_pressure_kPa,
            k_h_m_per_day=lay.k_h_m_per_day, gamma_unsat=lay.gamma_unsat_kN_per_m3)
    solid = ElasticSolid(sc.structure.E, sc.structure.nu)
    for name in md.cell_names:
        if groups.is_structure(name):
            materials[name] = solid
    # rollers on the block sides and on the symmetry planes of a reduced model (its flux is
    # zero there, the natural condition of the mass balance)
    rollers = ((groups.SIDE_XMIN, 0), (groups.SIDE_XMAX, 0), (groups.SIDE_YMIN, 1),
               (groups.SIDE_YMAX, 1), (groups.SYM_X, 0), (groups.SYM_Y, 1))
    dbcs = [DisplacementBC(f, c) for f, c in rollers if f in md.facet_names]
    dbcs += [DisplacementBC(groups.BOTTOM, c) for c in range(3)]
    names = loaded_facets(sc, md)
    loads = [SurfaceLoad(f, sc.total_cap_load() / full_load_area(sc, geo, md))
             for f in names] + surcharge_loads(sc) + face_actions(sc, geo, md)
    disc = Discretisation(sc.numerics.element)
    p = scenario_preset(sc, geo.symmetry, estimate_dofs(md, sc.numerics.element), preset)
    num = sc.numerics
    newton = NewtonOptions(rtol=num.newton_rtol, atol=num.newton_atol, max_it=num.time.max_newton,
                           krylov_forcing=num.solver.krylov_forcing)
    h = geo.spec.sizing.h_pile
    width = get_preset(p).band_width_m
    opts = SolverOptions(preset=p, overrides=dict(num.solver.options), newton=newton,
                         band_layers=None if width is None else band_layers(h, width))
    return BiotProblem(md, materials, disc, displacement_bcs=dbcs,
                       pressure_bcs=drainage(sc), loads=loads, options=opts,
                       interface=interface_coupling(sc, h, shaft_factor(geo.spec)),
                       installation=installation(sc, meshed_radii(geo.spec)),
                       install_later=sc.installation_stage is not None, water_table=water_table(sc),
                       seepage=[(-d, u) for d, u in seepage(sc.site, sc.layers)])


def water_table(sc: Scenario) -> float | None:
    """Elevation (m) of a water table below the ground surface; None: at the surface."""
    return -sc.site.water_table_depth_m if sc.site.water_table_depth_m > 0.0 else None


def installation(sc: Scenario, radii: list[float]) -> InstallationExcess | None:
    """The piles' installation pore pressures (every pile of the whole foundation), or None.

    Each pile's cavity has its own radius and toe: ``radii``, the meshed circumradii (every
    shaft node at r0), and its length in soil.
    """
    p = sc.piles
    ins = p.installation
    if ins is None:
        return None
    return InstallationExcess(tuple((x, y, r0, -length) for (x, y), r0, length
                                    in zip(p.xy, radii, p.lengths, strict=True)),
                              ins.excess_pore_pressure_ratio, ins.radius_ratio)


def ground_actions(sc: Scenario) -> list[Stage]:
    """The surcharge stages, in order: ground action ``i`` is the ``i``-th of them.

    Every groundwater stage moves one more action, the water table's (the last one).
    """
    return [st for st in sc.stages if st.kind == "surcharge"]


def surcharge_loads(sc: Scenario) -> list[SurfaceLoad]:
    """One load on the ground surface per surcharge stage (its ground action's amplitude 0 -> 1).

    The ground surface group does not hold the cap's footprint (``cap_bottom``): a fill is
    placed around a cap, never beneath it.
    """
    return [SurfaceLoad(groups.GROUND, st.surcharge_kPa, action=i,  # type: ignore[arg-type]
                        area=st.area_m)
            for i, st in enumerate(ground_actions(sc))]


def drainage(sc: Scenario) -> list[PressureBC]:
    """The drained ground surface and every drained layer (an aquifer), at the same pressure.

    A lowered water table lowers the aquifers' pressure with it (pumping lowers the head of the
    aquifer it draws from; docs/model.md, "Ground that moves"), not a layer's own piezometric
    level (the region holds it, :func:`~pilegroup.model.insitu.own_levels`).
    """
    top = ground_drainage(sc)
    return [top] + [PressureBC(None, top.value, action=top.action, cells=groups.soil_layer(j + 1))
                    for j, lay in enumerate(sc.layers) if lay.drained] \
        + [PressureBC(None, u, cells=groups.soil_layer(j + 1))
           for j, u in own_levels(sc.site, sc.layers)]


def ground_drainage(sc: Scenario) -> PressureBC:
    """The drained top of the saturated soil: excess pore pressure 0, or ``-gamma_w x drawdown``.

    The ground surface, or the water table below it (docs/model.md, "The ground at rest"). A
    lowered water table (groundwater stages) prescribes the drop of the pore pressure (kPa)
    there; the soil above the new water table stays saturated ("Ground that moves").
    """
    z, lowered = water_table(sc), any(st.kind == "groundwater" for st in sc.stages)
    return PressureBC(groups.GROUND if z is None else None, -GAMMA_W if lowered else 0.0,
                      action=len(ground_actions(sc)) if lowered else None, level=z)


def full_load_area(sc: Scenario, geo: ResolvedGeometry, md: MeshData) -> float:
    """Area (m^2) of the loaded top of the whole foundation (cap top, or every pile head).

    With a cap, its plan area. Without one, the meshed pile heads (polygons slightly smaller
    than circles, so that the resultant is exactly the scenario's load); a symmetry-reduced mesh
    holds 1/2 (one mirror plane) or 1/4 (two) of them. A uniform pressure of total load / this
    area then carries the reduced model's share of the load.
    """
    if sc.cap is not None:
        return sc.cap.size_x_m * sc.cap.size_y_m
    return facet_area(md, loaded_facets(sc, md)) / geo.kept_fraction


def interface_law(sc: Scenario, j: int, mesh_size: float, base: bool = False
                  ) -> PileSoilInterface | None:
    """The pile-soil interface law of soil layer ``j`` (Table 1 parameters of that layer).

    ``k_normal = normal_stiffness_factor * E_layer / h``, ``h`` the element size at the piles
    (the fade at most :data:`FADE_FACTOR`); ``mode = "elastic"``: no viscoplastic slip.
    ``base``: the law of the pile bases, with the layer's ``base_bearing_kPa`` as limit.
    """
    lay = sc.layers[j]
    ip = lay.interface
    if ip is None:
        return None
    opt = sc.interface
    return PileSoilInterface(
        K=ip.K, n=ip.n, R_f=ip.R_f, c=lay.c_kPa, phi_deg=lay.phi_deg,
        eta=1.0 if ip.eta is None else ip.eta,  # an elastic interface has no viscosity
        k_normal=opt.normal_stiffness_factor * lay.E / mesh_size, delta_deg=ip.delta_deg,
        N=opt.N, variant=opt.variant, integrator=opt.integrator,
        viscous=opt.mode == "viscoplastic", bearing=ip.base_bearing_kPa if base else None,
        fade_stiffness=min(opt.normal_stiffness_factor / mesh_size,
                           FADE_FACTOR / FADE_LENGTH_M) * lay.E)


def interface_coupling(sc: Scenario, mesh_size: float, shaft: float = 1.0
                       ) -> InterfaceCoupling | None:
    """The interface coupling (h at the piles ``mesh_size``, ``shaft_factor`` ``shaft``) or None."""
    if sc.interface.mode == "tied":
        return None
    layers = range(len(sc.layers))
    laws = tuple(interface_law(sc, j, mesh_size) for j in layers) \
        + tuple(interface_law(sc, j, mesh_size, base=True) for j in layers)
    return InterfaceCoupling(laws, quadrature=sc.interface.quadrature, shaft_factor=shaft)


def estimate_dofs(md: MeshData, element: str) -> int:
    """Rough global unknown count of the u-p problem (vertices, or Q2 nodes ~ 8 x vertices)."""
    nv = md.mesh.topology.index_map(0).size_global
    return int(nv * (3 * (8 if element == "Q2Q1" else 1) + 1))


def solver_stages(sc: Scenario) -> list[SolverStage]:
    """The scenario's stages as solver stages (load factor 1 = the full cap load).

    Surcharge and groundwater stages are ground stages: surcharge ``i`` ramps its action's
    amplitude from 0 to 1, a groundwater stage the water-table action's amplitude (the
    drawdown so far, m) by its ``drawdown_m``. A load stage ramps the cap actions' amplitudes
    (:mod:`~pilegroup.studies.run.cap_loads`) with its load factor.
    """
    out = []
    total = sc.total_cap_load()
    surcharges = ground_actions(sc)
    caps = stage_amplitudes(sc)
    slot = first_slot(sc)
    amp = [0.0] * (slot + len(used_components(sc)))
    for i, (st, t0, t1) in enumerate(sc.stage_times()):
        if st.kind == "geostatic":
            out.append(SolverStage(st.name, "geostatic"))
        elif st.kind == "installation":
            out.append(SolverStage(st.name, "install"))
        elif st.kind == "capacity":  # at least CAPACITY_STEPS points on the curve
            dt = (t1 - t0) / CAPACITY_STEPS
            out.append(SolverStage(st.name, "capacity", duration=t1 - t0, load_factor=1.0,
                                   dt0=min(dt, sc.numerics.time.dt_initial_day), dt_max=dt))
        elif st.kind == "load":
            lf = st.vertical_kN / total if total > 0 else 0.0  # type: ignore[operator]
            amp[slot:] = caps[i]
            out.append(SolverStage(st.name, "load", duration=t1 - t0, load_factor=lf,
                                   ground=tuple(amp)))
        elif st.kind in ("surcharge", "groundwater"):
            if st.kind == "surcharge":
                amp[surcharges.index(st)] = 1.0
            else:
                amp[-1] += st.drawdown_m  # type: ignore[operator]
            out.append(SolverStage(st.name, "ground", duration=t1 - t0, ground=tuple(amp)))
        else:
            out.append(SolverStage(st.name, "consolidation", duration=t1 - t0))
    return out


def check_runaway(sc: Scenario, settlement_m: float, t: float, load_factor: float,
                  stage: str) -> None:
    """Raise :class:`StepFailure` once the foundation settles more than a pile diameter.

    The small-strain model can keep "carrying" a load far beyond the foundation's capacity by
    settling without bound; a settlement beyond the pile diameter (ten times the usual failure
    criterion of 10 % of it) is taken as the foundation having failed, and the run ends there
    (exit 1, ``summary.json`` status ``failed``) instead of completing. The settlement is the
    foundation's (cap, or mean of the pile heads), so a group of piles of different diameters
    is measured against the smallest diameter: the rule then stops a run no later than the
    thinnest pile's failure and never lets one pile run away unnoticed.
    """
    d = min(sc.piles.diameters)
    what = "pile diameter" if d == max(sc.piles.diameters) else "smallest pile diameter"
    if settlement_m > d:
        raise StepFailure(f"stage {stage!r}: the settlement {settlement_m:.4g} m exceeds the"
                          f" {what} {d:g} m (runaway: the foundation does not carry the load)",
                          t, load_factor, stage)


def time_stepping(sc: Scenario) -> StepControl:
    """The solver's adaptive stepping rules from ``numerics.time`` and ``time.output_days``."""
    t = sc.numerics.time
    return StepControl(dt0=t.dt_initial_day, dt_min=t.dt_min_day, dt_max=t.dt_max_day,
                        grow=t.grow_factor, cut=t.cut_factor, easy_newton=t.easy_newton,
                        milestones=tuple(x for x in sc.time.output_days
                                         if x > sc.time.start_day))


def xdmf_label(symmetry: str) -> str | None:
    """XDMF grid name of a reduced model: the part it holds and how to see the whole.

    The files hold the reduced domain (smaller files; ParaView's Reflect filter about the named
    planes shows the whole foundation); ``None`` (the default name) for the full model.
    """
    planes = PLANES[symmetry]
    if not planes:
        return None
    part = "_".join(f"{a}_ge_0" for a in planes)
    return f"{symmetry}_model_{part}_reflect_about_" + "_and_".join(f"{a}0" for a in planes)


def _step_hook(sc: Scenario, probes: tuple[PileProbe, LoadSettlementCurve, SettlementSeries,
                                            CapacityProbe | None], bar: tqdm
               ) -> Callable[[BiotProblem, float, str], None]:
    """What a run does after every accepted step: record, show progress, check for runaway.

    A capacity stage is not checked for runaway (the failure is its result): its probe
    records the step and applies the stage's own stop rule instead.
    """
    piles, curve, settlement, capacity = probes

    def on_step(problem: BiotProblem, t: float, stage: str) -> None:
        piles.record_step(t)
        curve.record(t, stage)
        w = settlement.probe()
        bar.n = t
        bar.set_postfix_str(f"{stage}, settlement {1000 * w:.2f} mm")
        if capacity is not None and stage == capacity.stage:
            capacity.record(t, stage)
            capacity.check(t, stage)
        else:
            check_runaway(sc, w, t, problem.load_factor, stage)

    return on_step


def _write_stiffness(sc: Scenario, pb: BiotProblem, motion: CapMotion,
                     stages: list[SolverStage], out: Path) -> None:
    """``cap_stiffness.csv`` probed at the run's final state (:mod:`.stiffness`)."""
    K = cap_stiffness(sc, pb, motion, stages)
    if pb.comm.rank == 0:
        write_cap_stiffness(out / STIFFNESS_CSV, K)


def run_coupled(sc: Scenario, geo: ResolvedGeometry, md: MeshData, out: Path,
                preset: str | None = None, resume: dict[str, Any] | None = None
                ) -> RunSummary:
    """Run every stage of ``sc`` on ``md`` (``geo``'s mesh) with its exports; the summary.

    Exports, written at every output time: ``settlement.csv``, the pile tables
    (:class:`~pilegroup.studies.run.pile_probe.PileProbe`,
    :mod:`~pilegroup.studies.run.section_probe`: sections, heads, cap motion), ``gauges.csv``
    (with ``outputs.gauge_depths_m``: :class:`~pilegroup.studies.run.gauge_probe.GaugeProbe`),
    ``results*.xdmf`` (when ``outputs.xdmf``) and ``summary_solver.json`` (``complete: false``
    until the end, then the full run summary; after a :class:`~pilegroup.errors.StepFailure`
    the summary up to the failure, with the message as ``failure``). Checkpoints
    (:class:`~pilegroup.studies.run.checkpoint.Checkpoints`) at every output time, every
    ``outputs.checkpoint_every_min`` and on a stop request (which ends the run with
    :class:`~pilegroup.errors.RunInterrupted`). ``resume``: the manifest of the checkpoint to
    continue from (:func:`~pilegroup.studies.run.checkpoint.check_resume`). With
    ``outputs.cap_stiffness``, ``cap_stiffness.csv`` at the end. The linear solver is closed
    at the end; after a failure only this rank's out-of-core files are emptied.
    """
    t0 = time.perf_counter()
    pb = build_problem(sc, geo, md, preset)
    try:
        data = _run_problem(sc, geo, md, out, pb, resume, t0)
    except BaseException:
        # only this rank's out-of-core files: destroying the solver is collective, and after
        # a failure on one rank the others are elsewhere (the failure then ends every rank)
        pb.linear_solver.abandon()
        raise
    pb.linear_solver.close()
    return data


def _run_problem(sc: Scenario, geo: ResolvedGeometry, md: MeshData, out: Path, pb: BiotProblem,
                 resume: dict[str, Any] | None, t0: float) -> RunSummary:
    """:func:`run_coupled` once the problem is built."""
    settlement = SettlementSeries(pb, loaded_facets(sc, md), out / "settlement.csv")
    piles = PileProbe(sc, geo, pb, out)
    gauges = GaugeProbe(sc, pb, piles, out / GAUGES_CSV) if sc.outputs.gauge_depths_m else None
    ground = GroundProbe(sc, pb, piles, out)
    capacity = CapacityProbe(sc, pb, piles, settlement.probe, out) \
        if sc.capacity_stage is not None else None

    def summary(complete: bool) -> RunSummary:
        return {"complete": complete, "dofs": pb.num_dofs, "centre_pile": piles.centre,
                "interface_mode": sc.interface.mode,
                "symmetry": {"model": geo.symmetry, "reason": geo.reason},
                "element": sc.numerics.element, "preset": pb.linear_solver.preset,
                "gauge_sections": gauges.summary() if gauges is not None else None,
                "neutral_plane": ground.summary(),
                "settlement_m": [{"t_day": t, "stage": s, "settlement_m": w}
                                 for t, s, w in settlement.history],
                "settlement_sign": "positive = downward (compression-positive habit)",
                "resumed_from_day": resume["t_day"] if resume is not None else None,
                "checkpoints": ckpt.written, "wall_s": time.perf_counter() - t0,
                **({"capacity": capacity.result()} if capacity is not None else {})}

    writer = SummaryWriter(out / SOLVER_SUMMARY_JSON, pb.comm, summary)
    curve = LoadSettlementCurve(pb, settlement.probe, sc.total_cap_load(),
                                out / "load_settlement.csv")
    motion = CapMotion(sc, geo, pb, out)
    exports: list[Export] = [settlement, piles, ground, curve, motion,
                             PileSections(sc, geo, pb, piles, out)]
    # the capacity probe after the pile probe, which sets the forces' zero
    exports += [e for e in (capacity, gauges) if e is not None]
    if sc.outputs.xdmf:
        exports.append(XDMFSeries(pb, out / "results.xdmf", xdmf_label(geo.symmetry),
                                  resume=resume is not None))
    exports.append(writer)
    stages = solver_stages(sc)
    ckpt = Checkpoints(out, sc, pb, [st.name for st in stages], exports)
    state = ckpt.restore(resume) if resume is not None else None
    bar = tqdm(total=sc.time.end_day, initial=sc.time.start_day, unit="day", desc=sc.name,
               disable=pb.comm.rank != 0 or os.environ.get("PILEGROUP_PROGRESS") == "0",
               bar_format="{desc}: {n:.3g}/{total:g} day |{bar}| {elapsed}{postfix}")
    on_step = _step_hook(sc, (piles, curve, settlement, capacity), bar)
    try:
        run_log = run_stages(pb, stages, time_stepping(sc), on_step=on_step,
                             geostatic_tol=GEOSTATIC_TOL_M, exports=exports, state=state,
                             boundary=ckpt, t_start=sc.time.start_day)
    except StepFailure as exc:
        load = exc.load_factor * sc.total_cap_load()
        msg = (f"no equilibrium beyond load factor {exc.load_factor:.4g} ({load:.6g} kN) at "
               f"t = {exc.t:.6g} day, {exc}")
        if isinstance(exc.run_log, RunLog):  # the counts and extremes up to the failure
            writer.finish(run_summary(pb, exc.run_log, summary(False) | {"failure": msg}))
        raise StepFailure(msg, exc.t, exc.load_factor, exc.stage, exc.run_log) from exc
    finally:
        bar.close()
    if capacity is not None:
        capacity.finish(run_log.capacity_end)
    if sc.outputs.cap_stiffness:
        _write_stiffness(sc, pb, motion, stages, out)
    data = run_summary(pb, run_log, summary(True))
    writer.finish(data)
    return data
