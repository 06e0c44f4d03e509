"""Gauss-point interface quadrature (solver/interface.py GaussInterface): forces, tangent, output;
and the Newton matrix assembled in parts (kept part, flow term, interface tangent) against the
matrix of the whole Jacobian form, with either quadrature.

A 2 x 1 x 1 m box of hexahedra: x < 1 is the "pile", x > 1 the soil in two layers (z < 0.5,
z > 0.5); the plane x = 1 carries the shaft facet groups. The Jacobian is checked against
central finite differences of the assembled monolithic residual of a BiotProblem, serially and
under ``mpirun -n 2`` (the interface plane may then lie on the partition boundary).
"""


import numpy as np
import pytest
import ufl
from dolfinx import fem, la, mesh
from mpi4py import MPI

from pilegroup.errors import ConstitutiveError
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver import (
    BiotProblem,
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    InterfaceCoupling,
    PressureBC,
    SoilMaterial,
    SolverInputError,
)
from pilegroup.solver.interface import NodalInterface
from pilegroup.solver.interface_gauss import GaussInterface
from pilegroup.solver.layout import split_bodies

KN, KT = 5.0e4, 2.0e3  # kPa/m


class CubicSprings:
    """Test law: ``t = t_n + (K + M) d + C d^3`` (componentwise cube), exact tangent.

    ``M`` is a constant non-symmetric coupling, so the tangent is a full 3 x 3 matrix that
    varies from point to point with the jump increment ``d``.
    """

    K = np.diag([KN, KT, KT])
    M = np.array([[0.0, 3.0e2, -1.0e2], [5.0e2, 0.0, 2.0e2], [-4.0e2, 1.0e2, 0.0]])
    C = np.array([4.0e9, 3.0e9, 2.0e9])  # kPa/m^3

    def initial_state(self, n, traction0=None):
        t0 = np.zeros((n, 3)) if traction0 is None else np.asarray(traction0, float)
        return {"traction": t0.copy(), "slip_vp": np.zeros((n, 3)), "detached": np.zeros((n, 1))}

    def update(self, d, state_n, dt):
        t = state_n["traction"] + d @ (self.K + self.M).T + self.C * d**3
        D = np.broadcast_to(self.K + self.M, (len(d), 3, 3)).copy()
        D[:, [0, 1, 2], [0, 1, 2]] += 3.0 * self.C * d**2
        n = len(d)
        return t, {"traction": t, "slip_vp": np.zeros((n, 3)), "detached": np.zeros((n, 1))}, D


def box(comm, n=4) -> MeshData:
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
    fmap = msh.topology.index_map(tdim - 1)
    facets = np.arange(fmap.size_local + fmap.num_ghosts, dtype=np.int32)
    fm = mesh.compute_midpoints(msh, tdim - 1, facets)
    fv = np.zeros(facets.size, dtype=np.int32)
    fv[np.isclose(fm[:, 0], 1.0)] = np.where(fm[np.isclose(fm[:, 0], 1.0), 2] < 0.5, 11, 12)
    fv[np.isclose(fm[:, 0], 0.0)] = 21  # structure end
    fv[np.isclose(fm[:, 0], 2.0)] = 22  # soil end
    fv[np.isclose(fm[:, 1], 0.0) & (fm[:, 0] < 1.0)] = 23  # structure side: has interface nodes
    keep = fv > 0
    ft = mesh.meshtags(msh, tdim - 1, facets[keep], fv[keep])
    return MeshData(msh, ct, ft, {"pile_1": 1, "soil_layer_01": 2, "soil_layer_02": 3},
                    {"shaft_p1_l01": 11, "shaft_p1_l02": 12, "xmin": 21, "xmax": 22,
                     "pile_front": 23})


def _traction0(x, z, m):
    t = np.zeros((z.size, 3))
    t[:, 0] = -10.0 * (1.0 + z)  # linear in z: both quadratures integrate it exactly
    t[:, 1] = 3.0 - 2.0 * z
    t[:, 2] = 1.0
    return t


def _interfaces(comm=MPI.COMM_WORLD):
    md = box(comm)
    split = split_bodies(md)
    Vp = fem.functionspace(split.structure, ("Lagrange", 1, (3,)))
    Vs = fem.functionspace(split.soil, ("Lagrange", 1, (3,)))
    laws = [CubicSprings(), CubicSprings(), None, None]
    return Vp, Vs, [cls(md, split, Vp, Vs, laws, _traction0)
                    for cls in (NodalInterface, GaussInterface)]


