"""The step protocol: the only way Newton, the stepper and the rigid plate use a problem.

:class:`~pilegroup.solver.problem.BiotProblem` implements it; :mod:`pilegroup.solver.newton`,
:mod:`pilegroup.solver.stepping` and :mod:`pilegroup.solver.constraints` are written against
it (``tests/package/test_structure.py`` checks that they use no other member of the problem).
Block vectors hold the unknowns in the order of the block layout (``[u, p, u_structure]``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np
from petsc4py import PETSc

if TYPE_CHECKING:
    from dolfinx import fem


@dataclass
class StepInfo:
    """Outcome of one attempted step."""

    converged: bool
    newton_its: int = 0
    ksp_its: int = 0
    ksp_max: int = 0  # Krylov iterations of the step's hardest Newton solve
    linear_failure: bool = False  # the step failed in a Krylov solve (not in Newton)
    alternate: bool = False  # converged by Newton's alternate tolerance (solver/newton.py)
    residuals: list[tuple[float, ...]] = field(default_factory=list)
    message: str = ""
    seconds: float = 0.0


class PlateControl(Protocol):
    """A force-controlled rigid plate as Newton sees it (``constraints.RigidPlateControl``)."""

    value: float
    """The plate's displacement, m."""

    def target(self, load_factor: float) -> float:
        """Plate force (kN) at ``load_factor``."""
        ...

    def set(self, value: float) -> None:
        """Move the plate to ``value`` (m)."""
        ...

    def border(self, problem: StepProblem, load_factor: float) -> float:
        """Correct the Newton increment for the plate force; returns the plate's motion, m."""
        ...


class StepProblem(Protocol):
    """A problem solved step by step (collective methods unless stated)."""

    # ---- state as block vectors
    @property
    def x(self) -> PETSc.Vec:
        """The unknowns (block vector)."""
        ...

    @property
    def b(self) -> PETSc.Vec:
        """The residual (block vector, zero at constrained dofs)."""
        ...

    @property
    def dx(self) -> PETSc.Vec:
        """The Newton increment (block vector); ``x <- x - dx``."""
        ...

    @property
    def block_count(self) -> int:
        """Number of blocks (fields) of the block vectors."""
        ...

    @property
    def u_blocks(self) -> list[int]:
        """Blocks of the displacement fields."""
        ...

    @property
    def plate(self) -> PlateControl | None:
        """The rigid plate under force control, if any."""
        ...

    @property
    def plate_block(self) -> int | None:
        """Block of the body the plate acts on, if any."""
        ...

    def block_norms(self, vec: PETSc.Vec) -> np.ndarray:
        """Euclidean norm of each block of ``vec`` over the owned dofs."""
        ...

    def x_to_fields(self, vec: PETSc.Vec) -> None:
        """Put the block vector ``vec`` into the fields."""
        ...

    # ---- one Newton step
    def set_step(self, dt: float, load_factor: float) -> None:
        """Step size (day), loads and prescribed values; fields -> ``x``."""
        ...

    def evaluate_laws(self) -> None:
        """Evaluate every law at the current fields."""
        ...

    def residual_state(self, load_factor: float) -> tuple[np.ndarray, float]:
        """Laws and residual at the current fields: (block norms, plate force gap kN)."""
        ...

    def assemble_jacobian(self, force: bool = False) -> bool:
        """Assemble the Newton matrix (``force``: even when it could be kept)."""
        ...

    def solve_linear(self, rhs: PETSc.Vec, sol: PETSc.Vec,
                     block_tol: np.ndarray | None = None) -> int:
        """Solve the Newton system for ``rhs`` into ``sol``; returns the Krylov iterations.

        ``block_tol``: the largest residual norm each block may keep (an inexact solve, where
        the linear solver supports it); ``None``: the solver's own tolerance.
        """
        ...

    def force_scales(self) -> list[float]:
        """Norm (kN) of each body's internal force (a residual reference)."""
        ...

    def block_resultant(self, owned: np.ndarray, body: int) -> float:
        """Sum (kN) of body ``body``'s unconstrained residual over the owned dofs ``owned``."""
        ...

    def dirichlet_response(self, bcs: list[fem.DirichletBC], out: PETSc.Vec) -> None:
        """Solve the Newton system for the lifting of the conditions ``bcs`` into ``out``."""
        ...

    # ---- steps, stages and state
    def solve_step(self, dt: float, load_factor: float) -> StepInfo:
        """One backward-Euler step by Newton; never raises on non-convergence."""
        ...

    def commit(self) -> None:
        """Adopt the converged step."""
        ...

    def rollback(self) -> None:
        """Return to the last committed step."""
        ...

    def fall_back_linear_solver(self, reason: str) -> bool:
        """Switch to the fallback linear solver, if there is one; whether it switched."""
        ...

    def set_ground(self, amplitudes: Sequence[float]) -> None:
        """Amplitudes of the ground actions (surcharges, water table) for the next steps."""
        ...

    @property
    def has_initial_excess(self) -> bool:
        """Whether the soil starts with an excess pore pressure (layers, installation)."""
        ...

    def set_initial_pressure(self) -> None:
        """The excess pore pressure at the start (the consolidating layers'; else 0)."""
        ...

    def geostatic_stress(self) -> dict[str, np.ndarray]:
        """The in-situ effective stress at the quadrature points of each group."""
        ...

    def set_initial_stress(self, stress0: Mapping[str, np.ndarray | None]) -> None:
        """Initialise every group's law state with ``stress0``."""
        ...

    def install_structure(self, restored: bool) -> None:
        """The structure, held still until now, joins the soil (an ``install`` stage).

        ``restored``: the state is a checkpoint's, taken after the installation.
        """
        ...

    def max_displacement(self) -> float:
        """Largest displacement magnitude, m."""
        ...

    def reset_displacements(self) -> None:
        """Set the displacements to zero, keeping the stress state."""
        ...


__all__ = ["PlateControl", "StepInfo", "StepProblem"]
