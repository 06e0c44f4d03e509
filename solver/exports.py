"""Exports of a run: objects written at every output time by the stage runner.

Protocol (:class:`Export`): built on a problem (set up), ``write(t, stage)`` at each output
time (stage ends and ``StepControl.milestones``; collective), ``close()`` at the end.
:class:`XDMFSeries` (fields for ParaView) and :class:`SummaryWriter` (a JSON summary rewritten
at every output time) live here; the studies add their own (settlement, pile probes).

Everything written states its sign convention: stresses and strains are written **tension
positive** (as used inside the code); the excess pore pressure is compression positive. Units
kN, m, day (displacement m, stress kPa).

Robustness: the XDMF file is closed after every time written (re-opened in append mode for the
next), so an interrupted run leaves a valid ``.xdmf``/``.h5`` pair with every completed time;
``summary.json`` is written to a temporary file and renamed. Rank 0 writes the JSON; all
scalars are all-reduced over ``mesh.comm`` first.
"""

from __future__ import annotations

import resource
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypedDict

import basix.ufl
import h5py
import numpy as np
from dolfinx import fem, io
from dolfinx import mesh as dmesh
from mpi4py import MPI

from pilegroup.constitutive.base import mandel_to_tensor
from pilegroup.errors import OutputError
from pilegroup.fileio import atomic_path, proc_kib, write_json_atomic
from pilegroup.geometry import groups
from pilegroup.solver.qpstate import QuadratureState
from pilegroup.solver.runlog import RunLog

if TYPE_CHECKING:
    from pilegroup.solver.problem import BiotProblem


class Export(Protocol):
    """What the stage runner calls at every output time and at the end of a run."""

    def write(self, t: float, stage: str) -> None:
        """Write the state at output time ``t`` (day) of stage ``stage`` (collective)."""

    def close(self) -> None:
        """Finish (files stay complete after every :meth:`write` anyway)."""


class _MeshSeries:
    """One XDMF file on one mesh: displacement, optional pressure, cell fields of a qp state."""

    def __init__(self, comm: MPI.Comm, path: Path, mesh: dmesh.Mesh,
                 u: fem.Function | None = None, qp: QuadratureState | None = None,
                 p: fem.Function | None = None, resume: bool = False) -> None:
        self.comm, self.path, self.u, self.qp, self.p = comm, path, u, qp, p
        cell = mesh.basix_cell()
        self.u1 = None
        if u is not None:
            V1 = fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, 1, shape=(3,)))
            self.u1 = fem.Function(V1, name=u.name if u.name.startswith("displacement")
                                   else "displacement")
        self.T0 = fem.functionspace(mesh, basix.ufl.element("DG", cell, 0, shape=(3, 3)))
        self.S0 = fem.functionspace(mesh, basix.ufl.element("DG", cell, 0))
        keys: dict[str, int] = {}
        for g in (qp.groups if qp is not None else []):
            for k, n in g.material.law.state_layout().items():
                if n in (1, 6):
                    keys[k] = n
        self.cell_fields = {}
        for k, n in keys.items():
            name = {"stress": "effective_stress", "eps_p": "plastic_strain"}.get(k, k)
            self.cell_fields[k] = fem.Function(self.T0 if n == 6 else self.S0, name=name)
        if not resume:
            with _xdmf(comm, path, "w") as f:
                f.write_mesh(mesh)

    def write(self, t: float) -> None:
        if self.u1 is not None:
            self.u1.interpolate(self.u)
        for key, f in self.cell_fields.items():
            f.x.array[:] = 0.0
            n = 6 if f.function_space is self.T0 else 1
            for cells, avg in self.qp.cell_average(key).values():
                if n == 6:
                    f.x.array.reshape(-1, 9)[cells] = mandel_to_tensor(avg).reshape(-1, 9)
                else:
                    f.x.array[cells] = avg[:, 0]
            f.x.scatter_forward()
        with _xdmf(self.comm, self.path, "a") as f:
            if self.u1 is not None:
                f.write_function(self.u1, t)
            if self.p is not None:
                f.write_function(self.p, t)
            for fn in self.cell_fields.values():
                f.write_function(fn, t)


