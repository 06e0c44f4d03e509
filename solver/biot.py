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
    InterfaceCoupling,
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
    residuals: list[tuple[float, ...]] = field(default_factory=list)
    message: str = ""
    seconds: float = 0.0


@dataclass
class Body:
    """One displacement field: the whole mesh (tied piles) or the soil / the structure."""

    name: str
    mesh: Any
    emap: Any  # EntityMap sub-mesh -> parent (None for the parent mesh itself)
    tags: tuple[int, ...]  # parent cell tags of the body
    V: Any
    u: Any
    u_n: Any
    qp: QuadratureState


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
        interface: give piles and cap their own displacement field on the structure sub-mesh,
            joined to the soil (own field on the soil sub-mesh) only by the zero-thickness
            interface (:class:`~pilegroup.solver.interface.NodalInterface`, or
            :class:`~pilegroup.solver.interface.GaussInterface` with ``quadrature="gauss"``);
            ``None`` ties them.
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
        interface: InterfaceCoupling | None = None,
    ) -> None:
        import basix.ufl
        import ufl
        from dolfinx import default_scalar_type, fem
        from dolfinx import mesh as dmesh
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
        if not covered[:n_owned].all():
            raise SolverInputError(
                f"materials cover {int(covered[:n_owned].sum())} of {n_owned} owned cells; "
                f"cell groups: {sorted(md.cell_names)}"
            )
        self.soil_tags = tuple(md.cell_tag(nm) for nm, m in self.materials.items()
                               if isinstance(m, SoilMaterial))
        self.solid_tags = tuple(md.cell_tag(nm) for nm, m in self.materials.items()
                                if not isinstance(m, SoilMaterial))
        self.has_solids = len(self.solid_tags) > 0
        self.coupling = interface
        if interface is not None and not (self.has_solids and self.soil_tags):
            raise SolverInputError("interface coupling needs both solid and soil cell groups")

        # --- bodies: one displacement field on the whole mesh (tied), or soil and structure
        # on their own sub-meshes joined by the interface terms
        cell = mesh.basix_cell()
        Ve = basix.ufl.element("Lagrange", cell, disc.u_degree, shape=(3,))
        Qe = basix.ufl.element("Lagrange", cell, 1)
        qdeg = disc.quadrature_degree
        self.split = None
        if interface is None:
            specs = [("all", mesh, None, self.soil_tags + self.solid_tags)]
            if self.has_solids:
                sc = np.unique(np.concatenate(soil_cells)).astype(np.int32)
                self.p_mesh, p_emap, self._vmap, _ = dmesh.create_submesh(mesh, tdim, sc)
                self._emaps: list[Any] | None = [p_emap]
            else:
                self.p_mesh, self._vmap, self._emaps = mesh, None, None
        else:
            from pilegroup.solver.interface import split_bodies

            self.split = split = split_bodies(md)
            specs = [("soil", split.soil, split.soil_map, self.soil_tags),
                     ("structure", split.structure, split.structure_map, self.solid_tags)]
            self.p_mesh, self._vmap = split.soil, split.soil_vertex_map
            self._emaps = [split.soil_map, split.structure_map]
        self.bodies: list[Body] = []
        for bname, bmesh, emap, tags in specs:
            V = fem.functionspace(bmesh, Ve)
            u = fem.Function(V, name=f"displacement_{bname}" if bname != "all"
                             else "displacement")
            u_n = fem.Function(V)
            groups: dict[str, tuple[Any, np.ndarray]] = {}
            for name, mat in self.materials.items():
                if md.cell_tag(name) not in tags:
                    continue
                cells = md.cell_tags.find(md.cell_tag(name))
                cells = cells[cells < n_owned]
                if emap is not None:
                    cells = emap.sub_topology_to_topology(cells, inverse=True).astype(np.int32)
                groups[name] = (mat, cells)
            qp = QuadratureState(bmesh, groups, qdeg, eps_mandel(u) - eps_mandel(u_n))
            self.bodies.append(Body(bname, bmesh, emap, tags, V, u, u_n, qp))
        self.V, self.u, self.u_n = self.bodies[0].V, self.bodies[0].u, self.bodies[0].u_n
        self.qp = self.bodies[0].qp  # soil (or all) quadrature state
        self.Q = Q = fem.functionspace(self.p_mesh, Qe)
        self.p = fem.Function(Q, name="excess_pore_pressure")
        self.p_n = fem.Function(Q)
        # block order: [u (soil or all), p, u_structure]
        self.fields = [self.u, self.p] + [b.u for b in self.bodies[1:]]
        self.fields_n = [self.u_n, self.p_n] + [b.u_n for b in self.bodies[1:]]
        self._u_blocks = [0] + list(range(2, len(self.fields)))
        self._block_body = {0: self.bodies[0], **{i + 1: b for i, b in
                                                  enumerate(self.bodies) if i > 0}}

        # --- material coefficients (DG0 on the parent mesh)
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
            for name, mat in self.materials.items():
                if isinstance(mat, SoilMaterial):
                    continue
                cells = md.cell_tags.find(md.cell_tag(name))
                zc = dmesh.compute_midpoints(mesh, tdim, cells)[:, 2]
                self._gam.x.array[cells] = self._layer_value(zc, 2)

        self.dt = fem.Constant(mesh, default_scalar_type(0.0))
        self.load_factor = 0.0
        # Every term is integrated with the same Gauss rule (2 * u_degree: exact on affine
        # cells for Q2-Q1 and Q1-Q1 products); UFL's estimate for hexahedra (from the total
        # degree of the tensor-product spaces) would use up to 8x more points.
        md_q = {"quadrature_degree": qdeg}
        dx_all = ufl.Measure("dx", domain=mesh, subdomain_data=md.cell_tags, metadata=md_q)
        dx = dx_all(self.soil_tags) if self.has_solids else \
            ufl.Measure("dx", domain=mesh, metadata=md_q)
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=md.facet_tags)
        nrm = ufl.FacetNormal(mesh)
        u, p, u_n, p_n = self.u, self.p, self.u_n, self.p_n
        q, dp = ufl.TestFunction(Q), ufl.TrialFunction(Q)
        tests = [ufl.TestFunction(b.V) for b in self.bodies]
        trials = [ufl.TrialFunction(b.V) for b in self.bodies]
        nb = len(self.fields)
        F: list[Any] = [None] * nb
        J: list[list[Any]] = [[None] * nb for _ in range(nb)]
        self._Fint_forms = []
        self._facet_body: dict[str, int] = {}
        for b, v, du in zip(self.bodies, tests, trials, strict=True):
            i = self._block_of(b)
            dxb = dx_all(b.tags) if self.has_solids else dx
            sig, Dt = b.qp.stress, b.qp.tangent
            F[i] = ufl.inner(sig, eps_mandel(v)) * dxb
            self._Fint_forms.append(ufl.inner(sig, eps_mandel(v)) * dxb)
            if self_weight:
                F[i] += self._gam * v[2] * dxb  # solids carry their buoyant weight too
            J[i][i] = ufl.inner(ufl.dot(Dt, eps_mandel(du)), eps_mandel(v)) * dxb
        v0, du0 = tests[0], trials[0]
        F[0] += -p * ufl.div(v0) * dx
        self._load_consts = []
        for ld in self.loads:
            c = fem.Constant(mesh, default_scalar_type(0.0))
            self._load_consts.append((ld, c))
            i = self._block_of(self.body_of_facet(ld.facet))
            F[i] += c * ufl.inner(nrm, tests[self._body_index(i)]) * ds(md.facet_tag(ld.facet))
        S, mob, dt = self._S, self._mob, self.dt
        F[1] = (S * (p - p_n) + ufl.div(u - u_n)) * q * dx + dt * mob * ufl.inner(
            ufl.grad(p), ufl.grad(q)) * dx
        J[1][1] = S * dp * q * dx + dt * mob * ufl.inner(ufl.grad(dp), ufl.grad(q)) * dx
        self.stabilised = disc.pair == "Q1Q1" and disc.stabilise
        if self.stabilised:
            sd = dict(subdomain_data=md.cell_tags, subdomain_id=self.soil_tags) \
                if self.has_solids else {}
            dx_full = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 2}, **sd)
            dx_one = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": 1}, **sd)
            tau = self._tau
            F[1] += tau * (p - p_n) * q * dx_full - tau * (p - p_n) * q * dx_one
            J[1][1] += tau * dp * q * dx_full - tau * dp * q * dx_one
        J[0][1] = -dp * ufl.div(v0) * dx
        J[1][0] = ufl.div(du0) * q * dx
        self.interface = None
        if interface is not None:
            self._add_interface_terms(interface, F, J, tests, trials, dp)
        em = self._emaps
        jo = dict(self.options.jit_options) if self.options.jit_options is not None else None
        self._F_forms = fem.form(F, entity_maps=em, jit_options=jo)
        self._F_u_forms = [fem.form(F[self._block_of(b)], entity_maps=em, jit_options=jo)
                           for b in self.bodies]
        self._Fint_forms = [fem.form(f, entity_maps=em, jit_options=jo)
                            for f in self._Fint_forms]
        self._J_forms = fem.form(J, entity_maps=em, jit_options=jo)
        preset = get_preset(self.options.preset)
        self._P_forms = None
        if preset.fixed_stress:
            # P = J + (fixed-stress mass) on the p block, built as J + M_beta (one axpy)
            self._zero = fem.Constant(mesh, default_scalar_type(0.0))
            P = [[None] * nb for _ in range(nb)]
            for b, v, du in zip(self.bodies, tests, trials, strict=True):
                i = self._block_of(b)
                P[i][i] = self._zero * ufl.inner(du, v) * (dx_all(b.tags) if self.has_solids
                                                           else dx)
            P[1][1] = self._beta * dp * q * dx
            self._P_forms = fem.form(P, entity_maps=em, jit_options=jo)

        # --- boundary conditions
        self._bcs = []
        self._bcs_zero = []
        self._drain_bcs: set[int] = set()
        self._u_bc_consts: list[tuple[DisplacementBC, Any]] = []
        self._bc_targets = []
        for bc in self.displacement_bcs:
            if bc.component not in (0, 1, 2):
                raise SolverInputError(f"DisplacementBC.component = {bc.component}; allowed 0-2")
            b = self.body_of_facet(bc.facet)
            dofs = self._facet_dofs(b, bc.facet, bc.component)
            c = fem.Constant(mesh, default_scalar_type(0.0))
            self._u_bc_consts.append((bc, c))
            Vc = b.V.sub(bc.component)
            self._bcs.append(fem.dirichletbc(c, dofs, Vc))
            self._bc_targets.append((self._bcs[-1], b.u))
            self._bcs_zero.append(fem.dirichletbc(default_scalar_type(0.0), dofs, Vc))
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
            self._bc_targets.append((bc, self.p))
            self._bcs_zero.append(bc0)
            if pbc.facet is not None and not pbc.in_undrained_steps:
                self._drain_bcs.update({id(bc), id(bc0)})
        self.plate_U = 0.0
        self._plate = None
        if self.plates:
            pl = self.plates[0]
            b = self.body_of_facet(pl.facet)
            dofs = self._facet_dofs(b, pl.facet, pl.component)
            Vc = b.V.sub(pl.component)
            cU = fem.Constant(mesh, default_scalar_type(0.0))
            cunit = fem.Constant(mesh, default_scalar_type(-1.0))
            self._bcs.append(fem.dirichletbc(cU, dofs, Vc))
            self._bc_targets.append((self._bcs[-1], b.u))
            unit_bc = fem.dirichletbc(cunit, dofs, Vc)
            owned = dofs[dofs < b.V.dofmap.index_map.size_local * 3]
            self._plate = {"spec": pl, "U": cU, "unit_bcs": self._bcs_zero + [unit_bc],
                           "owned": owned, "db": None, "body": self.bodies.index(b)}
            self._bcs_zero.append(fem.dirichletbc(default_scalar_type(0.0), dofs, Vc))
            if self.interface is not None and self.interface.has_matrix:
                # the bordering lifts the plate motion through the forms only
                from mpi4py import MPI

                hit = np.isin(dofs, self.interface.touched_dofs(b.name)).any()
                if self.comm.allreduce(bool(hit), op=MPI.LOR):
                    raise SolverInputError(
                        f"RigidPlate on {pl.facet!r} moves interface nodes; allowed with "
                        "InterfaceCoupling.quadrature = 'nodal' only")

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
        is_u = is_p = nns = None
        if preset.fieldsplit:
            is_u, is_p = self._index_sets()
            nns = self._rigid_body_modes()
        self.ksp = create_ksp(self.comm, self.A, self.P, self.options.prefix,
                              self.options.preset, self.options.overrides, is_u, is_p, nns)
        self._matrix_key: float | None = None  # dt of the assembled matrix (linear reuse)
        self.refactorisations = 0  # LU factorisations with a reuse preset
        self._reusing = False
        self._factor_undrained: bool | None = None  # constraint set of the kept factorisation
        self._itf_is: Any = None  # block index sets for the interface's own matrix (Gauss)
        self._R_run = np.zeros(len(self.fields))
        for b in self.bodies:
            b.qp.initialise({})

    def _block_of(self, body: Body) -> int:
        """Block index of a body's displacement (0 for the first body, 2, 3, ... after p)."""
        i = self.bodies.index(body)
        return 0 if i == 0 else i + 1

    def _body_index(self, block: int) -> int:
        return 0 if block == 0 else block - 1

    def body_of_facet(self, name: str) -> Body:
        """The body whose cells carry the facet group ``name`` (collective)."""
        from mpi4py import MPI

        if len(self.bodies) == 1:
            return self.bodies[0]
        md = self.md
        facets = md.facet_tags.find(md.facet_tag(name))
        f2c = self.mesh.topology.connectivity(self.mesh.topology.dim - 1,
                                              self.mesh.topology.dim)
        cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int32)
        counts = np.array([int(np.sum(self.split.is_structure[cells] == (b.name == "structure")))
                           for b in self.bodies])
        counts = self.comm.allreduce(counts, op=MPI.SUM)
        return self.bodies[int(np.argmax(counts))]

    def _facet_dofs(self, body: Body, name: str, component: int) -> np.ndarray:
        """Dofs of ``component`` of ``body``'s displacement on the parent facet group ``name``."""
        from dolfinx import fem

        fdim = self.mesh.topology.dim - 1
        facets = self.md.facet_tags.find(self.md.facet_tag(name))
        if body.emap is not None:
            facets = self.sub_facets(body, facets)
        return fem.locate_dofs_topological(body.V.sub(component), fdim, facets)

    def sub_facets(self, body: Body, facets: np.ndarray) -> np.ndarray:
        """Parent facets -> facets of ``body``'s sub-mesh (through an adjacent body cell).

        ``create_submesh`` keeps each cell's vertex order, so a facet has the same local index
        in the parent cell and in its sub-mesh copy.
        """
        tdim = self.mesh.topology.dim
        self.mesh.topology.create_connectivity(tdim, tdim - 1)
        body.mesh.topology.create_connectivity(tdim, tdim - 1)
        body.mesh.topology.create_connectivity(tdim - 1, tdim)
        f2c = self.mesh.topology.connectivity(tdim - 1, tdim)
        c2f = self.mesh.topology.connectivity(tdim, tdim - 1)
        sc2f = body.mesh.topology.connectivity(tdim, tdim - 1)
        out = []
        for k in range(2):  # each facet has one or two cells; take one inside the body
            has = (f2c.offsets[facets + 1] - f2c.offsets[facets]) > k
            f = facets[has]
            c = f2c.array[f2c.offsets[f] + k]
            sc = body.emap.sub_topology_to_topology(c.astype(np.int32), inverse=True)
            inside = sc >= 0
            for fi, ci, si in zip(f[inside], c[inside], sc[inside], strict=True):
                lf = int(np.flatnonzero(c2f.links(ci) == fi)[0])
                out.append(sc2f.links(si)[lf])
        return np.unique(np.array(out, dtype=np.int32))

    def _add_interface_terms(self, coupling: InterfaceCoupling, F: list, J: list,
                             tests: list, trials: list, dp: Any) -> None:
        """Interface traction (law + excess pore pressure) between structure and soil.

        The law gives the effective traction ``t'``; the total traction on the pile is
        ``t' - p n`` (``n`` the structure's outward normal, ``p`` the excess pore pressure on
        the soil side), so the residuals get ``-int (t' - p n) . v_str`` and
        ``+int (t' - p n) . v_soil`` over the pile surfaces.
        """
        import ufl

        from pilegroup.solver.interface import GaussInterface, NodalInterface

        soil, struct = self.bodies
        traction0 = coupling.traction0 or self._interface_traction0
        if coupling.quadrature == "gauss" and self.disc.u_degree != 1:
            raise SolverInputError(
                f"InterfaceCoupling.quadrature = 'gauss' with pair = {self.disc.pair!r}; "
                "allowed: pair 'Q1Q1' (or quadrature 'nodal')")
        cls = GaussInterface if coupling.quadrature == "gauss" else NodalInterface
        self.interface = itf = cls(self.md, self.split, struct.V, soil.V, list(coupling.laws),
                                   traction0)
        i_s, i_t = self._block_of(soil), self._block_of(struct)
        v_s, v_t = tests[0], tests[1]
        du_s, du_t = trials[0], trials[1]
        r_t, r_s = itf.residual_forms(v_t, v_s)
        n = ufl.FacetNormal(self.mesh)("+")
        dS = itf.dS(1) + itf.dS(2)
        F[i_t] += r_t + self.p("-") * ufl.inner(n, v_t("+")) * dS
        F[i_s] += r_s - self.p("-") * ufl.inner(n, v_s("-")) * dS
        Ji = itf.jacobian_forms(du_t, du_s, v_t, v_s)
        J[i_t][i_t] += Ji[0][0]
        J[i_t][i_s] = Ji[0][1]
        J[i_s][i_t] = Ji[1][0]
        J[i_s][i_s] += Ji[1][1]
        J[i_s][1] += -dp("-") * ufl.inner(n, v_s("-")) * dS
        J[i_t][1] = dp("-") * ufl.inner(n, v_t("+")) * dS

    def _interface_traction0(self, z: np.ndarray, m: int) -> np.ndarray:
        """In-situ local traction of interface group ``m`` at heights ``z`` (kPa)."""
        L = self.split.n_layers
        sv = self._sigma_v(z)
        t = np.zeros((z.size, 3))
        if m < L:
            mat = self.materials.get(f"soil_layer_{m + 1:02d}")
            k0 = mat.k0 if isinstance(mat, SoilMaterial) else self._layer_value(z, 3)
            t[:, 0] = k0 * sv
        else:
            t[:, 0] = sv
        return t

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
        return int(sum(b.V.dofmap.index_map.size_global * 3 for b in self.bodies)
                   + self.Q.dofmap.index_map.size_global)

    def _index_sets(self) -> tuple[Any, Any]:
        from petsc4py import PETSc

        sizes = [f.function_space.dofmap.index_map.size_local
                 * f.function_space.dofmap.index_map_bs for f in self.fields]
        offs = self.A.getOwnershipRange()[0] + np.concatenate([[0], np.cumsum(sizes)])
        u_rows = np.concatenate([np.arange(offs[i], offs[i + 1]) for i in self._u_blocks])
        is_u = PETSc.IS().createGeneral(u_rows.astype(PETSc.IntType), comm=self.comm)
        is_p = PETSc.IS().createStride(sizes[1], first=int(offs[1]), step=1, comm=self.comm)
        is_u.setBlockSize(3)
        return is_u, is_p

    def _rigid_body_modes(self) -> Any:
        """Six rigid-body modes of the displacement space as a PETSc near-nullspace."""
        from dolfinx import la
        from petsc4py import PETSc

        x = np.concatenate([b.V.tabulate_dof_coordinates()[:b.V.dofmap.index_map.size_local]
                            for b in self.bodies])
        nloc = x.shape[0]
        imap = _local_index_map(self.comm, nloc)
        basis = [la.vector(imap, bs=3, dtype=PETSc.ScalarType) for _ in range(6)]
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
        loc = np.array([float(a[off0[i]:off0[i + 1]] @ a[off0[i]:off0[i + 1]])
                        for i in range(len(self.fields))])
        from mpi4py import MPI

        return np.sqrt(self.comm.allreduce(loc, op=MPI.SUM))

    # ------------------------------------------------------------------ assembly
    def _evaluate_law(self) -> None:
        t0 = time.perf_counter()
        dt = float(self.dt.value)
        for b in self.bodies:
            b.qp.evaluate(dt)
        if self.interface is not None:
            self.interface.update(self.bodies[1].u, self.bodies[0].u, dt)
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
        if self._linear() and self._matrix_key == key:
            return False
        t0 = time.perf_counter()
        self.A.zeroEntries()
        fpetsc.assemble_matrix(self.A, self._J_forms, bcs=bcs, diag=1.0)
        self.A.assemble()
        if self.interface is not None and self.interface.has_matrix:
            self._add_interface_matrix(bcs)
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

    def _add_interface_matrix(self, bcs: list) -> None:
        """Add the interface's own (non-form) tangent to ``A`` (Gauss-point quadrature)."""
        from dolfinx import fem
        from dolfinx.cpp.la.petsc import create_index_sets

        if self._itf_is is None:
            self._itf_is = create_index_sets(
                [(V.dofmap.index_map, V.dofmap.index_map_bs) for V in self._spaces])
        i_s, i_t = self._block_of(self.bodies[0]), self._block_of(self.bodies[1])
        by_block = fem.bcs_by_block(self._spaces, bcs)

        def constrained(i: int) -> np.ndarray:
            return np.concatenate([bc.dof_indices()[0] for bc in by_block[i]]
                                  + [np.zeros(0, np.int32)])

        self.interface.add_jacobian(self.A, self._itf_is[i_s], self._itf_is[i_t],
                                    constrained(i_s), constrained(i_t))

    def _solve(self, rhs: Any, sol: Any) -> int:
        """Solve with the KSP; with a reused factorisation, refactor when it has gone stale.

        Presets with ``reuse_factor_its`` keep the last LU factorisation as the preconditioner
        of GMRES across Newton iterations and steps (the matrix itself is always the current
        Jacobian, so Newton stays exact); a solve that needs more than ``reuse_factor_its``
        iterations, or fails, triggers a new factorisation (and a re-solve when it failed).
        A factorisation made under another set of constraints (undrained steps release the
        drainage conditions) is not tried at all: it is refactored at once.
        """
        t0 = time.perf_counter()
        limit = get_preset(self.options.preset).reuse_factor_its
        pc = self.ksp.getPC()
        if limit and self._reusing and self._factor_undrained != self._undrained:
            self._set_reuse(pc, False)
        self.ksp.solve(rhs, sol)
        if limit and self.ksp.getConvergedReason() < 0 and self._reusing:
            self._set_reuse(pc, False)  # stale factorisation: refactor and solve again
            self.ksp.solve(rhs, sol)
        its = check_reason(self.ksp, "Newton correction")
        if limit:
            if not self._reusing:
                self.refactorisations += 1
                self._factor_undrained = self._undrained
            self._set_reuse(pc, its <= limit)
        self.timings["solve"] += time.perf_counter() - t0
        return its

    def _set_reuse(self, pc: Any, reuse: bool) -> None:
        pc.setReusePreconditioner(reuse)
        self._reusing = reuse

    def reaction(self, facet: str, component: int) -> float:
        """Resultant (kN) of the unconstrained momentum residual on a facet group.

        Sums the residual over the dofs of ``component`` on facet group ``facet`` at the current
        state: the reaction of the constraint, ``int sigma_total . n`` over the facets (tension
        positive).
        """
        b = self.body_of_facet(facet)
        dofs = self._facet_dofs(b, facet, component)
        owned = dofs[dofs < b.V.dofmap.index_map.size_local * 3]
        return self._resultant(owned, self.bodies.index(b))

    def _linear(self) -> bool:
        """Linear problem: every law linear (interface laws declare ``linear = True``)."""
        lin = all(b.qp.linear for b in self.bodies)
        if self.interface is not None:
            lin = lin and all(getattr(g["law"], "linear", False) for g in self.interface.groups
                              if g["law"] is not None)
        return lin

    def _resultant(self, owned: np.ndarray, body: int = 0) -> float:
        from dolfinx import fem, la
        from mpi4py import MPI

        vec = fem.assemble_vector(self._F_u_forms[body])
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
                info.residuals.append(tuple(float(r) for r in rn))
                if it == 0:
                    ref = np.maximum(ref, rn)
                    # force scale of the u block: the internal force of the current stress
                    # (includes the geostatic state) and the plate force (not in the residual)
                    for i, fn in zip(self._u_blocks, self._internal_force_norms(), strict=True):
                        ref[i] = max(ref[i], fn)
                    if plate is not None:
                        ib = self._block_of(self.bodies[plate["body"]])
                        ref[ib] = max(ref[ib], abs(plate["spec"].force * load_factor))
                    # one force scale for all displacement blocks (one field, kN, as ABAQUS
                    # takes one time-averaged force per field): the bodies exchange their
                    # forces through the interface, whose imbalance shows in both blocks
                    ref[self._u_blocks] = np.max(ref[self._u_blocks])
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

    def _internal_force_norms(self) -> list[float]:
        """Euclidean norms (kN) of each body's internal force ``int sigma' : eps(v)``."""
        from dolfinx import fem, la
        from mpi4py import MPI

        out = []
        for b, form in zip(self.bodies, self._Fint_forms, strict=True):
            vec = fem.assemble_vector(form)
            vec.scatter_reverse(la.InsertMode.add)
            n = b.V.dofmap.index_map.size_local * 3
            loc = float(vec.array[:n] @ vec.array[:n])
            out.append(float(np.sqrt(self.comm.allreduce(loc, op=MPI.SUM))))
        return out

    def _state_residual(self, load_factor: float) -> tuple[np.ndarray, float]:
        """Evaluate the laws and the residual at the current fields: (block norms, plate gap)."""
        self._evaluate_law()
        for b in self.bodies:
            if not b.qp.all_finite():
                raise ConvergenceError("NaN/inf stress from the constitutive law "
                                       f"{b.qp.last_error}".rstrip())
        if self.interface is not None and not self._all_finite(self.interface.T.x.array):
            raise ConvergenceError("NaN/inf traction from the interface law")
        self._assemble_residual()
        rn = self._block_norms(self.b)
        if not np.all(np.isfinite(rn)):
            raise ConvergenceError("NaN residual")
        g = 0.0
        if self._plate is not None:
            g = self._resultant(self._plate["owned"], self._plate["body"]) \
                - self._plate["spec"].force * load_factor
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
        Ra = self._resultant(plate["owned"], plate["body"])
        xb = xa.copy()
        xb.axpy(-1.0, db)
        self._x_to_fields(xb)
        self._evaluate_law()
        Rb = self._resultant(plate["owned"], plate["body"])
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
        for b in self.bodies:
            b.qp.commit()
        if self.interface is not None:
            self.interface.commit()
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            fn.x.array[:] = f.x.array
        self._committed_U = self.plate_U

    def rollback(self) -> None:
        """Return to the last committed step (fields, plate and quadrature state)."""
        for b in self.bodies:
            b.qp.rollback()
        if self.interface is not None:
            self.interface.rollback()
        for f, fn in zip(self.fields, self.fields_n, strict=True):
            f.x.array[:] = fn.x.array
        self.plate_U = getattr(self, "_committed_U", 0.0)
        if self._plate is not None:
            self._plate["U"].value = self.plate_U

    def reset_displacements(self) -> None:
        """Set u (current and committed) to zero, keeping the stress state (after geostatic)."""
        for b in self.bodies:
            b.u.x.array[:] = 0.0
            b.u_n.x.array[:] = 0.0
        if self.interface is not None:
            self.interface.reset_jump()
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
        for g in (g for b in self.bodies for g in b.qp.groups):
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
        for b in self.bodies:
            b.qp.initialise(stress0)

    # ------------------------------------------------------------------ diagnostics
    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude, m (all ranks)."""
        from mpi4py import MPI

        loc = 0.0
        for b in self.bodies:
            nloc = b.V.dofmap.index_map.size_local
            a = b.u.x.array[: 3 * nloc].reshape(-1, 3)
            loc = max(loc, float(np.sqrt((a**2).sum(axis=1)).max()) if nloc else 0.0)
        return float(self.comm.allreduce(loc, op=MPI.MAX))

    def _all_finite(self, a: np.ndarray) -> bool:
        from mpi4py import MPI

        return bool(self.comm.allreduce(bool(np.all(np.isfinite(a))), op=MPI.LAND))


def _local_index_map(comm: Any, n_local: int) -> Any:
    """An index map with ``n_local`` owned entries per rank and no ghosts."""
    from dolfinx import common

    return common.IndexMap(comm, n_local)
