"""Result writers: XDMF time series for ParaView and ``summary.json``.

Everything written states its sign convention: stresses and strains are written **tension
positive** (as used inside the code); the excess pore pressure is compression positive. Units
kN, m, day (displacement m, stress kPa).

Robustness: the XDMF file is closed after every time written (re-opened in append mode for the
next), so an interrupted run leaves a valid ``.xdmf``/``.h5`` pair with every completed time;
``summary.json`` is written to a temporary file and renamed. Rank 0 writes the JSON; all
scalars are all-reduced over ``mesh.comm`` first.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np

from pilegroup.constitutive.base import mandel_to_tensor
from pilegroup.fileio import write_json_atomic


class XDMFSeries:
    """XDMF time series of a :class:`~pilegroup.solver.biot.BiotProblem`.

    Fields: ``displacement`` (m, interpolated to the mesh's Q1 space), ``excess_pore_pressure``
    (kPa, compression positive), ``effective_stress`` (kPa, tension positive, cell average) and
    every other state of the laws with 6 (tensor) or 1 (scalar) components per point, e.g. the
    plastic strain (cell average).
    """

    def __init__(self, problem: Any, path: str | Path) -> None:
        import basix.ufl
        from dolfinx import fem, io

        self.problem = problem
        self.path = Path(path)
        mesh = problem.mesh
        self.comm = mesh.comm
        if self.comm.rank == 0:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        self.comm.barrier()
        cell = mesh.basix_cell()
        self.V1 = fem.functionspace(mesh, basix.ufl.element("Lagrange", cell, 1, shape=(3,)))
        self.u1 = fem.Function(self.V1, name="displacement")
        self.T0 = fem.functionspace(mesh, basix.ufl.element("DG", cell, 0, shape=(3, 3)))
        self.S0 = fem.functionspace(mesh, basix.ufl.element("DG", cell, 0))
        keys: dict[str, int] = {}
        for g in problem.qp.groups:
            for k, n in g.material.law.state_layout().items():
                if n in (1, 6):
                    keys[k] = n
        self.cell_fields = {}
        for k, n in keys.items():
            name = {"stress": "effective_stress", "eps_p": "plastic_strain"}.get(k, k)
            self.cell_fields[k] = fem.Function(self.T0 if n == 6 else self.S0, name=name)
        with io.XDMFFile(self.comm, str(self.path), "w") as f:
            f.write_mesh(mesh)
        # with solids the pressure lives on the soil sub-mesh: its own file
        self.p_path = None
        if problem.p_mesh is not mesh:
            self.p_path = self.path.with_name(self.path.stem + "_pressure.xdmf")
            with io.XDMFFile(self.comm, str(self.p_path), "w") as f:
                f.write_mesh(problem.p_mesh)
        self.times: list[float] = []

    def _update_cell_fields(self) -> None:
        for key, f in self.cell_fields.items():
            f.x.array[:] = 0.0
            n = 6 if f.function_space is self.T0 else 1
            for cells, avg in self.problem.qp.cell_average(key).values():
                if n == 6:
                    vals = mandel_to_tensor(avg).reshape(-1, 9)
                    f.x.array.reshape(-1, 9)[cells] = vals
                else:
                    f.x.array[cells] = avg[:, 0]
            f.x.scatter_forward()

    def write(self, t: float) -> None:
        """Append the current fields at time ``t`` (day)."""
        from dolfinx import io

        self.u1.interpolate(self.problem.u)
        self._update_cell_fields()
        with io.XDMFFile(self.comm, str(self.path), "a") as f:
            f.write_function(self.u1, t)
            if self.p_path is None:
                f.write_function(self.problem.p, t)
            for fn in self.cell_fields.values():
                f.write_function(fn, t)
        if self.p_path is not None:
            with io.XDMFFile(self.comm, str(self.p_path), "a") as f:
                f.write_function(self.problem.p, t)
        self.times.append(float(t))

    def close(self) -> None:
        """Nothing stays open between writes; kept for the writer protocol."""


def write_summary(path: str | Path, data: dict[str, Any], comm: Any) -> None:
    """Write ``data`` as JSON on rank 0 (atomic rename); every rank returns after it."""
    if comm.rank == 0:
        write_json_atomic(path, data)
    comm.barrier()


def run_summary(problem: Any, log: Any, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """All-reduced scalars of a run: sizes, steps, Newton/KSP counts, timings, extremes."""
    from mpi4py import MPI

    comm = problem.comm
    timings = {k: comm.allreduce(v, op=MPI.MAX) for k, v in problem.timings.items()}
    nloc = problem.Q.dofmap.index_map.size_local
    pl = problem.p.x.array[:nloc]
    out = {
        "conventions": {"units": "kN, m, day (kPa, m/day)", "stress": "tension positive",
                        "excess_pore_pressure": "compression positive"},
        "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
        "ranks": comm.size,
        "dofs": problem.num_dofs,
        "pair": problem.disc.pair,
        "linear_solver": problem.options.preset,
        "steps": len(log.steps),
        "rejected_steps": log.rejected,
        "newton_iterations": log.newton_total,
        "ksp_iterations": sum(s.ksp_its for s in log.steps),
        "wall_s": comm.allreduce(log.wall_s, op=MPI.MAX),
        "timings_s": timings,
        "geostatic_max_u_m": log.geostatic_max_u,
        "max_displacement_m": problem.max_displacement(),
        "max_excess_pore_pressure_kPa": comm.allreduce(float(pl.max()) if nloc else -np.inf,
                                                       op=MPI.MAX),
        "min_excess_pore_pressure_kPa": comm.allreduce(float(pl.min()) if nloc else np.inf,
                                                       op=MPI.MIN),
        "final_time_day": log.steps[-1].t if log.steps else 0.0,
        "history": [{"stage": s.stage, "t": s.t, "dt": s.dt, "load_factor": s.load_factor,
                     "newton": s.newton_its, "ksp": s.ksp_its} for s in log.steps],
    }
    out.update(extra or {})
    return out


def run_and_write(problem: Any, stages: Any, ts: Any, out_dir: str | Path,
                  extra: dict[str, Any] | None = None, geostatic_tol: float = 1e-6) -> Any:
    """Run the stages, writing ``results.xdmf`` at every milestone and ``summary.json`` after.

    Milestones are the stage ends and ``ts.milestones``. The summary is also rewritten at each
    milestone (``"complete": false`` until the end), so an interrupted run leaves a readable
    summary of what was done. Returns the :class:`~pilegroup.solver.stepping.RunLog`.
    """
    from pilegroup.solver.stepping import run_stages

    out = Path(out_dir)
    series = XDMFSeries(problem, out / "results.xdmf")

    def on_milestone(pb: Any, t: float, stage: str) -> None:
        series.write(t)
        data = {"complete": False, "last_output_time_day": t, "last_stage": stage,
                "output_times_day": series.times}
        write_summary(out / "summary.json", data, problem.comm)

    log = run_stages(problem, stages, ts, on_milestone=on_milestone, geostatic_tol=geostatic_tol)
    series.close()
    data = run_summary(problem, log, extra)
    data.update({"complete": True, "output_times_day": series.times,
                 "xdmf": str((out / "results.xdmf").name)})
    write_summary(out / "summary.json", data, problem.comm)
    return log