class XDMFSeries:
    """XDMF time series of a :class:`~pilegroup.solver.problem.BiotProblem`.

    Files (next to ``path``): ``path`` holds the soil (or, with tied piles, the whole mesh):
    ``displacement`` (m, Q1), ``excess_pore_pressure`` (kPa, compression positive, when it
    lives on that mesh), ``effective_stress`` (kPa, tension positive, cell average) and every
    other 1- or 6-component law state (e.g. ``plastic_strain``). ``<stem>_pressure.xdmf``: the
    pressure when it lives on a soil sub-mesh of a tied model. ``<stem>_structure.xdmf``: pile
    and cap displacement and stress (separate fields). ``<stem>_interface.xdmf``: interface
    fields on the pile-surface facets (see :meth:`NodalInterface.nodal_fields`).
    ``label`` names the XDMF grids (ParaView shows it), e.g. the part a reduced model holds.
    ``resume``: continue the files of a run (they are not rewritten; :meth:`restore_state`
    cuts them back to the output times of the checkpoint).
    """

    def __init__(self, problem: BiotProblem, path: str | Path, label: str | None = None,
                 resume: bool = False) -> None:
        self.problem = problem
        self.path = Path(path)
        self.comm = problem.comm
        if label is not None:  # the grid name ParaView shows (e.g. a reduced model's part)
            for msh in {id(m): m for m in [b.mesh for b in problem.bodies]
                        + [problem.p_mesh]}.values():
                msh.name = label
        if self.comm.rank == 0:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self.comm.barrier()
        stem = self.path.stem
        self.series: list[_MeshSeries | _InterfaceSeries] = []
        for i, b in enumerate(problem.bodies):
            path_b = self.path if i == 0 else self.path.with_name(f"{stem}_{b.name}.xdmf")
            p = problem.p if problem.p_mesh is b.mesh else None
            self.series.append(_MeshSeries(self.comm, path_b, b.mesh, b.u, b.qp, p, resume))
        if all(problem.p_mesh is not b.mesh for b in problem.bodies):
            self.series.append(_MeshSeries(self.comm, self.path.with_name(
                f"{stem}_pressure.xdmf"), problem.p_mesh, p=problem.p, resume=resume))
        if problem.interface is not None:
            self.series.append(_InterfaceSeries(problem, self.path.with_name(
                f"{stem}_interface.xdmf"), resume))
        self.times: list[float] = []

    def write(self, t: float, stage: str = "") -> None:
        """Append the current fields at time ``t`` (day); each file is closed after."""
        for s in self.series:
            s.write(t)
        self.times.append(float(t))

    def close(self) -> None:
        """Nothing stays open between writes; kept for the writer protocol."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the output times written."""
        return {"times": list(self.times)}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue after the checkpoint's output times: later times are cut from the files.

        A run killed after writing an output time but before its checkpoint has that time in
        the files already; it is removed (XDMF grids and HDF5 datasets), and written again.
        """
        self.times = [float(t) for t in data["times"]]
        if self.comm.rank == 0:
            for s in self.series:
                trim_xdmf(s.path, len(self.times))
        self.comm.barrier()


@contextmanager
def _xdmf(comm: MPI.Comm, path: Path, mode: str) -> Iterator[io.XDMFFile]:
    """``io.XDMFFile(comm, path, mode)``, its failures raised as ``OutputError``.

    A failure of the file or its HDF5 file is raised as :class:`~pilegroup.errors.OutputError`
    naming the file (on every rank: the XDMF/HDF5 I/O is collective). DOLFINx reports such a
    failure as a ``RuntimeError`` (e.g. "Failed to create HDF5 file."); HDF5 itself also prints
    its error stack on stderr.
    """
    try:
        with io.XDMFFile(comm, str(path), mode) as f:
            yield f
    except RuntimeError as exc:
        target = path.with_suffix(".h5") if "HDF5" in str(exc) else path
        raise OutputError(target, OSError(None, str(exc))) from exc


def trim_xdmf(path: Path, n: int) -> None:
    """Keep the first ``n`` times of every time series in the XDMF file ``path`` (and .h5).

    The HDF5 datasets of the removed times are deleted (unless a kept time uses them).
    """
    ET.register_namespace("xi", "https://www.w3.org/2001/XInclude")
    tree = ET.parse(path)
    removed, kept = set(), set()
    for coll in tree.getroot().iter("Grid"):
        if coll.get("CollectionType") != "Temporal":
            continue
        for i, grid in enumerate(list(coll.findall("Grid"))):
            items = {d.text.strip().split(":", 1)[1] for d in grid.iter("DataItem")
                     if d.get("Format") == "HDF" and d.text}
            (kept if i < n else removed).update(items)
            if i >= n:
                coll.remove(grid)
    if not removed:
        return
    with atomic_path(path) as tmp:
        tree.write(tmp, xml_declaration=True, encoding="utf-8")
    with h5py.File(path.with_suffix(".h5"), "a") as f:
        for name in sorted(removed - kept):
            if name in f:
                del f[name]


class _InterfaceSeries:
    """Interface fields on a facet mesh of the pile surfaces (nodal values, Q1)."""

    def __init__(self, problem: BiotProblem, path: Path, resume: bool = False) -> None:
        itf = problem.interface
        soil = problem.body("soil")
        md = problem.md
        names = [n for n in md.facet_names if groups.is_interface(n)]
        facets = np.unique(np.concatenate(
            [problem.sub_facets(soil, md.facet_tags.find(md.facet_tag(n))) for n in names]))
        tdim = soil.mesh.topology.dim
        fmesh, _, vmap, _ = dmesh.create_submesh(soil.mesh, tdim - 1, facets)
        self.comm, self.path, self.itf = problem.comm, path, itf
        nv = fmesh.topology.index_map(0).size_local + fmesh.topology.index_map(0).num_ghosts
        sub_v = vmap.sub_topology_to_topology(np.arange(nv, dtype=np.int32), inverse=False)
        self.node_of = _vertex_to_dof(soil.V)[sub_v]  # facet-mesh vertex -> soil node
        self.dof_of = _vertex_to_dof_sub(fmesh)
        self.fields: dict[str, Any] = {}
        for key, k in itf.nodal_field_layout().items():
            shape = (k,) if k > 1 else ()
            W = fem.functionspace(fmesh, ("Lagrange", 1, shape))
            self.fields[key] = fem.Function(W, name=key)
        if not resume:
            with _xdmf(self.comm, path, "w") as f:
                f.write_mesh(fmesh)

    def write(self, t: float) -> None:
        vals = self.itf.nodal_fields()
        for key, fn in self.fields.items():
            a = vals[key].reshape(vals[key].shape[0], -1)
            arr = fn.x.array.reshape(-1, a.shape[1])
            arr[self.dof_of] = a[self.node_of]
        with _xdmf(self.comm, self.path, "a") as f:
            for fn in self.fields.values():
                f.write_function(fn, t)


def _vertex_to_dof(V: fem.FunctionSpace) -> np.ndarray:
    """Node (block dof) of each vertex of a Lagrange space.

    Basix numbers a Lagrange cell's dofs by entity, the vertices first in the reference order
    of the cell's vertices, so dof i of a cell is its vertex i for every degree (the Q2
    displacement space's edge, face and interior nodes come after and are not output).
    """
    msh = V.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim, 0)
    c2v = msh.topology.connectivity(tdim, 0)
    nv = msh.topology.index_map(0).size_local + msh.topology.index_map(0).num_ghosts
    out = np.full(nv, -1, dtype=np.int64)
    nc = msh.topology.index_map(tdim).size_local + msh.topology.index_map(tdim).num_ghosts
    if nc == 0:  # a rank without cells of this mesh (e.g. no interface facets)
        return out
    nper = int(c2v.offsets[1] - c2v.offsets[0])
    dm = V.dofmap.list[:nc, :nper]
    out[c2v.array[: nc * nper]] = dm.reshape(-1)
    return out


def _vertex_to_dof_sub(fmesh: dmesh.Mesh) -> np.ndarray:
    return _vertex_to_dof(fem.functionspace(fmesh, ("Lagrange", 1)))


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MB.

    Linux: ``VmHWM`` of ``/proc/self/status``, the high-water mark of this program's own
    address space. ``getrusage``'s ``ru_maxrss`` survives ``execve``: a process started by a
    large parent (``fork`` then ``exec``, e.g. a run launched from a test session of 1 GB)
    reports the parent's size at the fork as its own peak. Elsewhere ``ru_maxrss`` (KiB).
    """
    hwm = proc_kib("/proc/self/status", "VmHWM")
    if hwm is not None:
        return hwm / 1024.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def write_summary(path: str | Path, data: dict[str, Any], comm: MPI.Comm) -> None:
    """Write ``data`` as JSON on rank 0 (atomic rename); every rank returns after it."""
    if comm.rank == 0:
        write_json_atomic(path, data)
    comm.barrier()