def test_gauss_forces_equal_nodal_forces_for_linear_traction():
    """f_a = sum_g N_a w_g |J_g| t_g through T_a = f_a / A_a and the GLL forms: equal to the
    nodal variant's int t phi_a dS when t is linear (both exact)."""
    Vp, Vs, itfs = _interfaces()
    up, us = fem.Function(Vp), fem.Function(Vs)
    vecs = []
    for itf in itfs:
        itf.update(up, us, dt=1.0)  # zero jump: the initial traction
        _, Fs = itf.residual_forms(ufl.TestFunction(Vp), ufl.TestFunction(Vs))
        r = fem.assemble_vector(fem.form(Fs, entity_maps=itf.entity_maps))
        r.scatter_reverse(la.InsertMode.add)
        vecs.append(r.array[: 3 * Vs.dofmap.index_map.size_local].copy())
    scale = np.abs(vecs[0]).max()
    assert scale > 0.1
    np.testing.assert_allclose(vecs[1], vecs[0], rtol=0, atol=1e-12 * scale)
    # resultant normal force on the soil: int -10 (1 + z) dA over x = 1 (area 1) = -15 kN
    fx = MPI.COMM_WORLD.allreduce(float(vecs[1].reshape(-1, 3)[:, 0].sum()), op=MPI.SUM)
    assert fx == pytest.approx(-15.0, rel=1e-12)


def test_gauss_points_weights_and_nodal_output():
    Vp, Vs, (_, itf) = _interfaces()
    comm = MPI.COMM_WORLD
    area = comm.allreduce(sum(float(itf.material_points(m)["weight"].sum()) for m in (0, 1)),
                          op=MPI.SUM)
    assert area == pytest.approx(1.0, rel=1e-12)
    n_pts = comm.allreduce(sum(itf.material_points(m)["weight"].size for m in (0, 1)),
                           op=MPI.SUM)
    assert n_pts == 4 * 16  # 4 x 4 facets, 2 x 2 points each
    for m in (0, 1):
        p = itf.material_points(m)
        assert np.all((p["x"][:, 2] < 0.5) == (m == 0))  # layer groups by the soil cell
        np.testing.assert_allclose(itf.groups[m].R[:, 0], np.tile([1.0, 0, 0],
                                                                      (len(p["x"]), 1)),
                                   atol=1e-12)
        np.testing.assert_allclose(p["state"]["traction"], _traction0(p["x"], p["x"][:, 2], m))
    # area-weighted nodal averages of a linear field are exact at interior nodes; the constant
    # tau2 = 1 is reproduced at every interface node
    f = itf.nodal_fields()
    on = itf.A > 0
    np.testing.assert_allclose(f["shear_traction_circumferential"][on, 0], 1.0, rtol=1e-13)
    z = Vs.tabulate_dof_coordinates()[:, 2]
    inner = on & (z > 1e-9) & (z < 1 - 1e-9)
    np.testing.assert_allclose(f["normal_traction"][inner, 0], -10.0 * (1.0 + z[inner]),
                               rtol=1e-12)


def _problem(quadrature="gauss", pair="Q1Q1", law=None, drained=None):
    md = box(MPI.COMM_WORLD)
    from pilegroup.constitutive.soil import LinearElastic

    soil = SoilMaterial(LinearElastic(1.0e2, 0.3), 1e-3, 0.4, gamma_sat=18.0, K0=0.5)
    bcs = [DisplacementBC(f, c) for f in ("xmin", "xmax") for c in range(3)]
    bcs.append(DisplacementBC("pile_front", 1))
    law = law or CubicSprings()
    laws = (law, law, None, None)
    return BiotProblem(md, {"pile_1": ElasticSolid(1.0e2, 0.2), "soil_layer_01": soil,
                            "soil_layer_02": soil}, Discretisation(pair=pair),
                       displacement_bcs=bcs, pressure_bcs=[PressureBC(drained)],
                       interface=InterfaceCoupling(laws, _traction0, quadrature=quadrature),
                       self_weight=False)


