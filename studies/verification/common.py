"""Helpers shared by the verification cases.

The communicator, point evaluation and sums over ranks, the boundary conditions of the box
meshes of :func:`pilegroup.geometry.box.build_box`, the weightless one-soil box problem, the
step plans that several cases use, and for the interface cases their small meshes (a single
pile in a block, two stacked cubes), the drained soil-and-structure problem and the roughness
of the shaft tractions.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.plan import shaft_factor
from pilegroup.geometry.spec import BlockSpec, GeometrySpec, LayerSpec, MeshSizing, PileSpec
from pilegroup.model import scenario_from_dict
from pilegroup.solver import (
    BiotProblem,
    Discretisation,
    DisplacementBC,
    PressureBC,
    SoilMaterial,
    SolverOptions,
    SolverStage,
)
from pilegroup.solver.probes import eval_points
from pilegroup.studies.results.tables import Table, read_csv
from pilegroup.studies.run.job import run_scenario

if TYPE_CHECKING:  # annotations only
    from pilegroup.solver import ElasticSolid, InterfaceCoupling, RigidPlate, SurfaceLoad
    from pilegroup.solver.interface import NodalInterface

__all__ = ["DRAINED", "TENTHS", "ElasticSoil", "allsum", "box_bcs", "eval_points",
           "load_then_consolidate", "p_along", "shaft_profile_oscillation", "single_pile_mesh",
           "soil_problem", "structure_problem", "two_blocks", "world"]

#: Every pressure dof fixed to zero (drained analysis).
DRAINED = (PressureBC(None),)

#: Output times 0.1, 0.2, ... 0.9 (a stage of one day, or load factor tenths).
TENTHS = tuple(np.round(np.arange(0.1, 1.0, 0.1), 12))


@dataclass(frozen=True)
class ElasticSoil:
    """A linear elastic soil: ``E`` (kPa), ``nu``, permeability ``k`` (m/day), ``porosity``.

    Weightless use only (no unit weight, default K0); the storage includes the water
    compressibility (:attr:`~pilegroup.solver.SoilMaterial.storage`).
    """

    E: float = 1.0e4
    nu: float = 0.3
    k: float = 1.0e-3
    porosity: float = 0.4

    def material(self) -> SoilMaterial:
        """The solver's material."""
        return SoilMaterial(LinearElastic(self.E, self.nu), k_m_per_day=self.k,
                            porosity=self.porosity)


def world() -> MPI.Comm:
    """The communicator of every case that is given none: ``MPI.COMM_WORLD``."""
    return MPI.COMM_WORLD


def allsum[T: (int, float, np.ndarray)](comm: MPI.Comm, x: T) -> T:
    """``x`` summed over the ranks of ``comm`` (on every rank)."""
    return comm.allreduce(x, op=MPI.SUM)


def p_along(problem: BiotProblem, z: np.ndarray, x: float, y: float) -> np.ndarray:
    """Pressure at points ``(x, y, z)`` gathered on every rank (kPa)."""
    return eval_points(problem.p, np.column_stack([np.full_like(z, x), np.full_like(z, y), z]))


def box_bcs(bottom: Sequence[int] = (2,), *extra: DisplacementBC) -> list[DisplacementBC]:
    """Rollers on the four sides of a box, the ``bottom`` components fixed, then ``extra``."""
    return [DisplacementBC(groups.SIDE_XMIN, 0), DisplacementBC(groups.SIDE_XMAX, 0),
            DisplacementBC(groups.SIDE_YMIN, 1), DisplacementBC(groups.SIDE_YMAX, 1),
            *(DisplacementBC(groups.BOTTOM, c) for c in bottom), *extra]


def soil_problem(md: MeshData, soil: SoilMaterial, disc: Discretisation,
                 bcs: Sequence[DisplacementBC], pressure_bcs: Sequence[PressureBC] = (),
                 loads: Sequence[SurfaceLoad] = (), plates: Sequence[RigidPlate] = (),
                 options: SolverOptions | None = None) -> BiotProblem:
    """A weightless problem on a box whose one cell group ``soil_layer_01`` is ``soil``."""
    return BiotProblem(md, {groups.soil_layer(1): soil}, disc, displacement_bcs=bcs,
                       pressure_bcs=pressure_bcs, loads=loads, plates=plates, options=options,
                       self_weight=False)


def load_then_consolidate(t_end: float) -> list[SolverStage]:
    """An instantaneous (undrained) load step, then consolidation under it to ``t_end`` days."""
    return [SolverStage("load", "load", 0.0, 1.0),
            SolverStage("consolidation", "consolidation", t_end)]


def single_pile_mesh(comm: MPI.Comm, layers: tuple[tuple[str, float | None], ...], length: float,
                     size: str) -> tuple[MeshData, float]:
    """A single pile (d = 1 m, head on the ground, no cap) in a small block, by gmsh.

    Returns the mesh and its pile's ``InterfaceCoupling.shaft_factor``.
    """
    h = {"fast": 0.5, "bench": 0.25}[size]
    spec = GeometrySpec(
        block=BlockSpec(6.0, 6.0, length + 3.0),
        layers=tuple(LayerSpec(n, t) for n, t in layers),
        piles=(PileSpec(0.0, 0.0, 1.0, length, 0.0),),
        cap=None,
        sizing=MeshSizing(h_pile=h, n_circ_min=8 if size == "fast" else 16,
                          near_field_margin=1.0, h_far=1.5, dz_surface=h, dz_toe=h,
                          dz_max=2 * h, dz_max_deep=1.5, dz_growth=1.3))
    return build_mesh(spec, comm, cache_dir=False), shaft_factor(spec)