class StepHistory(TypedDict):
    """One accepted step in a run summary (``history``)."""

    stage: str
    t: float
    """End of the step, day."""
    dt: float
    """Step size, day (0: an instantaneous, undrained step)."""
    load_factor: float
    newton: int
    ksp: int
    seconds: float


class SolverSummary(TypedDict, total=False):
    """What :func:`run_summary` reports of a run (all-reduced; units in the names)."""

    conventions: dict[str, str]
    """Units and sign conventions of the numbers."""
    created: str
    """Local time of writing, ISO 8601."""
    ranks: int
    dofs: int
    """Unknowns of the whole system."""
    pair: str
    """Element pair, e.g. ``"Q1Q1"``."""
    linear_solver: str
    """The linear-solver preset in use at the end."""
    linear_solver_fallbacks: int
    """Hand-overs to the preset's fallback."""
    peak_rss_mb_per_rank: list[float]
    steps: int
    rejected_steps: int
    alternate_tolerance_steps: int
    """Steps accepted by Newton's alternate tolerance (docs/solver.md, "Newton")."""
    newton_iterations: int
    ksp_iterations: int
    ksp_iterations_max_per_solve: int
    wall_s: float
    """Wall time of the stage loop (largest over the ranks)."""
    timings_s: dict[str, float]
    """Assembly, solve and law-update times (largest over the ranks)."""
    geostatic_max_u_m: float | None
    """Largest displacement of the geostatic equilibrium check."""
    max_displacement_m: float
    max_excess_pore_pressure_kPa: float
    min_excess_pore_pressure_kPa: float
    final_time_day: float
    lu_factorisations: int
    history: list[StepHistory]


