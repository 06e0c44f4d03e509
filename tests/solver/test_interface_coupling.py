"""Nodal (GLL) interface coupling between two sub-meshes: weights, frames, jump, assembly.

A 2 x 1 x 1 m box: x < 1 is the "pile", x > 1 the soil in two layers (z < 0.5, z > 0.5); the
plane x = 1 carries the shaft facet groups. References are exact (areas, linear fields), so the
tolerances are round-off (1e-12 relative).
"""


import numpy as np
import pytest
import ufl
from dolfinx import fem, la, mesh
from mpi4py import MPI

from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.interface import NodalInterface
from pilegroup.solver.layout import split_bodies

KN, KT = 5.0e4, 2.0e3  # kPa/m


class LinearSprings:
    """Test law: t = diag(KN, KT, KT) [[u]] + t0, constant tangent."""

    def initial_state(self, n, traction0=None):
        t0 = np.zeros((n, 3)) if traction0 is None else np.asarray(traction0, float)
        return {"traction": t0.copy()}

    def update(self, d_jump, state_n, dt):
        K = np.array([KN, KT, KT])
        t = state_n["traction"] + d_jump * K
        return t, {"traction": t}, np.broadcast_to(np.diag(K), (len(d_jump), 3, 3)).copy()


def two_block_mesh(comm, n=4) -> MeshData:
    msh = mesh.create_box(comm, [[0, 0, 0], [2, 1, 1]], [2 * n, n, n], mesh.CellType.hexahedron,
                          ghost_mode=mesh.GhostMode.shared_facet)
    tdim = 3
    imap = msh.topology.index_map(tdim)
    cells = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
    mid = mesh.compute_midpoints(msh, tdim, cells)
    vals = np.where(mid[:, 0] < 1, 1, np.where(mid[:, 2] < 0.5, 2, 3)).astype(np.int32)
    ct = mesh.meshtags(msh, tdim, cells, vals)
    msh.topology.create_entities(tdim - 1)
    msh.topology.create_connectivity(tdim - 1, tdim)
    facets = mesh.locate_entities(msh, tdim - 1, lambda x: np.isclose(x[0], 1.0))
    fmid = mesh.compute_midpoints(msh, tdim - 1, facets)
    fvals = np.where(fmid[:, 2] < 0.5, 11, 12).astype(np.int32)
    order = np.argsort(facets)
    ft = mesh.meshtags(msh, tdim - 1, facets[order], fvals[order])
    return MeshData(msh, ct, ft, {"pile_1": 1, "soil_layer_01": 2, "soil_layer_02": 3},
                    {"shaft_p1_l01": 11, "shaft_p1_l02": 12})


def build(degree, comm=MPI.COMM_WORLD):
    md = two_block_mesh(comm)
    split = split_bodies(md)
    Vp = fem.functionspace(split.structure, ("Lagrange", degree, (3,)))
    Vs = fem.functionspace(split.soil, ("Lagrange", degree, (3,)))
    laws = [LinearSprings(), LinearSprings(), None, None]
    sigma0 = -10.0

    def traction0(x, z, m):
        t = np.zeros((x.shape[0], 3))
        t[:, 0] = sigma0 * (1 + z)
        return t

    return md, split, Vp, Vs, NodalInterface(md, split, Vp, Vs, laws, traction0)


def _owned_sum(values, V):
    n = V.dofmap.index_map.size_local
    return V.mesh.comm.allreduce(float(np.sum(values[:n])), op=MPI.SUM)


@pytest.mark.parametrize("degree", [1, 2])
def test_weights_frames_and_jump(degree):
    md, split, Vp, Vs, itf = build(degree)
    assert split.n_layers == 2
    # total and per-layer areas (exact: 1.0 and 0.5 m^2)
    assert _owned_sum(itf.A, Vs) == pytest.approx(1.0, rel=1e-12)
    assert _owned_sum(itf.W[:, 0], Vs) == pytest.approx(0.5, rel=1e-12)
    assert _owned_sum(itf.W[:, 1], Vs) == pytest.approx(0.5, rel=1e-12)
    for g in itf.groups[:2]:
        np.testing.assert_allclose(g.R[:, 0], np.tile([1.0, 0, 0], (len(g.nodes), 1)),
                                   atol=1e-12)
    # jump of linear fields is exact at the nodes
    up, us = fem.Function(Vp), fem.Function(Vs)
    up.interpolate(lambda x: np.vstack([0.1 * x[2], 0 * x[0], -0.02 + 0 * x[0]]))
    us.interpolate(lambda x: np.vstack([0.3 * x[2], 0.01 * x[1], 0.05 * x[2]]))
    jump = itf.compute_jump(up, us).reshape(-1, 3)
    xyz = Vs.tabulate_dof_coordinates()
    on = itf.A > 0
    expect = np.column_stack([0.2 * xyz[:, 2], 0.01 * xyz[:, 1], 0.05 * xyz[:, 2] + 0.02])
    np.testing.assert_allclose(jump[on], expect[on], atol=1e-13)


@pytest.mark.parametrize("degree", [1, 2])
def test_residual_and_tangent(degree):
    md, split, Vp, Vs, itf = build(degree)
    up, us = fem.Function(Vp), fem.Function(Vs)
    slip, gap = 1e-3, -2e-4
    us.interpolate(lambda x: np.vstack([gap + 0 * x[0], 0 * x[0], slip + 0 * x[0]]))
    itf.update(up, us, dt=1.0)
    vp, vs = ufl.TestFunction(Vp), ufl.TestFunction(Vs)
    Fp, Fs = itf.residual_forms(vp, vs)
    emaps = itf.entity_maps
    rs = fem.assemble_vector(fem.form(Fs, entity_maps=emaps))
    rs.scatter_reverse(la.InsertMode.add)
    rp = fem.assemble_vector(fem.form(Fp, entity_maps=emaps))
    rp.scatter_reverse(la.InsertMode.add)
    rs3 = rs.array.reshape(-1, 3)[: Vs.dofmap.index_map.size_local]
    rp3 = rp.array.reshape(-1, 3)[: Vp.dofmap.index_map.size_local]
    comm = md.mesh.comm
    # resultant shear on the soil = KT * slip * area; normal = int (sigma0 (1+z) + KN gap) dA
    fz = comm.allreduce(float(rs3[:, 2].sum()), op=MPI.SUM)
    fx = comm.allreduce(float(rs3[:, 0].sum()), op=MPI.SUM)
    assert fz == pytest.approx(KT * slip, rel=1e-12)
    assert fx == pytest.approx(-10.0 * 1.5 + KN * gap, rel=1e-12)
    # action and reaction
    assert comm.allreduce(float(rp3[:, 2].sum()), op=MPI.SUM) == pytest.approx(-fz, rel=1e-12)
    # the tangent blocks applied to the jump reproduce the spring part of the residual
    du_p, du_s = ufl.TrialFunction(Vp), ufl.TrialFunction(Vs)
    J = itf.jacobian_forms(du_p, du_s, vp, vs)
    a = fem.form(ufl.action(J[1][1], us), entity_maps=emaps)
    v = fem.assemble_vector(a)
    v.scatter_reverse(la.InsertMode.add)
    v3 = v.array.reshape(-1, 3)[: Vs.dofmap.index_map.size_local]
    assert comm.allreduce(float(v3[:, 2].sum()), op=MPI.SUM) == pytest.approx(KT * slip,
                                                                               rel=1e-12)


@pytest.mark.mpi
def test_interface_coupling_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, timeout=600)  # a dead rank ends the test, never hangs CI
