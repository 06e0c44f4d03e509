"""u–p Biot consolidation on a :class:`~pilegroup.geometry.meshdata.MeshData`.

Physics (design.md §4). Units kN, m, day; tension positive; ``p`` = excess pore pressure,
compression of the water positive; effective stress ``sigma' = sigma + p I`` (Biot coefficient 1,
incompressible grains).

* Momentum (excess-pressure form): ``div(sigma' - p I) + b' = 0`` with ``b' = -(gamma_sat -
  GAMMA_W) e_z`` the buoyant weight (only with ``self_weight``). The geostatic effective stress
  is the law's initial state, in equilibrium with ``b'``; loads act on top of it.
* Mass, backward Euler over ``dt`` (multiplied by dt):
  ``S (p - p_n) + div(u - u_n) - dt div((k/GAMMA_W) grad p) = 0``, ``S = n / K_w``.
  ``dt = 0`` is an undrained step.
* Soil stress and tangent come from the constitutive law at the quadrature points
  (:mod:`.qpstate`); the Jacobian is the consistent tangent.

Discretisation: Q2–Q1 (Taylor–Hood on hexahedra) or Q1–Q1 with the polynomial pressure
projection of Bochev, Dohrmann & Gunzburger (SIAM J. Numer. Anal. 44, 2006) in the form used for
consolidation by White & Borja (Comput. Methods Appl. Mech. Engrg. 197, 2008): the mass balance
gets ``tau * int (dp - Pi0 dp)(q - Pi0 q)`` with ``dp = p - p_n``, ``Pi0`` the cell-wise L2
projection on constants and ``tau = stab_factor / (2 G)``. On parallelepiped cells the value of
a Q1 function at the centroid is its cell mean, so the term is the full-quadrature mass matrix
minus the one-point (centroid) mass matrix.

Fields are kept as a list of blocks ``[u, p]`` assembled as one blocked (monolithic) PETSc matrix,
so further blocks (e.g. a pile displacement on a sub-mesh, joined by interface terms) can be
appended without changing the Newton loop.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pilegroup.solver.errors import ConvergenceError, SolverInputError
from pilegroup.solver.inputs import (
    GAMMA_W,
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    PressureBC,
    RigidPlate,
    SoilMaterial,
    SolverOptions,
    SurfaceLoad,
)
from pilegroup.solver.linsolve import check_reason, create_ksp, get_preset
from pilegroup.solver.qpstate import QuadratureState

SQRT2 = math.sqrt(2.0)


@dataclass
class StepInfo:
    """Outcome of one attempted step."""

    converged: bool
    newton_its: int = 0
    ksp_its: int = 0
    residuals: list[tuple[float, float]] = field(default_factory=list)
    message: str = ""
    seconds: float = 0.0


def eps_mandel(u: Any) -> Any:
    """Mandel strain 6-vector ``(xx, yy, zz, sqrt2 xy, sqrt2 xz, sqrt2 yz)`` of ``u`` (UFL)."""
    import ufl

    e = ufl.sym(ufl.grad(u))
    return ufl.as_vector(
        [e[0, 0], e[1, 1], e[2, 2], SQRT2 * e[0, 1], SQRT2 * e[0, 2], SQRT2 * e[1, 2]]
    )


class BiotProblem:
    """Coupled u–p problem with quadrature-point soil state and its own Newton solver.

    Args:
        md: mesh and tags.
        materials: cell-group name -> :class:`SoilMaterial` or :class:`ElasticSolid`; every
            cell must be covered. With solids, the pressure lives on the soil sub-mesh only
            (``dolfinx.mesh.create_submesh``; forms with ``entity_maps``) and the displacement
            is continuous across (piles tied to the soil).
        disc: element pair.
        displacement_bcs: prescribed displacement components.
        pressure_bcs: prescribed excess pore pressures (drained boundaries).
        loads: surface pressures.
        plates: rigid plates under force control (at most one).
        options: linear solver and Newton options.
        self_weight: apply the buoyant weight (geostatic stress must then balance it).
    """

    def __init__(
        self,
        md: Any,
        materials: Mapping[str, SoilMaterial | ElasticSolid],
        disc: Discretisation | None = None,
        displacement_bcs: Sequence[DisplacementBC] = (),
        pressure_bcs: Sequence[PressureBC] = (),
        loads: Sequence[SurfaceLoad] = (),
        plates: Sequence[RigidPlate] = (),
        options: SolverOptions | None = None,
        self_weight: bool = True,
    ) -> None:
        import basix.ufl
        import ufl
        from dolfinx import default_scalar_type, fem
        from dolfinx.fem import petsc as fpetsc

        self.md = md
        self.mesh = mesh = md.mesh
        self.comm = mesh.comm
        self.disc = disc = disc or Discretisation()
        self.options = options or SolverOptions()
        self.materials = dict(materials)
        self.displacement_bcs = tuple(displacement_bcs)
        self.pressure_bcs = tuple(pressure_bcs)
        self.loads = tuple(loads)
        self.plates = tuple(plates)
        if len(self.plates) > 1:
            raise SolverInputError(f"plates: {len(self.plates)} given; allowed: at most 1")
        self.self_weight = self_weight
        self.timings: dict[str, float] = {"assemble_F": 0.0, "assemble_J": 0.0, "solve": 0.0,
                                          "law": 0.0}
        tdim = mesh.topology.dim
        fdim = tdim - 1
        mesh.topology.create_connectivity(fdim, tdim)

        # --- cells per material group (owned cells)
        imap = mesh.topology.index_map(tdim)
        n_owned = imap.size_local
        groups: dict[str, tuple[Any, np.ndarray]] = {}
        covered = np.zeros(n_owned + imap.num_ghosts, dtype=bool)
        soil_cells = []
        for name, mat in self.materials.items():
            if not isinstance(mat, SoilMaterial | ElasticSolid):
                raise SolverInputError(
                    f"materials[{name!r}] = {type(mat).__name__}; allowed: SoilMaterial, "
                    "ElasticSolid")
            cells = md.cell_tags.find(md.cell_tag(name))
            if isinstance(mat, SoilMaterial):
                soil_cells.append(cells)
            covered[cells] = True
            groups[name] = (mat, cells[cells < n_owned])
        if not covered[:n_owned].all():
            raise SolverInputError(
                f"materials cover {int(covered[:n_owned].sum())} of {n_owned} owned cells; "
                f"cell groups: {sorted(md.cell_names)}"
            )

        # --- spaces and functions
        cell = mesh.basix_cell()
        Ve = basix.ufl.element("Lagrange", cell, disc.u_degree, shape=(3,))
        Qe = basix.ufl.element("Lagrange", cell, 1)
        self.V = V = fem.functionspace(mesh, Ve)
        self.soil_tags = tuple(md.cell_tag(nm) for nm, m in self.materials.items()
                               if isinstance(m, SoilMaterial))
        self.has_solids = len(self.soil_tags) < len(self.materials)
        self.p_mesh = mesh
        self._emaps: list[Any] | None = None
        self._vmap = None
        if self.has_solids:
            from dolfinx import mesh as dmesh

            sc = np.unique(np.concatenate(soil_cells)).astype(np.int32)
            self.p_mesh, emap, self._vmap, _ = dmesh.create_submesh(mesh, tdim, sc)
            self._emaps = [emap]
        self.Q = Q = fem.functionspace(self.p_mesh, Qe)
        self.u = fem.Function(V, name="displacement")
        self.p = fem.Function(Q, name="excess_pore_pressure")
        self.u_n = fem.Function(V)
        self.p_n = fem.Function(Q)
        self.fields = [self.u, self.p]
        self.fields_n = [self.u_n, self.p_n]

        # --- material coefficients (DG0)
        D0 = fem.functionspace(mesh, ("DG", 0))
        self._S = fem.Function(D0)
        self._mob = fem.Function(D0)
        self._gam = fem.Function(D0)
        self._tau = fem.Function(D0)
        self._beta = fem.Function(D0)
        for name, mat in self.materials.items():
            if not isinstance(mat, SoilMaterial):
                continue
            cells = md.cell_tags.find(md.cell_tag(name))
            K, G = mat.elastic_moduli()
            self._S.x.array[cells] = mat.storage
            self._mob.x.array[cells] = mat.mobility
            self._gam.x.array[cells] = mat.gamma_sat - GAMMA_W
            self._tau.x.array[cells] = disc.stab_factor / (2.0 * G)
            self._beta.x.array[cells] = 1.0 / K
        self._layers = self._soil_layers()
        if self.has_solids:
            from dolfinx import mesh as dmesh

            for name, mat in self.materials.items():
                if isinstance(mat, SoilMaterial):
                    continue
                cells = md.cell_tags.find(md.cell_tag(name))
                zc = dmesh.compute_midpoints(mesh, tdim, cells)[:, 2]
                self._gam.x.array[cells] = self._layer_value(zc, 2)

        self.dt = fem.Constant(mesh, default_scalar_type(0.0))
        self.load_factor = 0.0
        qdeg = disc.quadrature_degree
        dxq = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": qdeg})
        # Every other term is integrated with the same Gauss rule (2 * u_degree: exact on
        # affine cells for Q2-Q1 and Q1-Q1 products); UFL's estimate for hexahedra (from the
        # total degree of the tensor-product spaces) would use up to 8x more points.
        md_q = {"quadrature_degree": qdeg}
        if self.has_solids:  # pressure terms on the soil cells only
            dx = ufl.Measure("dx", domain=mesh, subdomain_data=md.cell_tags,
                             metadata=md_q)(self.soil_tags)
        else:
            dx = ufl.Measure("dx", domain=mesh, metadata=md_q)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=md.facet_tags)
        self.qp = QuadratureState(mesh, groups, qdeg, eps_mandel(self.u) - eps_mandel(self.u_n))
        sig, Dt = self.qp.stress, self.qp.tangent

        u, p, u_n, p_n = self.u, self.p, self.u_n, self.p_n
        v, q = ufl.TestFunction(V), ufl.TestFunction(Q)
        du, dp = ufl.TrialFunction(V), ufl.TrialFunction(Q)
        nrm = ufl.FacetNormal(mesh)
        F_u = ufl.inner(sig, eps_mandel(v)) * dxq - p * ufl.div(v) * dx
        if self_weight:
            F_u += self._gam * v[2] * dxq  # every cell: solids carry their buoyant weight too
        self._load_consts = []
        for ld in self.loads:
            c = fem.Constant(mesh, default_scalar_type(0.0))
            self._load_consts.append((ld, c))
            F_u += c * ufl.inner(nrm, v) * ds(md.facet_tag(ld.facet))
        S, mob, dt = self._S, self._mob, self.dt
        F_p = (S * (p - p_n) + ufl.div(u - u_n)) * q * dx + dt * mob * ufl.inner(
            ufl.grad(p), ufl.grad(q)) * dx
        J_pp = S * dp * q * dx + dt * mob * ufl.inner(ufl.grad(dp), ufl.grad(q)) * dx
        self.stabilised = disc.pair == "Q1Q1" and disc.stabilise
        if self.stabilised:
            sd = dict(subdomain_data=md.cell_tags, subdomain_id=self.soil_tags) \
                if self.has_solids else {}
            dx_full = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 2}, **sd)
            dx_one = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 1}, **sd)
            tau = self._tau
            F_p += tau * (p - p_n) * q * dx_full - tau * (p - p_n) * q * dx_one
            J_pp += tau * dp * q * dx_full - tau * dp * q * dx_one
        J_uu = ufl.inner(ufl.dot(Dt, eps_mandel(du)), eps_mandel(v)) * dxq
        J_up = -dp * ufl.div(v) * dx
        J_pu = ufl.div(du) * q * dx
        em = self._emaps
        jo = dict(self.options.jit_options) if self.options.jit_options is not None else None
        self._F_forms = fem.form([F_u, F_p], entity_maps=em, jit_options=jo)
        self._F_u_form = fem.form(F_u, entity_maps=em, jit_options=jo)
        self._Fint_form = fem.form(ufl.inner(sig, eps_mandel(v)) * dxq, jit_options=jo)
        self._J_forms = fem.form([[J_uu, J_up], [J_pu, J_pp]], entity_maps=em, jit_options=jo)
        preset = get_preset(self.options.preset)
        self._P_forms = None
        if preset.fixed_stress:
            # P = J + (fixed-stress mass) on the p block, built as J + M_beta (one axpy)
            self._zero = fem.Constant(mesh, default_scalar_type(0.0))
            zero_uu = self._zero * ufl.inner(du, v) * dx
            self._P_forms = fem.form(
                [[zero_uu, None], [None, self._beta * dp * q * dx]], entity_maps=em,
                jit_options=jo)

        # --- boundary conditions
        self._bcs = []
        self._bcs_zero = []
        self._drain_bcs: set[int] = set()
        self._u_bc_consts: list[tuple[DisplacementBC, Any]] = []
        for bc in self.displacement_bcs:
            if bc.component not in (0, 1, 2):
                raise SolverInputError(f"DisplacementBC.component = {bc.component}; allowed 0-2")
            facets = md.facet_tags.find(md.facet_tag(bc.facet))
            dofs = fem.locate_dofs_topological(V.sub(bc.component), fdim, facets)
            c = fem.Constant(mesh, default_scalar_type(0.0))
            self._u_bc_consts.append((bc, c))
            self._bcs.append(fem.dirichletbc(c, dofs, V.sub(bc.component)))
            self._bcs_zero.append(fem.dirichletbc(default_scalar_type(0.0), dofs,
                                                  V.sub(bc.component)))
        for pbc in self.pressure_bcs:
            if pbc.facet is None:
                qmap = Q.dofmap.index_map
                dofs = np.arange(qmap.size_local + qmap.num_ghosts, dtype=np.int32)
            else:
                facets = md.facet_tags.find(md.facet_tag(pbc.facet))
                dofs = self._pressure_dofs_on(facets)
            bc = fem.dirichletbc(default_scalar_type(pbc.value), dofs, Q)
            bc0 = fem.dirichletbc(default_scalar_type(0.0), dofs, Q)
            self._bcs.append(bc)
            self._bcs_zero.append(bc0)
            if pbc.facet is not None and not pbc.in_undrained_steps:
                self._drain_bcs.update({id(bc), id(bc0)})
        self.plate_U = 0.0
        self._plate = None
        if self.plates:
            pl = self.plates[0]
            facets = md.facet_tags.find(md.facet_tag(pl.facet))
            dofs = fem.locate_dofs_topological(V.sub(pl.component), fdim, facets)
            cU = fem.Constant(mesh, default_scalar_type(0.0))
            cunit = fem.Constant(mesh, default_scalar_type(-1.0))
            self._bcs.append(fem.dirichletbc(cU, dofs, V.sub(pl.component)))
            unit_bc = fem.dirichletbc(cunit, dofs, V.sub(pl.component))
            owned = dofs[dofs < V.dofmap.index_map.size_local * 3]
            self._plate = {"spec": pl, "U": cU, "unit_bcs": self._bcs_zero + [unit_bc],
                           "owned": owned, "db": None}
            self._bcs_zero.append(fem.dirichletbc(default_scalar_type(0.0), dofs,
                                                  V.sub(pl.component)))

        # --- PETSc objects (created once; sparsity reused)
        self.A = fpetsc.create_matrix(self._J_forms)
        self.P = None
        self._Mbeta = None
        if self._P_forms is not None:
            self._Mbeta = fpetsc.create_matrix(self._P_forms)
        spaces = fem.extract_function_spaces(self._F_forms)
        self.b = fpetsc.create_vector(spaces)
        self.x = fpetsc.create_vector(spaces)
        self.dx_vec = fpetsc.create_vector(spaces)
        self._tmp = fpetsc.create_vector(spaces)
        self._spaces = spaces
        self._undrained = False
        self._bc_targets = [(bc, self.u if V._cpp_object.contains(bc.function_space) else self.p)
                            for bc in self._bcs]
        is_u = is_p = nns = None
        if preset.fieldsplit:
            is_u, is_p = self._index_sets()
            nns = self._rigid_body_modes()
        self.ksp = create_ksp(self.comm, self.A, self.P, self.options.prefix,
                              self.options.preset, self.options.overrides, is_u, is_p, nns)
        self._matrix_key: float | None = None  # dt of the assembled matrix (linear reuse)
        self._R_run = np.zeros(2)
        self.qp.initialise({})

    # ------------------------------------------------------------------ sizes and helpers
    def _pressure_dofs_on(self, facets: np.ndarray) -> np.ndarray:
        """Pressure dofs on parent facets (through the vertices when p is on a sub-mesh)."""
        from dolfinx import fem

        fdim = self.mesh.topology.dim - 1
        if not self.has_solids:
            return fem.locate_dofs_topological(self.Q, fdim, facets)
        self.mesh.topology.create_connectivity(fdim, 0)
        f2v = self.mesh.topology.connectivity(fdim, 0)
        pv = np.unique(np.concatenate([f2v.links(f) for f in facets])) if len(facets) \
            else np.zeros(0, dtype=np.int32)
        sv = self._vmap.sub_topology_to_topology(pv.astype(np.int32), inverse=True)
        sv = sv[sv >= 0].astype(np.int32)
        self.p_mesh.topology.create_connectivity(0, self.p_mesh.topology.dim)
        return fem.locate_dofs_topological(self.Q, 0, sv)

    @property
    def num_dofs(self) -> int:
        """Global number of unknowns (u and p)."""
        return int(self.V.dofmap.index_map.size_global * 3 + self.Q.dofmap.index_map.size_global)

    def _index_sets(self) -> tuple[Any, Any]:
        from petsc4py import PETSc

        nu = self.V.dofmap.index_map.size_local * 3
        npr = self.Q.dofmap.index_map.size_local
        r0 = self.A.getOwnershipRange()[0]
        is_u = PETSc.IS().createStride(nu, first=r0, step=1, comm=self.comm)
        is_p = PETSc.IS().createStride(npr, first=r0 + nu, step=1, comm=self.comm)
        is_u.setBlockSize(3)
        return is_u, is_p

    def _rigid_body_modes(self) -> Any:
        """Six rigid-body modes of the displacement space as a PETSc near-nullspace."""
        from dolfinx import la
        from petsc4py import PETSc

        V = self.V
        imap = V.dofmap.index_map
        nloc = imap.size_local
        basis = [la.vector(imap, bs=3, dtype=PETSc.ScalarType) for _ in range(6)]
        x = V.tabulate_dof_coordinates()[:nloc]
        b = [v.array.reshape(-1, 3) for v in basis]
        for i in range(3):
            b[i][:nloc, i] = 1.0
        b[3][:nloc, 0], b[3][:nloc, 1] = -x[:, 1], x[:, 0]
        b[4][:nloc, 0], b[4][:nloc, 2] = x[:, 2], -x[:, 0]
        b[5][:nloc, 2], b[5][:nloc, 1] = x[:, 1], -x[:, 2]
        la.orthonormalize(basis)
        vecs = []
        for v in basis:
            w = PETSc.Vec().createMPI((nloc * 3, PETSc.DECIDE), comm=self.comm)
            w.array[:] = v.array[: nloc * 3]
            vecs.append(w)
        return PETSc.NullSpace().create(vectors=vecs, comm=self.comm)

    def _set_step_constants(self, dt: float, load_factor: float) -> None:
        self.dt.value = dt
        self.load_factor = load_factor
        for ld, c in self._load_consts:
            c.value = ld.pressure * (load_factor if ld.ramp else 1.0)
        for bc, c in self._u_bc_consts:
            c.value = bc.value * (load_factor if bc.ramp else 1.0)

    def _fields_to_x(self, x: Any) -> None:
        from dolfinx.fem.petsc import assign

        assign(self.fields, x)

    def _x_to_fields(self, x: Any) -> None:
        from dolfinx.fem.petsc import assign
        from petsc4py import PETSc

        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        assign(x, self.fields)

    def _block_norms(self, vec: Any) -> np.ndarray:
        off0, _ = vec.getAttr("_blocks")
        a = vec.array_r
        loc = np.array([float(a[off0[i]:off0[i + 1]] @ a[off0[i]:off0[i + 1]]) for i in (0, 1)])
        from mpi4py import MPI

        return np.sqrt(self.comm.allreduce(loc, op=MPI.SUM))

    # ------------------------------------------------------------------ assembly
    def _evaluate_law(self) -> None:
        t0 = time.perf_counter()
        self.qp.evaluate(float(self.dt.value))
        self.timings["law"] += time.perf_counter() - t0

    def _active(self, bcs: list) -> list:
        """The boundary conditions active in the current step (drainage off when undrained)."""
        if not self._undrained:
            return bcs
        return [bc for bc in bcs if id(bc) not in self._drain_bcs]

    def _apply_bc_values(self) -> None:
        """Put the prescribed values into the fields; Newton increments then vanish there."""
        for bc, f in self._bc_targets:
            if not (self._undrained and id(bc) in self._drain_bcs):
                bc.set(f.x.array)

    def _assemble_residual(self) -> None:
        """Residual with zero rows at constrained dofs (their values are already imposed)."""
        from dolfinx.fem import petsc as fpetsc
        from petsc4py import PETSc

        t0 = time.perf_counter()
        b = self.b
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, self._F_forms)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        from dolfinx import fem

        fpetsc.set_bc(b, fem.bcs_by_block(self._spaces, self._active(self._bcs_zero)))
        b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self.timings["assemble_F"] += time.perf_counter() - t0

    def _assemble_matrix(self) -> bool:
        """Assemble J (and P); skipped for linear problems with an unchanged dt."""
        from dolfinx.fem import petsc as fpetsc

        key = float(self.dt.value)
        bcs = self._active(self._bcs)
        if self.qp.linear and self._matrix_key == key:
            return False
        t0 = time.perf_counter()
        self.A.zeroEntries()
        fpetsc.assemble_matrix(self.A, self._J_forms, bcs=bcs, diag=1.0)
        self.A.assemble()
        if self._Mbeta is not None:
            from petsc4py import PETSc

            self._Mbeta.zeroEntries()
            fpetsc.assemble_matrix(self._Mbeta, self._P_forms, bcs=bcs, diag=0.0)
            self._Mbeta.assemble()
            if self.P is None:
                self.P = self.A.duplicate(copy=True)
            else:
                self.A.copy(self.P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
            self.P.axpy(1.0, self._Mbeta, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)
        self.ksp.setOperators(self.A, self.P if self.P is not None else self.A)
        self._matrix_key = key
        if self._plate is not None:
            self._plate["db"] = None
        self.timings["assemble_J"] += time.perf_counter() - t0
        return True

    def _solve(self, rhs: Any, sol: Any) -> int:
        t0 = time.perf_counter()
        self.ksp.solve(rhs, sol)
        its = check_reason(self.ksp, "Newton correction")
        self.timings["solve"] += time.perf_counter() - t0
        return its

    def reaction(self, facet: str, component: int) -> float:
        """Resultant (kN) of the unconstrained momentum residual on a facet group.

        Sums the residual over the dofs of ``component`` on facet group ``facet`` at the current
        state: the reaction of the constraint, ``int sigma_total . n`` over the facets (tension
        positive).
        """
        from dolfinx import fem

        fdim = self.mesh.topology.dim - 1
        facets = self.md.facet_tags.find(self.md.facet_tag(facet))
        dofs = fem.locate_dofs_topological(self.V.sub(component), fdim, facets)
        owned = dofs[dofs < self.V.dofmap.index_map.size_local * 3]
        return self._resultant(owned)

    def _resultant(self, owned: np.ndarray) -> float:
        from dolfinx import fem, la
        from mpi4py import MPI

        vec = fem.assemble_vector(self._F_u_form)
        vec.scatter_reverse(la.InsertMode.add)
        return float(self.comm.allreduce(float(vec.array[owned].sum()), op=MPI.SUM))

    # ------------------------------------------------------------------ the step
    def solve_step(self, dt: float, load_factor: float) -> StepInfo:
        """Solve one backward-Euler step of size ``dt`` (day) at ``load_factor``.

        Starts from the current fields (the committed ones unless a caller changed them).
        Never raises on non-convergence: returns ``StepInfo(converged=False)`` and leaves the
        trial state uncommitted; the caller calls :meth:`commit` or :meth:`rollback`.
        """
        from petsc4py import PETSc

        t_start = time.perf_counter()
        nw = self.options.newton
        self._set_step_constants(dt, load_factor)
        self._undrained = dt == 0.0
        info = StepInfo(converged=False)
        plate = self._plate
        ref = self._R_run.copy()
        ok_inc = False
        self._apply_bc_values()
        self._fields_to_x(self.x)
        try:
            rn, g_plate = self._state_residual(load_factor)
            for it in range(nw.max_it + 1):
                info.residuals.append((float(rn[0]), float(rn[1])))
                if it == 0:
                    ref = np.maximum(ref, rn)
                    # force scale of the u block: the internal force of the current stress
                    # (includes the geostatic state) and the plate force (not in the residual)
                    ref[0] = max(ref[0], self._internal_force_norm())
                    if plate is not None:
                        ref[0] = max(ref[0], abs(plate["spec"].force * load_factor))
                    self._R_run = np.maximum(self._R_run, ref)
                ok_res = np.all(rn <= nw.rtol * ref + nw.atol)
                if plate is not None:
                    fscale = max(abs(plate["spec"].force * load_factor), 1e-30)
                    ok_res = ok_res and abs(g_plate) <= nw.rtol * fscale + nw.atol
                if it >= 1 and (ok_res or ok_inc):
                    info.converged = True
                    break
                if it == nw.max_it:
                    info.message = f"no convergence in {nw.max_it} iterations; |r| = {rn}"
                    break
                self._assemble_matrix()
                info.ksp_its += self._solve(self.b, self.dx_vec)
                dU = self._border_plate(load_factor) if plate is not None else 0.0
                dxn = self._block_norms(self.dx_vec)
                if not np.all(np.isfinite(dxn)):
                    raise ConvergenceError("NaN Newton increment")
                xn = self._block_norms(self.x)
                ok_inc = bool(np.all(dxn <= nw.stol * np.maximum(xn, 1e-300)))
                info.newton_its = it + 1
                # backtracking line search on the scaled residual (only acts when it grows)
                scale = np.maximum(ref, nw.atol)
                gscale = max(abs(plate["spec"].force * load_factor), nw.atol) \
                    if plate is not None else 1.0
                m0 = float(np.sum(rn / scale)) + abs(g_plate) / gscale
                x_old = self.x.copy()
                U_old = self.plate_U - dU
                alpha = 1.0
                for ls in range(nw.line_search + 1):
                    self.x.array[:] = x_old.array_r
                    self.x.axpy(-alpha, self.dx_vec)
                    if plate is not None:
                        self.plate_U = U_old + alpha * dU
                        plate["U"].value = self.plate_U
                    self._x_to_fields(self.x)
                    try:
                        rn, g_plate = self._state_residual(load_factor)
                        m1 = float(np.sum(rn / scale)) + abs(g_plate) / gscale
                    except ConvergenceError:
                        if ls == nw.line_search:
                            raise
                        m1 = np.inf
                    if m1 <= (1.0 - 1e-4 * alpha) * m0 or ls == nw.line_search:
                        break
                    alpha *= 0.5
                x_old.destroy()
        except ConvergenceError as exc:
            info.converged = False
            info.message = str(exc)
        except PETSc.Error as exc:  # pragma: no cover - PETSc failures are reported, not hidden
            info.converged = False
            info.message = f"PETSc error {exc}"
        info.seconds = time.perf_counter() - t_start
        return info

    def _internal_force_norm(self) -> float:
        """Euclidean norm (kN) of the assembled internal force ``int sigma' : eps(v)``."""
        from dolfinx import fem, la
        from mpi4py import MPI

        vec = fem.assemble_vector(self._Fint_form)
        vec.scatter_reverse(la.InsertMode.add)
        n = self.V.dofmap.index_map.size_local * 3
        loc = float(vec.array[:n] @ vec.array[:n])
        return float(np.sqrt(self.comm.allreduce(loc, op=MPI.SUM)))

    def _state_residual(self, load_factor: float) -> tuple[np.ndarray, float]:
        """Evaluate the laws and the residual at the current fields: (block norms, plate gap)."""
        self._evaluate_law()
        if not self.qp.all_finite():
            raise ConvergenceError("NaN/inf stress from the constitutive law "
                                   f"{self.qp.last_error}".rstrip())
        self._assemble_residual()
        rn = self._block_norms(self.b)
        if not np.all(np.isfinite(rn)):
            raise ConvergenceError("NaN residual")
        g = 0.0
        if self._plate is not None:
            g = self._resultant(self._plate["owned"]) - self._plate["spec"].force * load_factor
        return rn, g

    def _border_plate(self, load_factor: float) -> float:
        """Rigid-plate bordering: correct dx so that the plate resultant equals its force.

        ``dx = dx_a + dU * dx_b`` where ``dx_a`` solves with the plate held, ``dx_b`` is the
        response to a unit plate motion; ``dU`` from a secant on the plate resultant (exact
        for linear problems).
        """
        from dolfinx.fem import petsc as fpetsc
        from petsc4py import PETSc

        plate = self._plate
        pl = plate["spec"]
        if plate["db"] is None:
            rhs = self._tmp
            with rhs.localForm() as rl:
                rl.set(0.0)
            unit_bcs = self._active(plate["unit_bcs"])
            bcs1 = self._bcs_by_block_J(unit_bcs)
            fpetsc.apply_lifting(rhs, self._J_forms, bcs=bcs1, alpha=1.0)
            rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
            from dolfinx import fem

            fpetsc.set_bc(rhs, fem.bcs_by_block(fem.extract_function_spaces(self._F_forms),
                                                unit_bcs))
            db = self.dx_vec.duplicate()
            db.setAttr("_blocks", self.dx_vec.getAttr("_blocks"))
            self._solve(rhs, db)
            plate["db"] = db
        db = plate["db"]
        x0 = self.x.copy()
        xa = self.x.copy()
        xa.axpy(-1.0, self.dx_vec)
        self._x_to_fields(xa)
        self._evaluate_law()
        Ra = self._resultant(plate["owned"])
        xb = xa.copy()
        xb.axpy(-1.0, db)
        self._x_to_fields(xb)
        self._evaluate_law()
        Rb = self._resultant(plate["owned"])
        target = pl.force * load_factor
        dU = -(Ra - target) / (Rb - Ra)
        self.dx_vec.axpy(dU, db)
        self.plate_U += dU
        plate["U"].value = self.plate_U
        self._x_to_fields(x0)
        return dU

    def _bcs_by_block_J(self, bcs: Any) -> Any:
        from dolfinx import fem

        return fem.bcs_by_block(fem.extract_function_spaces(self._J_forms, 1), bcs)

    # ------------------------------------------------------------------ state management
    def commit(self) -> None:
        """Adopt the converged step: state committed, ``u_n, p_n`` updated."""
        self.qp.commit()
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            fn.x.array[:] = f.x.array
        self._committed_U = self.plate_U

    def rollback(self) -> None:
        """Return to the last committed step (fields, plate and quadrature state)."""
        self.qp.rollback()
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            f.x.array[:] = fn.x.array
        self.plate_U = getattr(self, "_committed_U", 0.0)
        if self._plate is not None:
            self._plate["U"].value = self.plate_U

    def reset_displacements(self) -> None:
        """Set u (current and committed) to zero, keeping the stress state (after geostatic)."""
        for f in (self.u, self.u_n):
            f.x.array[:] = 0.0
        self.plate_U = 0.0
        self._committed_U = 0.0

    # ------------------------------------------------------------------ initial stress
    def geostatic_stress(self) -> dict[str, np.ndarray]:
        """K0 effective stress at the quadrature points of each group (Mandel, kPa).

        ``sigma'_v(z) = -int_z^{z_top} (gamma_sat - GAMMA_W) dz`` over horizontal layers (the
        groups' elevation ranges, all-reduced), ``sigma'_h = K0 sigma'_v``; ``z_top`` is the
        highest soil elevation (water table at the ground surface). Solids ("wished in place")
        get the stress and buoyant weight of the soil layer they replace (zero above ground).
        """
        out = {}
        for g in self.qp.groups:
            z = g.x[:, 2]
            sv = self._sigma_v(z)
            k0 = (g.material.k0 if isinstance(g.material, SoilMaterial)
                  else self._layer_value(z, 3))
            s = np.zeros((g.n, 6))
            s[:, 0] = s[:, 1] = k0 * sv
            s[:, 2] = sv
            out[g.name] = s
        return out

    def _soil_layers(self) -> list[tuple[float, float, float, float]]:
        """(z_min, z_max, buoyant unit weight, K0) of each soil group, all-reduced."""
        from mpi4py import MPI

        gx = self.mesh.geometry.x
        cdm = self.mesh.geometry.dofmaps[0]
        layers = []
        for name, mat in self.materials.items():
            if not isinstance(mat, SoilMaterial):
                continue
            cells = self.md.cell_tags.find(self.md.cell_tag(name))
            z = gx[cdm[cells].reshape(-1), 2] if cells.size else None
            zmin = self.comm.allreduce(float(z.min()) if z is not None else np.inf, op=MPI.MIN)
            zmax = self.comm.allreduce(float(z.max()) if z is not None else -np.inf, op=MPI.MAX)
            layers.append((zmin, zmax, mat.gamma_sat - GAMMA_W, mat.k0))
        return layers

    def _sigma_v(self, z: np.ndarray) -> np.ndarray:
        """Vertical geostatic effective stress (kPa, negative) at elevations ``z`` (m)."""
        z_top = max(lay[1] for lay in self._layers)
        s = np.zeros_like(z)
        for zmin, zmax, g, _ in self._layers:
            s -= g * np.clip(np.minimum(zmax, z_top) - np.maximum(zmin, z), 0.0, None)
        return s

    def _layer_value(self, z: np.ndarray, k: int) -> np.ndarray:
        """Entry ``k`` of the soil layer containing each elevation (0 outside every layer)."""
        out = np.zeros_like(z)
        for lay in self._layers:
            inside = (z >= lay[0]) & (z <= lay[1])
            out[inside] = lay[k]
        return out

    def set_initial_stress(self, stress0: dict[str, np.ndarray | None]) -> None:
        """Initialise every group's law state with ``stress0[name]`` ((n,6) Mandel kPa)."""
        self.qp.initialise(stress0)

    # ------------------------------------------------------------------ diagnostics
    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude, m (all ranks)."""
        from mpi4py import MPI

        nloc = self.V.dofmap.index_map.size_local
        a = self.u.x.array[: 3 * nloc].reshape(-1, 3)
        loc = float(np.sqrt((a**2).sum(axis=1)).max()) if nloc else 0.0
        return float(self.comm.allreduce(loc, op=MPI.MAX))