def test_gauss_jacobian_matches_finite_differences():
    from dolfinx.fem import petsc as fpetsc

    pb = _problem()
    assert isinstance(pb.interface, GaussInterface)
    rng = np.random.default_rng(7 + MPI.COMM_WORLD.rank)
    for b in pb.bodies:  # a jump of a few mm: the cubic term changes the tangent by O(1)
        b.u.interpolate(lambda x: np.vstack([2e-3 * np.sin(3 * x[1] + x[2]),
                                             1e-3 * np.cos(2 * x[2] + x[0]),
                                             3e-3 * x[1] * x[2]]) * (1.0 + (x[0] > 1.0)))
    pb.set_step(1.0, 1.0)  # prescribed values into the fields, fields -> pb.x
    x = pb.x  # the problem's own block vector (keeps its block layout)
    x0 = x.array.copy()

    def residual(xa):
        x.array[:] = xa
        pb.layout.x_to_fields(x)
        pb.evaluate_laws()
        pb.assemble_residual()
        return pb.b.array.copy()

    residual(x0)
    pb.assemble_jacobian(force=True)
    v = pb.dx
    v.array[:] = rng.standard_normal(v.array.size)
    fpetsc.set_bc(v, fem.bcs_by_block(pb.spaces, pb.constraints.bcs_zero))  # bc dofs fixed
    Jv = pb.tmp
    pb.A.mult(v, Jv)
    jv, va = Jv.array.copy(), v.array.copy()
    h = 1e-7
    fd = (residual(x0 + h * va) - residual(x0 - h * va)) / (2.0 * h)
    comm = MPI.COMM_WORLD

    def norm(a):
        return np.sqrt(comm.allreduce(float(a @ a), op=MPI.SUM))

    err = norm(fd - jv) / norm(jv)
    print(f"FD check: relative error {err:.3e}")
    assert err < 1e-6, err
    # the interface matrix is what makes it exact: without it the error is O(1)
    pb.interface.has_matrix = False
    residual(x0)
    pb.assemble_jacobian(force=True)
    pb.A.mult(v, Jv)
    without = norm(fd - Jv.array) / norm(jv)
    print(f"FD check without the interface matrix: {without:.3e}")
    assert without > 0.5


def _whole_matrix(pb):
    """The Jacobian's matrix assembled from the whole form ``J`` (plus the Gauss matrix)."""
    from dolfinx.fem import petsc as fpetsc

    bcs = pb.active(pb.constraints.bcs)
    B = pb.A.duplicate()
    B.zeroEntries()
    fpetsc.assemble_matrix(B, pb.J_forms, bcs=bcs, diag=1.0)
    B.assemble()
    if pb.interface is not None and pb.interface.has_matrix:  # the Gauss tangent: not in J
        A, pb.A = pb.A, B
        try:
            pb._add_interface_matrix(bcs)
        finally:
            pb.A = A
    return B


def _matrix_error(pb):
    from petsc4py import PETSc

    B = _whole_matrix(pb)
    scale = B.norm(PETSc.NormType.FROBENIUS)
    B.axpy(-1.0, pb.A)
    return B.norm(PETSc.NormType.FROBENIUS) / scale


@pytest.mark.parametrize("quadrature,pair", [("nodal", "Q1Q1"), ("gauss", "Q1Q1"),
                                             ("nodal", "Q2Q1")])
def test_jacobian_in_parts_is_the_whole_jacobian(quadrature, pair, monkeypatch):
    """Kept part + flow term + interface tangent == the matrix of the whole form, to round-off.

    The kept part is integrated again only when the constraints change or after a checkpoint
    once it was updated; a tangent change in some cells is added over those cells only; the
    interface tangent of the nodal quadrature is inserted node by node (its GLL forms couple
    coincident nodes only).
    """
    pb = _problem(quadrature, pair, drained="xmax")  # the soil's end face drains
    whole = []
    kept = type(pb)._assemble_kept

    def counted(self, bcs):
        whole.append(1)
        kept(self, bcs)

    monkeypatch.setattr(type(pb), "_assemble_kept", counted)
    for b in pb.bodies:  # a jump of a few mm: the cubic law's tangent varies node by node
        b.u.interpolate(lambda x: np.vstack([2e-3 * np.sin(3 * x[1] + x[2]),
                                             1e-3 * np.cos(2 * x[2] + x[0]),
                                             3e-3 * x[1] * x[2]]) * (1.0 + (x[0] > 1.0)))
    pb.set_step(1.0, 1.0)
    pb.evaluate_laws()
    pb.assemble_jacobian()
    assert _matrix_error(pb) < 1e-14 and len(whole) == 1
    # a new trial state: new interface tangent, the kept part as it was
    for b in pb.bodies:
        b.u.x.array[:] *= 1.7
    pb.evaluate_laws()
    pb.assemble_jacobian()
    assert _matrix_error(pb) < 1e-14 and len(whole) == 1
    # the soil's tangent changes in some cells (as where a plastic law yields)
    qp = pb.body("soil").qp
    rng = np.random.default_rng(3 + MPI.COMM_WORLD.rank)
    for g in qp.groups:
        t = qp.tangent.x.array.reshape(-1, 36)[g.dofs].reshape(-1, qp.nqp, 36)
        t[rng.random(len(g.cells)) < 0.3] *= 1.5
        qp._write(g, qp.stress.x.array.reshape(-1, 6)[g.dofs], t.reshape(-1, 36))
    changed = MPI.COMM_WORLD.allreduce(qp.tangent_changes()[0].size, op=MPI.SUM)
    assert changed > 0
    pb.assemble_jacobian()
    assert _matrix_error(pb) < 1e-14 and len(whole) == 1
    assert not qp.tangent_changed  # the change is in the kept part now
    # a step with another size (flow term) keeps it; after a checkpoint (rebuild_kept) it is
    # built anew, being updated; an undrained step (drainage conditions released) builds it
    drained = len(pb.active(pb.constraints.bcs))
    for dt, rebuild, builds in ((0.25, False, 1), (0.5, True, 2), (0.5, True, 2), (0.0, False, 3)):
        pb.set_step(dt, 1.0)
        if rebuild:
            pb.rebuild_kept()
        pb.evaluate_laws()
        pb.assemble_jacobian()
        assert _matrix_error(pb) < 1e-14
        assert len(whole) == builds, dt
    assert len(pb.active(pb.constraints.bcs)) < drained


