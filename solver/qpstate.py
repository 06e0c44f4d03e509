"""Constitutive state at quadrature points (the external-operator pattern, written directly).

For each material group the owned cells, their quadrature points and the law's state arrays
``(n_points, k)`` are kept here. ``evaluate`` computes the strain increment at the points from a
compiled ``dolfinx.fem.Expression``, calls ``law.update`` and writes the stress (Mandel 6-vector,
kPa, tension positive) and the tangent (6x6, kPa) into quadrature Functions that the residual and
Jacobian forms read. ``commit`` adopts the trial state after a converged step; ``rollback`` keeps
the committed one (the trial is simply discarded).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import basix
import basix.ufl
import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from pilegroup.constitutive.base import ConstitutiveLaw

if TYPE_CHECKING:
    from pilegroup.solver.inputs import ElasticSolid, SoilMaterial


@dataclass
class MaterialPoints:
    """Quadrature points of one material group (owned cells only)."""

    name: str
    material: SoilMaterial | ElasticSolid
    cells: np.ndarray
    dofs: np.ndarray  # (n_cells * nqp,) block indices into the quadrature spaces
    x: np.ndarray  # (n_points, 3) coordinates, m
    state_n: dict[str, np.ndarray] = field(default_factory=dict)
    state_trial: dict[str, np.ndarray] | None = None

    @property
    def n(self) -> int:
        """Number of points."""
        return int(self.dofs.size)


class QuadratureState:
    """Stress and tangent quadrature Functions driven by the constitutive laws.

    Args:
        mesh: the mesh.
        groups: ``name -> (material, cells)`` with owned cell indices per material group.
        degree: quadrature degree (must match the forms' ``quadrature_degree``).
        strain_increment: UFL expression of the Mandel strain increment (6-vector).
    """

    def __init__(self, mesh: dmesh.Mesh,
                 groups: dict[str, tuple[SoilMaterial | ElasticSolid, np.ndarray]], degree: int,
                 strain_increment: ufl.core.expr.Expr) -> None:
        self.mesh = mesh
        self.degree = degree
        cell = mesh.basix_cell()
        self.points, self.weights = basix.make_quadrature(cell, degree)
        self.nqp = self.points.shape[0]
        Se = basix.ufl.quadrature_element(cell, value_shape=(6,), degree=degree)
        Te = basix.ufl.quadrature_element(cell, value_shape=(6, 6), degree=degree)
        self.S = fem.functionspace(mesh, Se)
        self.T = fem.functionspace(mesh, Te)
        self.stress = fem.Function(self.S, name="effective_stress_qp")
        self.tangent = fem.Function(self.T, name="tangent_qp")
        assert self.S.dofmap.bs == 6 and self.T.dofmap.bs == 36
        self.expr_strain = fem.Expression(strain_increment, self.points)
        self.expr_x = fem.Expression(ufl.SpatialCoordinate(mesh), self.points)
        self.groups: list[MaterialPoints] = []
        dm = self.S.dofmap.list
        for name, (mat, cells) in groups.items():
            cells = np.asarray(cells, dtype=np.int32)
            dofs = dm[cells].reshape(-1) if cells.size else np.zeros(0, dtype=np.int32)
            if cells.size:
                x = self.expr_x.eval(mesh, cells).reshape(-1, 3)
            else:
                x = np.zeros((0, 3))
            self.groups.append(MaterialPoints(name, mat, cells, dofs, x))
        self.linear = all(_is_linear(g.material.law) for g in self.groups)
        self.last_error = ""
        # the cells whose tangent changed since mark_tangent() and their tangent then
        n_cells = mesh.topology.index_map(mesh.topology.dim).size_local
        self._changed = np.zeros(n_cells, dtype=bool)
        self._saved: list[tuple[np.ndarray, np.ndarray]] = []

    def initialise(self, stress0: dict[str, np.ndarray | None]) -> None:
        """Set the committed state of each group from ``stress0[name]`` ((n,6) kPa or None)."""
        for g in self.groups:
            g.state_n = g.material.law.initial_state(g.n, stress0.get(g.name))
            g.state_trial = None
            self._write(g, g.state_n["stress"], None)
        self.stress.x.scatter_forward()

    def add_isotropic_stress(self, values: Mapping[str, np.ndarray]) -> None:
        """Add ``values[name]`` ((n,) kPa) to the normal stresses of group ``name``.

        The committed state changes; groups not named are left alone.
        """
        for g in self.groups:
            if g.name not in values or g.n == 0:
                continue
            g.state_n["stress"] = g.state_n["stress"].copy()
            g.state_n["stress"][:, :3] += np.asarray(values[g.name])[:, None]
            self._write(g, g.state_n["stress"], None)
        self.stress.x.scatter_forward()

    def evaluate(self, dt: float) -> None:
        """Evaluate the laws at the current strain increment; fill stress and tangent."""
        for g in self.groups:
            if g.n == 0:
                g.state_trial = {k: v.copy() for k, v in g.state_n.items()}
                continue
            de = self.expr_strain.eval(self.mesh, g.cells).reshape(-1, 6)
            stress, trial, tangent, error = guarded_update(g.material.law, de, g.state_n, dt)
            if error:
                self.last_error = f"{g.name}: {error}"
            g.state_trial = trial
            self._write(g, stress, tangent)

    def _write(self, g: MaterialPoints, stress: np.ndarray, tangent: np.ndarray | None) -> None:
        if g.n == 0:
            return
        s = self.stress.x.array.reshape(-1, 6)
        s[g.dofs] = stress
        if tangent is not None:
            t = self.tangent.x.array.reshape(-1, 36)
            new = np.asarray(tangent).reshape(-1, 36)
            old = t[g.dofs]
            cell_diff = np.any(old != new, axis=1).reshape(-1, self.nqp).any(axis=1)
            if not cell_diff.any():
                return
            first = cell_diff & ~self._changed[g.cells]
            if first.any():  # keep the tangent these cells had at the mark
                pts = np.repeat(first, self.nqp)
                self._saved.append((g.dofs[pts], old[pts]))
                self._changed[g.cells[first]] = True
            pts = np.repeat(cell_diff, self.nqp)
            t[g.dofs[pts]] = new[pts]

    @property
    def tangent_changed(self) -> bool:
        """Whether a tangent changed on this rank since :meth:`mark_tangent`."""
        return bool(self._saved)

    def mark_tangent(self) -> None:
        """Start tracking tangent changes from the current tangent."""
        self._changed[:] = False
        self._saved = []

    def tangent_changes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The tangent's change since :meth:`mark_tangent`: cells, their points, the change.

        Owned cells whose tangent changed, the quadrature dofs of those cells and the change
        of the tangent there (``(n_dofs, 36)``).
        """
        if not self._saved:
            return np.zeros(0, np.int32), np.zeros(0, np.int32), np.zeros((0, 36))
        dofs = np.concatenate([d for d, _ in self._saved])
        old = np.concatenate([v for _, v in self._saved])
        cells = np.flatnonzero(self._changed).astype(np.int32)
        return cells, dofs, self.tangent.x.array.reshape(-1, 36)[dofs] - old

    def all_finite(self) -> bool:
        """True when every trial stress is finite on every rank (collective)."""
        ok = bool(np.all(np.isfinite(self.stress.x.array)))
        return bool(self.mesh.comm.allreduce(ok, op=MPI.LAND))

    def commit(self) -> None:
        """Adopt the trial state of every group."""
        for g in self.groups:
            if g.state_trial is not None:
                g.state_n = {k: np.array(v, copy=True) for k, v in g.state_trial.items()}
            g.state_trial = None

    def rollback(self) -> None:
        """Discard the trial state; the stress Function is reset to the committed stress."""
        for g in self.groups:
            g.state_trial = None
            self._write(g, g.state_n["stress"], None)

    def saved_state(self) -> dict[str, np.ndarray]:
        """The committed law state of every group as arrays named ``group/key`` (checkpoint)."""
        return {f"{g.name}/{k}": v for g in self.groups for k, v in g.state_n.items()}

    def restore_state(self, arrays: Mapping[str, np.ndarray]) -> None:
        """Set the committed state of every group from :meth:`saved_state`'s arrays.

        The arrays are this rank's points, so they fit the same mesh partition only; a group
        whose point count differs raises ``ValueError``.
        """
        for g in self.groups:
            state = {name.rsplit("/", 1)[1]: np.array(a) for name, a in arrays.items()
                     if name.rsplit("/", 1)[0] == g.name}
            if any(a.shape[0] != g.n for a in state.values()) or "stress" not in state:
                raise ValueError(f"saved state of material group {g.name!r} does not fit its "
                                 f"{g.n} points on this rank")
            g.state_n, g.state_trial = state, None
            self._write(g, state["stress"], None)
        self.stress.x.scatter_forward()

    def cell_average(self, key: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Cell averages of state ``key`` per group: ``name -> (cells, (n_cells, k))``."""
        out = {}
        w = self.weights / self.weights.sum()
        for g in self.groups:
            if key not in g.state_n:
                continue
            a = g.state_n[key]
            k = a.shape[1]
            out[g.name] = (g.cells, np.einsum("cqk,q->ck", a.reshape(-1, self.nqp, k), w))
        return out


def guarded_update(law: ConstitutiveLaw, increment: np.ndarray, state_n: dict[str, np.ndarray],
                   dt: float) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray, str]:
    """``law.update`` that never raises: a failure gives NaN values and its message.

    A law that fails on one rank (e.g. a return mapping that does not converge) must not
    desynchronise the ranks: its NaN output is caught by the collective finiteness check of the
    residual, which rejects the iteration everywhere (the step is then cut back).
    Returns ``(values, trial state, tangent, error message or "")``.
    """
    try:
        values, trial, tangent = law.update(increment, state_n, dt)
        return values, trial, tangent, ""
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        n, k = increment.shape
        trial = {key: v.copy() for key, v in state_n.items()}
        return np.full((n, k), np.nan), trial, np.zeros((n, k, k)), str(exc)


def _is_linear(law: ConstitutiveLaw) -> bool:
    """A law is linear when it declares ``linear = True`` or is the LinearElastic law."""
    flag = getattr(law, "linear", None)
    if flag is not None:
        return bool(flag)
    return type(law).__name__ == "LinearElastic"
