"""u–p Biot consolidation of elastoplastic soil with elastic piles and cap.

Physics and units: docs/model.md (kN, m, day; tension positive; ``p`` = excess pore pressure,
compression of the water positive; effective stress ``sigma' = sigma + p I``). The weak form is
built term by term in :mod:`.forms`; bodies, spaces and block layout in :mod:`.layout`;
boundary conditions and the rigid plate in :mod:`.constraints`; the geostatic state in
:mod:`.geostatic` and :mod:`.initial_state`; the matrices, assembly and linear solves in
:mod:`.algebra`; Newton in :mod:`.newton`.

:class:`BiotProblem` is built in named steps (``_define_*``) and offers the protocol the Newton
driver, the stepper, the exports and the finite-difference Jacobian tests work through:
``set_step``, ``evaluate_laws``, ``assemble_residual``, ``assemble_jacobian``,
``solve_linear``, ``commit``, ``rollback``; plus what outputs need (``bodies``, ``body``,
``body_of_facet``, ``sub_facets``, ``interface``, ``p``).
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence

import numpy as np
from dolfinx import fem, la
from dolfinx import mesh as dmesh
from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import ConvergenceError, SolverInputError
from pilegroup.geometry import groups
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.algebra import MonolithicAlgebra
from pilegroup.solver.constraints import Constraints, RigidPlateControl
from pilegroup.solver.forms import Coefficients, FormBuilder, interface_force_form
from pilegroup.solver.geostatic import SoilColumn
from pilegroup.solver.initial_state import InitialState
from pilegroup.solver.inputs import (
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    FaceAction,
    InstallationExcess,
    InterfaceCoupling,
    PressureBC,
    RigidPlate,
    SoilMaterial,
    SolverOptions,
    SurfaceLoad,
)
from pilegroup.solver.interface import NodalInterface
from pilegroup.solver.interface_gauss import GaussInterface
from pilegroup.solver.layout import BlockLayout, Body
from pilegroup.solver.linsolve import get_preset
from pilegroup.solver.newton import NewtonSolver
from pilegroup.solver.qpstate import QuadratureState
from pilegroup.solver.step_protocol import StepInfo


class BiotProblem(MonolithicAlgebra):
    """Coupled u–p problem with quadrature-point soil state and its own Newton solver.

    Args:
        md: mesh and tags.
        materials: cell-group name -> :class:`SoilMaterial` or :class:`ElasticSolid`; every
            cell must be covered. With solids, the pressure lives on the soil sub-mesh only.
        disc: element pair.
        displacement_bcs: prescribed displacement components.
        pressure_bcs: prescribed excess pore pressures (drained boundaries).
        loads: surface pressures.
        plates: rigid plates under force control (at most one).
        options: linear solver and Newton options.
        self_weight: apply the buoyant weight (geostatic stress must then balance it).
        interface: give piles and cap their own displacement field, joined to the soil only by
            the zero-thickness interface (:class:`NodalInterface`, or :class:`GaussInterface`
            with ``quadrature="gauss"``); ``None`` ties them.
        installation: excess pore pressure the piles' installation leaves around them
            (``None``: none), at the start or at :meth:`install_structure`.
        install_later: the structure is installed by an ``install`` stage: until then it is
            held still and the interface carries its initial traction only (the ground moves
            past the piles' place); needs the interface.
        water_table: elevation (m) of the water table (None: the top of the soil). The soil
            above it is dry: its skeleton carries its total weight and no pore pressure, its
            pressure dofs are held at 0; the mesh must have a surface there. Its drained
            boundary is the caller's (``PressureBC(level=...)``).
        seepage: ``(elevation m, kPa)`` points of a pore pressure at rest above the hydrostatic
            one (:class:`~pilegroup.solver.geostatic.SoilColumn`); the layers that hold it are
            the caller's pressure conditions.
    """

    def __init__(
        self,
        md: MeshData,
        materials: Mapping[str, SoilMaterial | ElasticSolid],
        disc: Discretisation | None = None,
        displacement_bcs: Sequence[DisplacementBC] = (),
        pressure_bcs: Sequence[PressureBC] = (),
        loads: Sequence[SurfaceLoad | FaceAction] = (),
        plates: Sequence[RigidPlate] = (),
        options: SolverOptions | None = None,
        self_weight: bool = True,
        interface: InterfaceCoupling | None = None,
        installation: InstallationExcess | None = None,
        install_later: bool = False,
        water_table: float | None = None,
        seepage: Sequence[tuple[float, float]] = (),
    ) -> None:
        self.md, self.mesh, self.comm = md, md.mesh, md.mesh.comm
        self.disc = disc = disc or Discretisation()
        self.options = options or SolverOptions()
        self.coupling = interface
        self.timings = {"assemble_F": 0.0, "assemble_J": 0.0, "solve": 0.0, "law": 0.0}
        self.layout = BlockLayout(md, materials, disc, separate=interface is not None)
        if install_later and interface is None:
            raise SolverInputError("install_later needs an interface (the piles tied to the"
                                   " soil move with it from the start)")
        self.install_later = install_later
        self.column = SoilColumn(md, materials, installation, water_table, seepage)
        xq = self.layout.Q.tabulate_dof_coordinates()
        if self.column.has_excess:
            self.column.set_excess_levels(xq[:, 2], self.comm)
        self.column.check_installation(xq, self.comm)
        self.initial = InitialState(self.column, self.layout, installation, install_later)
        self.coef = Coefficients(self.layout, disc, self.column)
        self.interface = self._define_interface(interface)
        self._define_forms(loads, self_weight)
        self.constraints = Constraints(self.layout, displacement_bcs, pressure_bcs, plates,
                                       self.interface, self.column.z_w
                                       if self.column.has_dry else None)
        self._define_algebra()
        if install_later:
            self.constraints.hold(self.layout, "structure")
            self.interface.active = False  # type: ignore[union-attr]
        self.newton = NewtonSolver(self, self.options.newton)
        self._itf_force: fem.Form | None = None
        self.load_factor = 0.0
        self.undrained = False
        # the laws' clock stands still until the first commit after the initial stress is set
        # (the geostatic check step takes no time: :meth:`evaluate_laws`)
        self.at_rest = False
        self._initialise_laws()

    # ------------------------------------------------------------------ construction
    def _initialise_laws(self) -> None:
        """Every law's state at the start: the soil at rest where a law needs a stress.

        A law with ``needs_initial_stress`` (Modified Cam Clay, Soft Soil Creep: stiffness
        and pre-consolidation follow the stress) starts from the geostatic effective stress;
        every other law from zero stress. The geostatic stage sets it again.
        """
        groups_needing = [g.name for b in self.bodies for g in b.qp.groups
                          if getattr(g.material.law, "needs_initial_stress", False)]
        stress0 = self.geostatic_stress() if groups_needing else {}
        for b in self.bodies:
            b.qp.initialise({name: stress0[name] for name in groups_needing})

    def _define_interface(self, coupling: InterfaceCoupling | None) -> NodalInterface | None:
        """The interface object of the coupling (``None`` when the piles are tied)."""
        if coupling is None:
            return None
        if coupling.quadrature == "gauss" and self.disc.u_degree != 1:
            raise SolverInputError(
                f"InterfaceCoupling.quadrature = 'gauss' with pair = {self.disc.pair!r}; "
                "allowed: pair 'Q1Q1' (or quadrature 'nodal')")
        cls = GaussInterface if coupling.quadrature == "gauss" else NodalInterface
        lay = self.layout
        return cls(self.md, lay.split, lay.body("structure").V, lay.body("soil").V,
                   list(coupling.laws), coupling.traction0 or self._interface_traction0,
                   coupling.shaft_factor)

    def _interface_traction0(self, x: np.ndarray, z: np.ndarray, m: int) -> np.ndarray:
        """In-situ local traction of interface group ``m`` at points ``x``, heights ``z`` (kPa)."""
        L = self.layout.split.n_layers
        return self.column.interface_traction(x, z, groups.soil_layer(m + 1) if m < L
                                              else None)

    def _define_forms(self, loads: Sequence[SurfaceLoad | FaceAction], self_weight: bool) -> None:
        """Every term of the weak form, compiled once."""
        fb = FormBuilder(self.layout, self.disc, self.coef)
        fb.momentum(self_weight)
        self._load_consts = fb.surface_loads(loads)
        fb.mass_balance()
        if self.disc.stabilise:
            fb.stabilisation()
        if self.interface is not None:
            fb.interface(self.interface)
        empty = fb.pad_parts()
        em = self.layout.emaps
        jo = dict(self.options.jit_options) if self.options.jit_options is not None else None

        def compile_(forms: object) -> object:
            return fem.form(forms, entity_maps=em, jit_options=jo)

        self.F_forms = compile_(fb.forms.F)
        self.J_forms = compile_(fb.forms.J)
        self._J_kept_forms = compile_(fb.forms.J_kept)
        self._J_each_forms = compile_(fb.forms.J_each)
        # each body's tangent term, to be integrated over the cells whose tangent changed
        self._tangent_forms = [fem.compile_form(self.comm, fb.tangent(b, changed=True),
                                                jit_options=jo) for b in self.bodies]
        self._empty_forms = [compile_(e) for e in empty]
        self._F_u_forms = [compile_(fb.forms.F[self.layout.block_of(b)]) for b in self.bodies]
        self._Fint_forms = [compile_(fb.internal_force(b)) for b in self.bodies]
        self._P_forms = compile_(fb.fixed_stress()) \
            if get_preset(self.options.preset).fixed_stress else None

    # ------------------------------------------------------------------ what outputs read
    @property
    def bodies(self) -> list[Body]:
        """The displacement bodies (``[all]`` tied; ``[soil, structure]`` with an interface)."""
        return self.layout.bodies

    def body(self, role: str) -> Body:
        """The body of ``role`` (``"soil"``/``"structure"``; the whole mesh when tied)."""
        return self.layout.body(role)

    def body_of_facet(self, name: str) -> Body:
        """The body whose cells carry the facet group ``name`` (collective)."""
        return self.layout.body_of_facet(name)

    def sub_facets(self, body: Body, facets: np.ndarray) -> np.ndarray:
        """Parent facets -> the facets of ``body``'s mesh."""
        return self.layout.sub_facets(body, facets)

    @property
    def u(self) -> fem.Function:
        """Displacement of the soil (the whole mesh when tied), m."""
        return self.layout.bodies[0].u

    @property
    def p(self) -> fem.Function:
        """Excess pore pressure, kPa (compression positive)."""
        return self.layout.p

    @property
    def Q(self) -> fem.FunctionSpace:
        """Pressure space (on the soil cells)."""
        return self.layout.Q

    @property
    def p_mesh(self) -> dmesh.Mesh:
        """The mesh of the pressure (the soil sub-mesh when there are solids)."""
        return self.layout.p_mesh

    @property
    def surface_loads(self) -> list[tuple[SurfaceLoad | FaceAction, fem.Constant]]:
        """Every surface load and face action with its amplitude constant (set by the stages).

        The residual's load terms are :meth:`FormBuilder.surface_loads` of these loads.
        """
        return list(self._load_consts)

    @property
    def has_solids(self) -> bool:
        """Whether the mesh has structure (pile/cap) cells."""
        return self.layout.has_solids

    @property
    def num_dofs(self) -> int:
        """Global number of unknowns (u and p)."""
        return self.layout.num_dofs

    @property
    def plate(self) -> RigidPlateControl | None:
        """The force-controlled rigid plate, if any."""
        return self.constraints.plate

    @property
    def plate_block(self) -> int | None:
        """Block of the body the rigid plate acts on, if any."""
        plate = self.constraints.plate
        return None if plate is None else self.layout.block_of(self.bodies[plate.body])

    @property
    def block_count(self) -> int:
        """Number of blocks (fields) of the block vectors."""
        return len(self.layout.fields)

    @property
    def u_blocks(self) -> list[int]:
        """Blocks of the displacement fields."""
        return list(self.layout.u_blocks)

    def block_norms(self, vec: PETSc.Vec) -> np.ndarray:
        """Euclidean norm of each block of ``vec`` over the owned dofs."""
        return self.layout.block_norms(vec)

    def x_to_fields(self, vec: PETSc.Vec) -> None:
        """Put the block vector ``vec`` into the fields."""
        self.layout.x_to_fields(vec)

    def max_displacement(self) -> float:
        """Largest nodal displacement magnitude, m (all ranks)."""
        return self.layout.max_displacement()

    def reaction(self, facet: str, component: int) -> float:
        """Resultant (kN) of the unconstrained momentum residual on a facet group.

        The reaction of the constraint, ``int sigma_total . n`` over the facets (tension
        positive), at the current state.
        """
        b = self.body_of_facet(facet)
        dofs = self.layout.facet_dofs(b, facet, component)
        owned = dofs[dofs < b.V.dofmap.index_map.size_local * 3]
        return self.block_resultant(owned, self.bodies.index(b))

    def interface_force(self) -> np.ndarray:
        """The soil's force (kN) on each owned node of the structure, ``(n, 3)``.

        Through the pile-soil interface (effective traction and pore pressure) at the current
        state; row ``i`` is owned node ``i`` of the structure's displacement space (coordinates:
        ``body("structure").V.tabulate_dof_coordinates()``). Piles tied to the soil have no
        interface (an error).
        """
        if self.interface is None:
            raise SolverInputError("interface_force: the piles are tied to the soil (no "
                                   "interface)")
        if self._itf_force is None:
            self._itf_force = fem.form(
                interface_force_form(self.layout, self.interface, self.coef),
                entity_maps=self.layout.emaps)
        V = self.body("structure").V
        vec = fem.assemble_vector(self._itf_force)
        vec.scatter_reverse(la.InsertMode.add)
        n = V.dofmap.index_map.size_local
        return vec.array[: 3 * n].reshape(n, 3)

    def block_resultant(self, owned: np.ndarray, body: int) -> float:
        """Sum (kN) of body ``body``'s unconstrained residual over owned dofs ``owned``."""
        vec = fem.assemble_vector(self._F_u_forms[body])
        vec.scatter_reverse(la.InsertMode.add)
        return float(self.comm.allreduce(float(vec.array[owned].sum()), op=MPI.SUM))

    def force_scales(self) -> list[float]:
        """Euclidean norms (kN) of each body's internal force ``int sigma' : eps(v)``."""
        out = []
        for b, form in zip(self.bodies, self._Fint_forms, strict=True):
            vec = fem.assemble_vector(form)
            vec.scatter_reverse(la.InsertMode.add)
            n = b.V.dofmap.index_map.size_local * 3
            loc = float(vec.array[:n] @ vec.array[:n])
            out.append(float(np.sqrt(self.comm.allreduce(loc, op=MPI.SUM))))
        return out

    # ------------------------------------------------------------------ the step protocol
    def solve_step(self, dt: float, load_factor: float) -> StepInfo:
        """Solve one backward-Euler step of size ``dt`` (day) at ``load_factor`` (Newton).

        Never raises on non-convergence: returns ``StepInfo(converged=False)`` and leaves the
        trial state uncommitted; the caller calls :meth:`commit` or :meth:`rollback`.
        """
        return self.newton.solve(dt, load_factor)

    def set_step(self, dt: float, load_factor: float) -> None:
        """Step size, loads and prescribed values (put into the fields); fields -> ``x``."""
        self.coef.dt.value = dt
        self.load_factor = load_factor
        self.undrained = dt == 0.0
        self.linear_solver.new_step(dt)
        for ld, c in self._load_consts:
            if ld.action is None:
                c.value = ld.pressure * (load_factor if ld.ramp else 1.0)
        self.constraints.set_load(load_factor)
        self.constraints.apply_values(self.undrained)
        self.layout.fields_to_x(self.x)

    def set_ground(self, amplitudes: Sequence[float]) -> None:
        """Amplitudes of the actions (surcharges, water table, cap actions) for the next steps."""
        n = 1 + max([ld.action for ld, _ in self._load_consts if ld.action is not None]
                    + self.constraints.actions, default=-1)
        if len(amplitudes) < n:
            raise SolverInputError(f"ground amplitudes: {len(amplitudes)} given, the loads and "
                                   f"pressure conditions use {n}")
        for ld, c in self._load_consts:
            if ld.action is not None:
                c.value = ld.pressure * amplitudes[ld.action]
        self.constraints.set_ground(amplitudes)

    def active(self, bcs: list[fem.DirichletBC]) -> list[fem.DirichletBC]:
        """The conditions in force in the current step (drainage released when undrained)."""
        return self.constraints.active(bcs, self.undrained)

    def evaluate_laws(self) -> None:
        """Evaluate every law at the current fields (stress, tangent, interface traction)."""
        t0 = time.perf_counter()
        dt = float(self.coef.dt.value)
        for b in self.bodies:  # the soil laws' time: none in the geostatic check step
            b.qp.evaluate(0.0 if self.at_rest else dt)
        if self.interface is not None:
            self.interface.update(self.body("structure").u, self.body("soil").u, dt)
        self.timings["law"] += time.perf_counter() - t0

    def residual_state(self, load_factor: float) -> tuple[np.ndarray, float]:
        """Laws and residual at the current fields: (block norms, plate force gap)."""
        self.evaluate_laws()
        for b in self.bodies:
            if not b.qp.all_finite():
                raise ConvergenceError("NaN/inf stress from the constitutive law "
                                       f"{b.qp.last_error}".rstrip())
        if self.interface is not None:
            ok = bool(np.all(np.isfinite(self.interface.T.x.array)))
            if not self.comm.allreduce(ok, op=MPI.LAND):
                raise ConvergenceError("NaN/inf traction from the interface law "
                                       f"{self.interface.last_error}".rstrip())
        self.assemble_residual()
        rn = self.layout.block_norms(self.b)
        if not np.all(np.isfinite(rn)):
            raise ConvergenceError("NaN residual")
        gap = self.plate.gap(self, load_factor) if self.plate is not None else 0.0
        return rn, gap

    # ------------------------------------------------------------------ state management
    def _stateful(self) -> list[QuadratureState | NodalInterface | RigidPlateControl]:
        """Everything with a committed and a trial state besides the fields."""
        out: list[QuadratureState | NodalInterface | RigidPlateControl] = [
            b.qp for b in self.bodies]
        return out + [x for x in (self.interface, self.plate) if x is not None]

    def commit(self) -> None:
        """Adopt the converged step: state committed, ``u_n, p_n`` updated."""
        for st in self._stateful():
            st.commit()
        self.layout.commit_fields()
        self.at_rest = False

    def rollback(self) -> None:
        """Return to the last committed step (fields, plate and quadrature state)."""
        for st in self._stateful():
            st.rollback()
        self.layout.restore_fields()

    def reset_displacements(self) -> None:
        """Set u (current and committed) to zero, keeping the stress state (after geostatic)."""
        for b in self.bodies:
            b.u.x.array[:] = 0.0
            b.u_n.x.array[:] = 0.0
        if self.interface is not None:
            self.interface.reset_jump()
        if self.plate is not None:
            self.plate.value = self.plate.committed = 0.0

    def install_structure(self, restored: bool) -> None:
        """The structure, held still until now, joins the soil (an ``install`` stage).

        Its displacements are released and the interface's laws start from the jump now, at
        the traction they carried plus the installation's excess pore pressure, which the soil
        gets at this instant with the total stress held, as at the start (docs/model.md,
        "Order of events"). ``restored``: the run resumes from a checkpoint taken after the
        installation, whose state already holds all this.
        """
        if not self.install_later or self.constraints.installed:
            raise SolverInputError("install_structure: the structure is installed already (or"
                                   " was not built with install_later)")
        self.constraints.installed = True
        self.forget_matrix()  # the held structure's conditions are gone: a new matrix
        self.initial.install(self.bodies, restored)
        if restored:
            self.interface.active = True  # type: ignore[union-attr]
        else:
            self.interface.activate(self.column.installation_excess)  # type: ignore[union-attr]

    # ------------------------------------------------------------------ initial stress
    def geostatic_stress(self) -> dict[str, np.ndarray]:
        """K0 effective stress at the quadrature points of each group (Mandel, kPa)."""
        return self.initial.effective_stress(self.bodies)

    @property
    def has_initial_excess(self) -> bool:
        """Whether the soil starts with an excess pore pressure (layers, installation)."""
        return self.initial.has_excess

    def set_initial_pressure(self) -> None:
        """The excess pore pressure at the start: the layers' ``u0`` plus the installation's."""
        self.initial.set_pressure()

    def set_initial_stress(self, stress0: Mapping[str, np.ndarray | None]) -> None:
        """Initialise every group's law state with ``stress0[name]`` ((n,6) Mandel kPa).

        Until the next :meth:`commit` the soil laws see no time (``dt = 0``): the step that
        checks the initial equilibrium borrows its size from the next step for the flow of
        the water only, and a creeping law (Soft Soil Creep) must not creep in it.
        """
        for b in self.bodies:
            b.qp.initialise(dict(stress0))
        self.at_rest = True