def run_summary(problem: BiotProblem, log: RunLog, extra: Mapping[str, Any] | None = None
                ) -> SolverSummary:
    """All-reduced scalars of a run: sizes, steps, Newton/KSP counts, timings, extremes.

    ``extra`` (e.g. a scenario-aware run's own keys) is merged in last.
    """
    comm = problem.comm
    timings = {k: comm.allreduce(v, op=MPI.MAX) for k, v in problem.timings.items()}
    nloc = problem.Q.dofmap.index_map.size_local
    pl = problem.p.x.array[:nloc]
    out: SolverSummary = {
        "conventions": {"units": "kN, m, day (kPa, m/day)", "stress": "tension positive",
                        "excess_pore_pressure": "compression positive"},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
        "ranks": comm.size,
        "dofs": problem.num_dofs,
        "pair": problem.disc.pair,
        "linear_solver": problem.linear_solver.preset,
        "linear_solver_fallbacks": problem.linear_solver.fallbacks,
        "peak_rss_mb_per_rank": comm.allgather(peak_rss_mb()),
        "steps": len(log.steps),
        "rejected_steps": log.rejected,
        "alternate_tolerance_steps": log.alternate,
        "newton_iterations": log.newton_total,
        "ksp_iterations": sum(s.ksp_its for s in log.steps),
        "ksp_iterations_max_per_solve": max((s.ksp_max for s in log.steps), default=0),
        "wall_s": comm.allreduce(log.wall_s, op=MPI.MAX),
        "timings_s": timings,
        "geostatic_max_u_m": log.geostatic_max_u,
        "max_displacement_m": problem.max_displacement(),
        "max_excess_pore_pressure_kPa": comm.allreduce(float(pl.max()) if nloc else -np.inf,
                                                       op=MPI.MAX),
        "min_excess_pore_pressure_kPa": comm.allreduce(float(pl.min()) if nloc else np.inf,
                                                       op=MPI.MIN),
        "final_time_day": log.steps[-1].t if log.steps else 0.0,
        "lu_factorisations": problem.refactorisations,
        "history": [{"stage": s.stage, "t": s.t, "dt": s.dt, "load_factor": s.load_factor,
                     "newton": s.newton_its, "ksp": s.ksp_its, "seconds": s.seconds}
                    for s in log.steps],
    }
    out.update(extra or {})  # type: ignore[typeddict-item]
    return out


class SummaryWriter:
    """A JSON summary rewritten (rank 0, atomically) at every output time.

    ``content(complete)`` gives the data; it is written with ``complete = False`` at every
    output time, so an interrupted run leaves a readable summary of what was done; the final
    summary is written by :meth:`finish`.
    """

    def __init__(self, path: str | Path, comm: MPI.Comm,
                 content: Callable[[bool], dict[str, Any]]) -> None:
        self.path, self.comm, self.content = Path(path), comm, content

    def write(self, t: float, stage: str) -> None:
        """Rewrite the summary (``complete: false``)."""
        if self.comm.rank == 0:
            write_json_atomic(self.path, self.content(False))

    def close(self) -> None:
        """Nothing stays open."""

    def finish(self, data: dict[str, Any]) -> None:
        """Write the final summary ``data`` (collective)."""
        write_summary(self.path, data, self.comm)
