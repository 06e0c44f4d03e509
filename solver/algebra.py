"""The monolithic system's algebra: PETSc matrices and vectors, assembly and linear solves.

:class:`MonolithicAlgebra` is the part of :class:`~pilegroup.solver.problem.BiotProblem` that
turns the compiled forms into the Newton system: the Jacobian (with the fixed-stress
preconditioning matrix and the Gauss interface's own tangent), the residual with its
constrained rows, the lifting of prescribed values, and the linear solver with its fallback.
It works on what the problem defines: ``F_forms``, ``J_forms`` (and its parts
``_J_kept_forms``, ``_J_each_forms``), ``_P_forms``, ``layout``,
``interface``, ``coef``, ``options``, ``constraints``, ``plate``, ``bodies``, ``comm``,
``undrained``, ``timings`` and ``active``.
"""

from __future__ import annotations

import time

import numpy as np
from dolfinx import fem
from dolfinx.cpp.la.petsc import create_index_sets
from dolfinx.fem import petsc as fpetsc
from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.solver.forms import CHANGED_TAG
from pilegroup.solver.layout import Body
from pilegroup.solver.linsolve import KSPSolver


class MonolithicAlgebra:
    """Matrices, vectors, assembly and the linear solver of the coupled problem (a mixin)."""

    def _define_algebra(self) -> None:
        """PETSc matrices, vectors and the linear solver (created once; sparsity reused)."""
        self.A = fpetsc.create_matrix(self.J_forms)
        self.P: PETSc.Mat | None = None
        self._Mbeta = fpetsc.create_matrix(self._P_forms) if self._P_forms is not None else None
        self.spaces = fem.extract_function_spaces(self.F_forms)
        self.b, self.x, self.dx, self.tmp = (fpetsc.create_vector(self.spaces) for _ in range(4))
        opts = self.options
        self.linear_solver = KSPSolver(
            self.comm, self.A, opts.prefix, opts.preset, opts.overrides,
            lambda spec: self.layout.splits(
                self.A, spec.splits,
                spec.band_layers if opts.band_layers is None else opts.band_layers))
        self._matrix_key: float | None = None  # dt of the assembled matrix (linear reuse)
        self._block_is: list[PETSc.IS] | None = None  # index sets of the blocks
        # the kept part of the Jacobian (J_kept) and the constraints it was built with
        self._A_kept: PETSc.Mat | None = None
        self._kept_key: tuple | None = None
        # the kept part was updated cell by cell since it was built; it is to be built whole
        self._kept_updated = False
        self._rebuild_kept = False
        self._row_weights: PETSc.Vec | None = None  # inexact Newton's block weights

    def dirichlet_response(self, bcs: list[fem.DirichletBC], out: PETSc.Vec) -> None:
        """Solve the Newton system for the lifting of the conditions ``bcs`` into ``out``.

        The right-hand side is ``-J g`` off the constrained dofs and ``g`` on them (``g`` the
        conditions' values; the drainage conditions of an undrained step are left out), so
        ``out`` is the increment that moves the constrained dofs by ``g`` (collective).
        """
        rhs = self.tmp
        with rhs.localForm() as rl:
            rl.set(0.0)
        active = self.active(bcs)
        fpetsc.apply_lifting(rhs, self.J_forms, bcs=fem.bcs_by_block(
            fem.extract_function_spaces(self.J_forms, 1), active), alpha=1.0)
        rhs.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fpetsc.set_bc(rhs, fem.bcs_by_block(self.spaces, active))
        self.solve_linear(rhs, out)

    @property
    def refactorisations(self) -> int:
        """LU factorisations of the run (direct presets; 0 for iterative ones)."""
        return self.linear_solver.refactorisations

    def assemble_residual(self) -> None:
        """Residual ``b`` with zero rows at constrained dofs (their values are imposed)."""
        t0 = time.perf_counter()
        b = self.b
        with b.localForm() as bl:
            bl.set(0.0)
        fpetsc.assemble_vector(b, self.F_forms)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        fpetsc.set_bc(b, fem.bcs_by_block(self.spaces, self.active(self.constraints.bcs_zero)))
        b.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        self.timings["assemble_F"] += time.perf_counter() - t0

    def _linear(self) -> bool:
        """Linear problem: every law linear (interface laws declare ``linear = True``)."""
        lin = all(b.qp.linear for b in self.bodies)
        if self.interface is not None:
            lin = lin and all(getattr(g.law, "linear", False) for g in self.interface.groups
                              if g.law is not None)
        return lin

    def rebuild_kept(self) -> None:
        """The next assembly builds the kept part whole if it was updated cell by cell.

        Called after a checkpoint is written: the run then goes on from the kept part that a
        run resumed from that checkpoint builds, and both give the same numbers to the last
        bit (docs/checkpoint.md, "Exactness").
        """
        self._rebuild_kept = True

    def forget_matrix(self) -> None:
        """The constraints changed in a way the matrix keys do not see: assemble anew."""
        self._matrix_key = None
        self._kept_key = None

    def assemble_jacobian(self, force: bool = False) -> bool:
        """Assemble ``A`` (and the preconditioning matrix); returns whether it did.

        Skipped for linear problems with an unchanged dt unless ``force``. Otherwise ``A`` is
        the kept part plus ``J_each`` and the interface's tangent assembled now. The kept
        part (``J_kept``) is assembled whole when the constraints change (and after a
        checkpoint, :meth:`rebuild_kept`), and otherwise updated over the cells whose tangent
        changed (docs/solver.md, "Jacobian assembly").
        """
        key = float(self.coef.dt.value)
        if not force and self._linear() and self._matrix_key == key:
            return False
        t0 = time.perf_counter()
        bcs = self.active(self.constraints.bcs)
        bc_key = tuple(id(bc) for bc in bcs)
        stale = force or bc_key != self._kept_key or (self._rebuild_kept and self._kept_updated)
        self._rebuild_kept = False
        changed = any(b.qp.tangent_changed for b in self.bodies)
        todo = self.comm.allreduce(int(stale) | 2 * int(changed), op=MPI.BOR)
        if todo & 1:
            self._assemble_kept(bcs)
            self._kept_key = bc_key
        elif todo & 2:
            self._update_kept(bcs)
        self._A_kept.copy(self.A, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        fpetsc.assemble_matrix(self.A, self._J_each_forms, bcs=bcs, diag=1.0)
        self.A.assemble()
        if self.interface is not None:
            self._add_interface_matrix(bcs)
            self.A.assemble()
        if self._Mbeta is not None and self.linear_solver.uses_preconditioning_matrix:
            self._assemble_fixed_stress(bcs)
        self.linear_solver.set_operators(self.A, self.P)
        self._matrix_key = key
        if self.plate is not None:
            self.plate.db = None
        self.timings["assemble_J"] += time.perf_counter() - t0
        return True

    def _assemble_kept(self, bcs: list[fem.DirichletBC]) -> None:
        """``A_kept``: ``J_kept`` now, with a unit diagonal at the constrained dofs."""
        if self._A_kept is None:  # the whole J first, which gives A its whole sparsity
            self.A.zeroEntries()
            fpetsc.assemble_matrix(self.A, self.J_forms, bcs=bcs, diag=1.0)
            self.A.assemble()
            self._A_kept = self.A.duplicate()
        self._A_kept.zeroEntries()
        fpetsc.assemble_matrix(self._A_kept, self._J_kept_forms, bcs=bcs, diag=1.0)
        self._A_kept.assemble()
        self._kept_updated = False
        for b in self.bodies:
            b.qp.mark_tangent()

    def _update_kept(self, bcs: list[fem.DirichletBC]) -> None:
        """Add to ``A_kept`` the tangent's change since it was built, over the changed cells.

        Each body's tangent Function holds the change there while its term is integrated over
        those cells only, all bodies in one assembly (collective: every rank assembles, with
        or without cells).
        """
        n = len(self.spaces)
        forms = [[self._empty_forms[r] if r == c else None for c in range(n)] for r in range(n)]
        restore = []
        try:
            for b, compiled in zip(self.bodies, self._tangent_forms, strict=True):
                cells, dofs, delta = b.qp.tangent_changes()
                t = b.qp.tangent.x.array.reshape(-1, 36)
                restore.append((t, dofs, t[dofs]))
                t[dofs] = delta
                i = self.layout.block_of(b)
                forms[i][i] = self._on_cells(b, compiled, cells)
            fpetsc.assemble_matrix(self._A_kept, forms, bcs=bcs, diag=1.0)
            self._A_kept.assemble()
        finally:
            for t, dofs, now in restore:
                t[dofs] = now
        for b in self.bodies:
            b.qp.mark_tangent()
        self._kept_updated = True

    def _on_cells(self, b: Body, compiled: fem.CompiledForm, cells: np.ndarray) -> fem.Form:
        """The compiled tangent form of body ``b`` over its (body mesh) ``cells`` only.

        The form integrates over the subdomain ``forms.CHANGED_TAG``, which these cells (as
        parent-mesh cells) make up.
        """
        parent = cells if b.emap is None else \
            b.emap.sub_topology_to_topology(cells, inverse=False)
        domains = [(CHANGED_TAG, np.sort(parent).astype(np.int32))]
        form = compiled.ufl_form
        return fem.create_form(compiled, [b.V, b.V], self.layout.mesh,
                               {fem.IntegralType.cell: domains},
                               {c: c for c in form.coefficients()},
                               {c: c for c in form.constants()}, self.layout.emaps)

    def _block_index_sets(self) -> list[PETSc.IS]:
        if self._block_is is None:
            self._block_is = create_index_sets(
                [(V.dofmap.index_map, V.dofmap.index_map_bs) for V in self.spaces])
        return self._block_is

    def _assemble_fixed_stress(self, bcs: list[fem.DirichletBC]) -> None:
        """``P = J + M_beta`` (one axpy on J's sparsity)."""
        self._Mbeta.zeroEntries()
        fpetsc.assemble_matrix(self._Mbeta, self._P_forms, bcs=bcs, diag=0.0)
        self._Mbeta.assemble()
        if self.P is None:
            self.P = self.A.duplicate(copy=True)
        else:
            self.A.copy(self.P, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self.P.axpy(1.0, self._Mbeta, structure=PETSc.Mat.Structure.SUBSET_NONZERO_PATTERN)

    def _add_interface_matrix(self, bcs: list[fem.DirichletBC]) -> None:
        """Add the interface's tangent to ``A``: nodal, or the Gauss points' own matrix."""
        iss = self._block_index_sets()
        lay = self.layout
        i_s, i_t = lay.block_of(lay.body("soil")), lay.block_of(lay.body("structure"))
        by_block = fem.bcs_by_block(self.spaces, bcs)

        def constrained(i: int) -> np.ndarray:
            return np.concatenate([bc.dof_indices()[0] for bc in by_block[i]]
                                  + [np.zeros(0, np.int32)])

        args = (self.A, iss[i_s], iss[i_t], constrained(i_s), constrained(i_t))
        self.interface.add_nodal_tangent(*args)
        if self.interface.has_matrix:
            self.interface.add_jacobian(*args)

    def fall_back_linear_solver(self, reason: str) -> bool:
        """After a step failed in the linear solver: use the preset's fallback, if it has one."""
        if "KSP diverged" not in reason:
            return False
        return self.linear_solver.fall_back(reason)

    def solve_linear(self, rhs: PETSc.Vec, sol: PETSc.Vec,
                     block_tol: np.ndarray | None = None) -> int:
        """Solve with the current Jacobian; returns the Krylov iterations.

        ``block_tol``: the residual norm each block may keep (inexact Newton), given to the
        linear solver as row weights ``1 / block_tol`` (block by block).
        """
        t0 = time.perf_counter()
        weights = None
        if block_tol is not None and self.linear_solver.forcing:
            if self._row_weights is None:
                self._row_weights = fpetsc.create_vector(self.spaces)
            weights = self._row_weights
            off0, _ = weights.getAttr("_blocks")  # owned range of each block
            w = weights.array
            for i, tol in enumerate(block_tol):
                w[off0[i]:off0[i + 1]] = 1.0 / max(tol, 1e-30)
        its = self.linear_solver.solve(rhs, sol, self.undrained, weights)
        self.timings["solve"] += time.perf_counter() - t0
        return its


__all__ = ["MonolithicAlgebra"]