def two_blocks(comm: MPI.Comm) -> MeshData:
    """Two unit cubes stacked: ``pile_1`` (z in [0, 1]) on ``soil_layer_01`` (z in [-1, 0]).

    Facet groups: ``top`` (z = 1), ``struct_side`` and ``soil_side`` (the vertical faces of each
    block), ``bottom`` (z = -1) and the interior ``base_p1`` (z = 0). One cell per block.
    """
    md0 = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.array([-1.0, 0.0, 1.0]), 1, 1,
                    layer_tops=[0.0])
    msh = md0.mesh
    tdim = msh.topology.dim
    fdim = tdim - 1
    msh.topology.create_entities(fdim)
    msh.topology.create_connectivity(fdim, tdim)
    names = {"top": 1, "struct_side": 2, "soil_side": 3, groups.BOTTOM: 4, groups.base(1): 5}
    imap = msh.topology.index_map(fdim)
    facets = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
    mid = dmesh.compute_midpoints(msh, fdim, facets)
    tol = 1e-9
    side = (np.isclose(mid[:, 0], 0.0, atol=tol) | np.isclose(mid[:, 0], 1.0, atol=tol)
            | np.isclose(mid[:, 1], 0.0, atol=tol) | np.isclose(mid[:, 1], 1.0, atol=tol))
    vals = np.zeros(facets.size, dtype=np.int32)
    vals[np.isclose(mid[:, 2], 1.0, atol=tol)] = names["top"]
    vals[np.isclose(mid[:, 2], -1.0, atol=tol)] = names[groups.BOTTOM]
    vals[np.isclose(mid[:, 2], 0.0, atol=tol) & ~side] = names[groups.base(1)]
    vals[side & (mid[:, 2] > 0)] = names["struct_side"]
    vals[side & (mid[:, 2] < 0)] = names["soil_side"]
    keep = vals > 0
    ft = dmesh.meshtags(msh, fdim, facets[keep], vals[keep])
    # build_box numbers layers from the top: 1 = z > 0 (the structure), 2 = z < 0 (the soil)
    return MeshData(msh, md0.cell_tags, ft, {groups.pile(1): 1, groups.soil_layer(1): 2}, names,
                    {"builder": "verification.common.two_blocks"})


def structure_problem(md: MeshData, materials: dict[str, SoilMaterial | ElasticSolid],
                      pair: str, preset: str, prefix: str, coupling: InterfaceCoupling | None,
                      bcs: Sequence[DisplacementBC], loads: Sequence[SurfaceLoad] = (),
                      plates: Sequence[RigidPlate] = (), self_weight: bool = True
                      ) -> BiotProblem:
    """A drained problem (every pressure dof fixed) of soil and structure bodies.

    ``coupling`` joins the structure to the soil by the interface (``None``: tied); the linear
    solver is ``preset`` with the PETSc options prefix ``prefix``.
    """
    return BiotProblem(md, materials, Discretisation(pair=pair), displacement_bcs=bcs,
                       pressure_bcs=DRAINED, loads=loads, plates=plates,
                       options=SolverOptions(preset=preset, prefix=prefix),
                       self_weight=self_weight, interface=coupling)


def shaft_profile_oscillation(itf: NodalInterface, comm: MPI.Comm) -> dict[str, float]:
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


def run_pipeline(doc: dict[str, Any], comm: MPI.Comm, names: Sequence[str]
                 ) -> tuple[dict[str, Table], dict[str, Any]]:
    """Run a scenario (TOML document as a dict) as ``pilegroup run`` does, in a temporary folder.

    Returns the contract tables ``names`` it wrote and its counts (``dofs``, ``newton``,
    ``steps``) with the solver's summary (``summary``) and the mesh's (``mesh``,
    ``mesh/mesh_summary.json``), on every rank; the folder is removed after.
    """
    sc = scenario_from_dict(doc)
    tmp = tempfile.mkdtemp(prefix="pilegroup-case-") if comm.rank == 0 else None
    out = Path(comm.bcast(tmp, root=0))
    progress = os.environ.get("PILEGROUP_PROGRESS")
    os.environ["PILEGROUP_PROGRESS"] = "0"  # no progress bar inside a verification case
    try:
        summary = run_scenario(sc, out, comm=comm)["solver"] or {}
    finally:
        if progress is None:
            del os.environ["PILEGROUP_PROGRESS"]
        else:
            os.environ["PILEGROUP_PROGRESS"] = progress
    tables = mesh = None
    if comm.rank == 0:
        tables = {name: read_csv(out / name) for name in names}
        mesh = json.loads((out / "mesh" / "mesh_summary.json").read_text(encoding="utf-8"))
        shutil.rmtree(out, ignore_errors=True)
    counts = {"dofs": summary.get("dofs", 0), "newton": summary.get("newton_iterations", 0),
              "steps": summary.get("steps", 0), "summary": summary,
              "mesh": comm.bcast(mesh, root=0)}
    return comm.bcast(tables, root=0), counts
