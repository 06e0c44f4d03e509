"""XDMF series and summary.json of a staged run (geostatic, load ramp, consolidation)."""

import json
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

SCRIPT = r'''
import sys
from pathlib import Path
import numpy as np
import pilegroup
from mpi4py import MPI
from pilegroup.constitutive.soil import MohrCoulomb
from pilegroup.geometry.box import build_box
from pilegroup.solver import (BiotProblem, DisplacementBC, PressureBC, SoilMaterial, SolverStage,
                              SummaryWriter, SurfaceLoad, StepControl, XDMFSeries, run_stages,
                              run_summary)

md = build_box(MPI.COMM_WORLD, (0, 1), (0, 1), np.linspace(-2, 0, 5), 2, 2, layer_tops=[-1.0])
law = MohrCoulomb(E=1e4, nu=0.3, c=5.0, phi_deg=25.0)
mats = {n: SoilMaterial(law, 1e-3, 0.4, gamma_sat=18.0) for n in md.cell_names}
bcs = [DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
       DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1), DisplacementBC("bottom", 2)]
pb = BiotProblem(md, mats, displacement_bcs=bcs, pressure_bcs=[PressureBC("ground_surface")],
                 loads=[SurfaceLoad("ground_surface", 80.0)])
stages = [SolverStage("geo", "geostatic"), SolverStage("load", "load", 1.0, 1.0, dt0=0.25),
          SolverStage("cons", "consolidation", 10.0)]
out = Path(sys.argv[1])
series = XDMFSeries(pb, out / "results.xdmf")
writer = SummaryWriter(out / "summary.json", pb.comm,
                       lambda done: {"complete": done, "output_times_day": series.times})
log = run_stages(pb, stages, StepControl(dt0=0.5, milestones=(5.0,)), exports=[series, writer])
writer.finish(run_summary(pb, log, {"complete": True, "output_times_day": series.times}))
'''


def _run(tmp, nproc):
    py = sys.executable
    cmd = [py, "-c", SCRIPT, str(tmp)]
    if nproc > 1:
        cmd = [str(Path(py).parent / "mpirun"), "-n", str(nproc), *cmd]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    return json.loads((tmp / "summary.json").read_text())


def _times(xdmf):
    root = ET.parse(xdmf).getroot()
    return sorted({float(t.get("Value")) for t in root.iter("Time")})


def test_staged_run_writes_xdmf_and_summary(tmp_path):
    s = _run(tmp_path, 1)
    assert s["complete"] and s["output_times_day"] == [0.0, 1.0, 5.0, 11.0]
    assert s["geostatic_max_u_m"] < 1e-9
    assert s["conventions"]["stress"] == "tension positive"
    assert _times(tmp_path / "results.xdmf") == [0.0, 1.0, 5.0, 11.0]
    names = {a.get("Name") for a in ET.parse(tmp_path / "results.xdmf").getroot().iter("Attribute")}
    assert {"displacement", "excess_pore_pressure", "effective_stress", "plastic_strain"} <= names
    assert (tmp_path / "results.h5").stat().st_size > 0
    assert not list(tmp_path.glob("*.tmp"))


@pytest.mark.mpi
def test_staged_run_parallel_matches_serial(tmp_path):
    s1 = _run(tmp_path / "s", 1)
    s2 = _run(tmp_path / "p", 2)
    assert s2["ranks"] == 2
    for k in ("max_displacement_m", "max_excess_pore_pressure_kPa", "newton_iterations",
              "steps"):
        assert s2[k] == pytest.approx(s1[k], rel=1e-8)
    assert np.allclose([h["t"] for h in s1["history"]], [h["t"] for h in s2["history"]])


@pytest.mark.parametrize("degree", [1, 2])
def test_vertex_to_dof_finds_the_node_at_each_vertex(degree):
    # the interface output reads soil nodes at the facet-mesh vertices (Q1 and Q2 displacements)
    from dolfinx import fem
    from dolfinx import mesh as dmesh
    from mpi4py import MPI

    from pilegroup.solver.exports import _vertex_to_dof

    msh = dmesh.create_box(MPI.COMM_WORLD, [[0, 0, 0], [1, 2, 1]], [2, 3, 2],
                           cell_type=dmesh.CellType.hexahedron)
    V = fem.functionspace(msh, ("Lagrange", degree, (3,)))
    node = _vertex_to_dof(V)
    nv = msh.topology.index_map(0).size_local + msh.topology.index_map(0).num_ghosts
    msh.topology.create_connectivity(0, 3)
    vertices = np.arange(nv, dtype=np.int32)
    xv = msh.geometry.x[dmesh.entities_to_geometry(msh, 0, vertices).reshape(-1)]
    assert np.all(node >= 0)
    assert np.allclose(V.tabulate_dof_coordinates()[node], xv, atol=1e-12)
