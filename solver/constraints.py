"""Boundary conditions of the coupled problem and the force-controlled rigid plate.

Prescribed displacements (ramped with the load factor when asked), drained boundaries (excess
pore pressure prescribed; released in undrained steps unless ``in_undrained_steps``), the dry
soil above a water table (its pressure held at 0 in every step) and at most one rigid plate
whose resultant is held at a given force by bordering the Newton system.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dolfinx import default_scalar_type, fem
from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import SolverInputError
from pilegroup.solver.geostatic import Z_TOL
from pilegroup.solver.inputs import DisplacementBC, PressureBC, RigidPlate
from pilegroup.solver.interface import NodalInterface
from pilegroup.solver.layout import BlockLayout
from pilegroup.solver.step_protocol import StepProblem


class Constraints:
    """Dirichlet conditions with their values, homogeneous copies and drainage flags.

    ``bcs`` carry the prescribed values (matrix assembly, values put into the fields);
    ``bcs_zero`` are the same dofs with zero values (residual and Newton increments).
    """

    def __init__(self, layout: BlockLayout, displacement_bcs: Sequence[DisplacementBC],
                 pressure_bcs: Sequence[PressureBC], plates: Sequence[RigidPlate],
                 interface: NodalInterface | None, water_table: float | None = None) -> None:
        if len(plates) > 1:
            raise SolverInputError(f"plates: {len(plates)} given; allowed: at most 1")
        self.bcs: list[fem.DirichletBC] = []
        self.bcs_zero: list[fem.DirichletBC] = []
        self._drain: set[int] = set()
        self._targets: list[tuple[fem.DirichletBC, fem.Function]] = []
        self._u_consts: list[tuple[DisplacementBC, fem.Constant]] = []
        mesh = layout.mesh
        for bc in displacement_bcs:
            if bc.component not in (0, 1, 2):
                raise SolverInputError(f"DisplacementBC.component = {bc.component}; allowed 0-2")
            c = fem.Constant(mesh, default_scalar_type(0.0))
            self._u_consts.append((bc, c))
            for b in layout.bodies_of_facet(bc.facet):  # all bodies the group touches
                self.add(layout.facet_dofs(b, bc.facet, bc.component), b.V.sub(bc.component),
                          c, b.u)
        self._p_consts: list[tuple[PressureBC, fem.Constant]] = []
        dry = self._hold_dry(layout, water_table)
        for pbc in pressure_bcs:
            value = default_scalar_type(pbc.value)
            if pbc.action is not None:  # scaled by a ground action's amplitude (set_ground)
                value = fem.Constant(mesh, default_scalar_type(0.0))
                self._p_consts.append((pbc, value))
            dofs = np.setdiff1d(_pressure_dofs(layout, pbc), dry).astype(np.int32)
            bc, bc0 = self.add(dofs, layout.Q, value, layout.p)
            if (pbc.facet, pbc.cells, pbc.level) != (None,) * 3 and not pbc.in_undrained_steps:
                self._drain.update({id(bc), id(bc0)})
        self.plate = RigidPlateControl(self, layout, plates[0], interface) if plates else None
        self._held: set[int] = set()
        self.installed = True

    def _hold_dry(self, layout: BlockLayout, water_table: float | None) -> np.ndarray:
        """Hold the pressure dofs above the water table at 0 in every step; those dofs.

        The soil there is dry: no term of the mass balance acts on them (``solver/forms.py``),
        and no other condition may set them.
        """
        if water_table is None:
            return np.zeros(0, dtype=np.int32)
        z = layout.Q.tabulate_dof_coordinates()[:, 2]
        dofs = np.flatnonzero(z > water_table + Z_TOL).astype(np.int32)
        self.add(dofs, layout.Q, default_scalar_type(0.0), layout.p)
        return dofs

    def hold(self, layout: BlockLayout, role: str) -> None:
        """Hold every displacement of body ``role`` at zero until :attr:`installed` is set.

        A structure installed after the start (``BiotProblem(install_later=True)``) is held
        still while the ground moves without it.
        """
        b = layout.body(role)
        tdim = layout.mesh.topology.dim
        b.mesh.topology.create_connectivity(tdim, tdim)
        imap = b.mesh.topology.index_map(tdim)
        cells = np.arange(imap.size_local + imap.num_ghosts, dtype=np.int32)
        for c in range(3):
            dofs = fem.locate_dofs_topological(b.V.sub(c), tdim, cells)
            bc, bc0 = self.add(dofs, b.V.sub(c), default_scalar_type(0.0), b.u)
            self._held.update({id(bc), id(bc0)})
        self.installed = False

    def add(self, dofs: np.ndarray, V: fem.FunctionSpace, value: fem.Constant | float,
             target: fem.Function) -> tuple[fem.DirichletBC, fem.DirichletBC]:
        """Append a condition with value ``value`` and its homogeneous copy."""
        bc = fem.dirichletbc(value, dofs, V)
        bc0 = fem.dirichletbc(default_scalar_type(0.0), dofs, V)
        self.bcs.append(bc)
        self.bcs_zero.append(bc0)
        self._targets.append((bc, target))
        return bc, bc0

    def set_load(self, load_factor: float) -> None:
        """Prescribed displacements at ``load_factor`` (ramped ones scale with it)."""
        for bc, c in self._u_consts:
            c.value = bc.value * (load_factor if bc.ramp else 1.0)

    @property
    def actions(self) -> list[int]:
        """The ground actions the pressure conditions follow."""
        return [pbc.action for pbc, _ in self._p_consts if pbc.action is not None]

    def set_ground(self, amplitudes: Sequence[float]) -> None:
        """Prescribed pressures of the conditions that follow a ground action."""
        for pbc, c in self._p_consts:
            c.value = pbc.value * amplitudes[pbc.action]  # type: ignore[index]

    def active(self, bcs: list[fem.DirichletBC], undrained: bool) -> list[fem.DirichletBC]:
        """The conditions in force in the step.

        Drainage is released in an undrained step, a held body once installed.
        """
        out = [bc for bc in bcs if id(bc) not in self._drain] if undrained else bcs
        return [bc for bc in out if id(bc) not in self._held] if self.installed else out

    def apply_values(self, undrained: bool) -> None:
        """Put the prescribed values into the fields; Newton increments then vanish there."""
        for bc, f in self._targets:
            if not (undrained and id(bc) in self._drain) and not (
                    self.installed and id(bc) in self._held):
                bc.set(f.x.array)


def _pressure_dofs(layout: BlockLayout, pbc: PressureBC) -> np.ndarray:
    """The pressure dofs ``pbc`` prescribes: its facet group, cell group or level (all: none)."""
    if pbc.cells is not None:
        return layout.pressure_dofs_in_cells(pbc.cells)
    if pbc.level is None:
        return layout.pressure_dofs(pbc.facet)
    z = layout.Q.tabulate_dof_coordinates()[:, 2]
    return np.flatnonzero(np.abs(z - pbc.level) <= Z_TOL).astype(np.int32)


class RigidPlateControl:
    """A rigid plate under force control: the plate's displacement ``U`` is an extra unknown.

    The plate's facet dofs move by ``U`` (a Dirichlet condition); Newton borders its system so
    that the plate resultant equals ``force * load_factor``: ``dx = dx_a + dU dx_b`` where
    ``dx_a`` solves with the plate held, ``dx_b`` is the response to a unit plate motion, and
    ``dU`` comes from a secant on the plate resultant (exact for linear problems).
    """

    def __init__(self, cons: Constraints, layout: BlockLayout, spec: RigidPlate,
                 interface: NodalInterface | None) -> None:
        self.spec = spec
        b = layout.body_of_facet(spec.facet)
        self.body = layout.bodies.index(b)
        dofs = layout.facet_dofs(b, spec.facet, spec.component)
        Vc = b.V.sub(spec.component)
        self.U = fem.Constant(layout.mesh, default_scalar_type(0.0))
        cons.add(dofs, Vc, self.U, b.u)
        self.unit_bcs = cons.bcs_zero[:-1] + [fem.dirichletbc(
            fem.Constant(layout.mesh, default_scalar_type(-1.0)), dofs, Vc)]
        self.owned = dofs[dofs < b.V.dofmap.index_map.size_local * 3]
        self.db: PETSc.Vec | None = None
        self.value = 0.0
        self.committed = 0.0
        if interface is not None and interface.has_matrix:
            # the bordering lifts the plate motion through the forms only
            hit = np.isin(dofs, interface.touched_dofs(b.name)).any()
            if layout.comm.allreduce(bool(hit), op=MPI.LOR):
                raise SolverInputError(
                    f"RigidPlate on {spec.facet!r} moves interface nodes; allowed with "
                    "InterfaceCoupling.quadrature = 'nodal' only")

    def target(self, load_factor: float) -> float:
        """Plate force (kN) at ``load_factor``."""
        return self.spec.force * load_factor

    def set(self, value: float) -> None:
        """Move the plate to ``value`` (m)."""
        self.value = value
        self.U.value = value

    def commit(self) -> None:
        """Adopt the current plate position."""
        self.committed = self.value

    def rollback(self) -> None:
        """Return to the committed plate position."""
        self.set(self.committed)

    def gap(self, problem: StepProblem, load_factor: float) -> float:
        """Plate resultant minus its target force (kN) at the current state."""
        return problem.block_resultant(self.owned, self.body) - self.target(load_factor)

    def unit_response(self, problem: StepProblem) -> PETSc.Vec:
        """``dx_b``: the Newton response to a unit plate motion (cached until J changes)."""
        if self.db is None:
            db = problem.dx.duplicate()
            db.setAttr("_blocks", problem.dx.getAttr("_blocks"))
            problem.dirichlet_response(self.unit_bcs, db)
            self.db = db
        return self.db

    def border(self, problem: StepProblem, load_factor: float) -> float:
        """Correct the Newton increment ``problem.dx`` for the plate force; returns ``dU``."""
        db = self.unit_response(problem)
        x0 = problem.x.copy()
        xa = problem.x.copy()
        xa.axpy(-1.0, problem.dx)
        problem.x_to_fields(xa)
        problem.evaluate_laws()
        Ra = problem.block_resultant(self.owned, self.body)
        xb = xa.copy()
        xb.axpy(-1.0, db)
        problem.x_to_fields(xb)
        problem.evaluate_laws()
        Rb = problem.block_resultant(self.owned, self.body)
        dU = -(Ra - self.target(load_factor)) / (Rb - Ra)
        problem.dx.axpy(dU, db)
        self.set(self.value + dU)
        problem.x_to_fields(x0)
        return dU