class FailsOnRankZero(CubicSprings):
    """Raises like a return mapping that does not converge, on rank 0 only."""

    def update(self, d, state_n, dt):
        if MPI.COMM_WORLD.rank == 0 and len(d):
            raise ConstitutiveError("return mapping did not converge in 100 iterations")
        return super().update(d, state_n, dt)


@pytest.mark.parametrize("quadrature", ["nodal", "gauss"])
def test_a_law_failing_on_one_rank_rejects_the_step_everywhere(quadrature):
    pb = _problem(quadrature, law=FailsOnRankZero())
    info = pb.solve_step(1.0, 1.0)  # collective: every rank returns (no hang), none converges
    assert not info.converged
    assert "NaN/inf traction from the interface law" in info.message
    if MPI.COMM_WORLD.rank == 0:
        assert "return mapping did not converge" in info.message
    pb.rollback()


def test_gauss_needs_q1_and_a_valid_name():
    with pytest.raises(SolverInputError, match="quadrature = 'gauss' with pair = 'Q2Q1'"):
        _problem(pair="Q2Q1")
    with pytest.raises(SolverInputError, match=r"quadrature = 'lobatto'; allowed: 'nodal'"):
        InterfaceCoupling((None,), quadrature="lobatto")


@pytest.mark.parametrize("factor", [0.3, 1.2, float("nan")])
def test_a_shaft_factor_off_a_circle_over_its_polygon_is_refused(factor):
    with pytest.raises(SolverInputError, match=r"InterfaceCoupling\.shaft_factor = .*must"):
        InterfaceCoupling((None,), shaft_factor=factor)


@pytest.mark.mpi
def test_interface_gauss_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, timeout=600)  # a dead rank ends the test, never hangs CI


@pytest.mark.parametrize("pair", ["Q1Q1", "Q2Q1"])
def test_jacobian_in_parts_with_one_body(pair):
    """One body on the whole mesh (soil alone, or piles tied to it): a tangent change in some
    cells goes into the kept part over those cells only, as with separate bodies (its term
    over every cell, added at each change, made Newton linear: the strip footing stalled)."""
    from pilegroup.constitutive.soil import MohrCoulomb
    from pilegroup.geometry.box import build_box
    from pilegroup.studies.verification.common import DRAINED, box_bcs, soil_problem

    md = build_box(MPI.COMM_WORLD, (0.0, 2.0), (0.0, 0.5), np.linspace(-2.0, 0.0, 5), 4, 1)
    soil = SoilMaterial(MohrCoulomb(E=1e4, nu=0.3, c=10.0, phi_deg=0.0, psi_deg=0.0), 1e-3, 0.4)
    pb = soil_problem(md, soil, Discretisation(pair=pair), box_bcs((2,)), pressure_bcs=DRAINED)
    pb.set_step(1.0, 1.0)
    pb.evaluate_laws()
    pb.assemble_jacobian()
    assert _matrix_error(pb) < 1e-14
    qp = pb.bodies[0].qp
    rng = np.random.default_rng(5 + MPI.COMM_WORLD.rank)
    for _ in range(3):  # three changes in a row, each in about a third of the cells
        for g in qp.groups:
            t = qp.tangent.x.array.reshape(-1, 36)[g.dofs].reshape(-1, qp.nqp, 36)
            t[rng.random(len(g.cells)) < 0.3] *= 1.5
            qp._write(g, qp.stress.x.array.reshape(-1, 6)[g.dofs], t.reshape(-1, 36))
        assert MPI.COMM_WORLD.allreduce(qp.tangent_changes()[0].size, op=MPI.SUM) > 0
        pb.assemble_jacobian()
        assert _matrix_error(pb) < 1e-14
