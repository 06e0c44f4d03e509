"""Pile sections and cap motion: what a lateral design reads off a run.

Sign conventions (global axes, x and y horizontal, z up; moments by the right-hand rule):

* A **section** of a pile at depth ``d`` carries the action of the part above on the part
  below: shear ``Vx = int sigma_xz``, ``Vy = int sigma_yz`` (kN), axial force ``N = -int
  sigma_zz`` (kN, compression positive), bending moments about the section centre ``Mx = int
  (y - y_p) sigma_zz`` and ``My = -int (x - x_p) sigma_zz`` and torque ``T = int ((x - x_p)
  sigma_yz - (y - y_p) sigma_xz)`` (kN m). Each is the mean over an element layer of the pile
  (exact integrals of the quadrature-point stress over the layer's cells, over its height):
  the value at the layer's mid-height for a quantity linear in depth. The lateral deflection
  ``ux``, ``uy`` (m) is the layer's volume mean.
* The **head** (depth 0, the ground surface, where the pile leaves the cap): the action of the
  cap on the pile, same components. With the pile–soil interface it is exact: minus the force
  and moment the soil exerts on the pile through the interface (the pile below the head is a
  free body). Tied piles have no interface: their head row is the uppermost section, and
  ``depth_m`` says where it is.
* Every value is the change since the first output time (the geostatic state), as the axial
  force of ``pile_profiles.csv``: the effect of the loads and of the ground's movement.
* The **cap motion**: the rigid motion fitted to the loaded face's displacement
  (:class:`~pilegroup.solver.probes.FaceMotion`), given at the scenario's action point:
  ``u_P = u_C + theta x (P - C)``; displacements m (z up: a settlement is negative ``uz_m``),
  rotations rad.

In a symmetry-reduced model, components that a mirror plane makes zero are zero
(:data:`~pilegroup.model.actions.ANTISYMMETRIC`: e.g. for the plane y = 0, ``Vy``, ``Mx``,
``T`` and ``uy``), a pile cut by a plane reports its meshed part over its meshed fraction, and a
pile outside the mesh its mirror image's values with those components' signs reversed.
Every number is all-reduced over the ranks; rank 0 writes.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.geometry.adapter import ResolvedGeometry
from pilegroup.model import Scenario
from pilegroup.model.actions import ANTISYMMETRIC
from pilegroup.solver import BiotProblem
from pilegroup.solver.probes import FaceMotion
from pilegroup.studies.results.tables import (
    BENDING_COLUMNS,
    CAP_MOTION_COLUMNS,
    HEAD_COLUMNS,
    MAX_MOMENT_COLUMNS,
)
from pilegroup.studies.run.cap_loads import loaded_facets
from pilegroup.studies.run.pile_probe import PileProbe

#: Deflection components (ux, uy) a mirror plane makes zero / reverses.
_DEFLECTION_ANTISYMMETRIC = {"x": (0,), "y": (1,)}
_TOL = 1e-9


def _sign_flips(planes: tuple[str, ...], xy: tuple[float, float], src: tuple[float, float]
                ) -> tuple[str, ...]:
    """The planes across which pile ``xy`` is the mirror image of ``src`` (not itself)."""
    return tuple(a for a, k in (("x", 0), ("y", 1))
                 if a in planes and abs(xy[k] - src[k]) > _TOL)


def _on_planes(planes: tuple[str, ...], xy: tuple[float, float]) -> tuple[str, ...]:
    """The cut planes pile ``xy``'s axis lies on."""
    return tuple(a for a, k in (("x", 0), ("y", 1)) if a in planes and abs(xy[k]) <= _TOL)


def _symmetrise(v: np.ndarray, zero: tuple[str, ...], flip: tuple[str, ...],
                table: dict[str, tuple[int, ...]]) -> np.ndarray:
    """``v[..., k]`` set to 0 for the planes in ``zero`` and reversed for those in ``flip``."""
    out = np.array(v, dtype=float)
    for a in zero:
        out[..., list(table[a])] = 0.0
    for a in flip:
        out[..., list(table[a])] *= -1.0
    return out


class PileSections:
    """``pile_bending.csv``, ``pile_heads.csv``, ``pile_max_moment.csv`` (module docstring).

    An export: :meth:`write` at every output time rewrites the three files.
    """

    def __init__(self, sc: Scenario, geo: ResolvedGeometry, pb: BiotProblem,
                 piles: PileProbe, out: Path) -> None:
        self.pb, self.piles, self.out, self.comm = pb, piles, Path(out), pb.comm
        self.xy = [tuple(map(float, p)) for p in sc.piles.xy]
        self.radius = [0.5 * d for d in sc.piles.diameters]
        spec = geo.spec
        self.planes = spec.cut_planes()
        self.source = spec.mirror_of()
        self.fraction = {i: spec.pile_fraction(i) for i in spec.kept_piles()}
        body = pb.body("structure")
        x, u, s = ufl.SpatialCoordinate(body.mesh), body.u, body.qp.stress
        r2 = 1.0 / math.sqrt(2.0)
        sxz, syz, szz = r2 * s[4], r2 * s[5], s[2]
        vals = ufl.as_vector([sxz, syz, szz, x[0] * szz, x[1] * szz, x[0] * syz - x[1] * sxz,
                              u[0], u[1], 1.0])
        D = fem.functionspace(body.mesh, ("DG", 0, (9,)))
        dx = ufl.Measure("dx", domain=body.mesh,
                         metadata={"quadrature_degree": body.qp.degree})
        self._form = fem.form(ufl.inner(vals, ufl.TestFunction(D)) * dx)
        self.rows: dict[str, list[str]] = {"bending": [], "heads": [], "max": []}
        self._zero: dict[str, np.ndarray] = {}
        self._nodes = self._pile_nodes(body.V) if pb.interface is not None else {}

    def _pile_nodes(self, V: fem.FunctionSpace) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Meshed pile -> (its owned structure nodes, their arms from the head centre, m)."""
        x = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local]
        out = {}
        for i in self.fraction:
            xp, yp = self.xy[i - 1]
            on = np.flatnonzero(np.hypot(x[:, 0] - xp, x[:, 1] - yp)
                                <= self.radius[i - 1] * 1.001 + _TOL)
            out[i] = (on, x[on] - np.array([xp, yp, 0.0]))
        return out

    # ------------------------------------------------------------------ quantities
    def sections(self) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Meshed pile -> (depths, (n, 6) section actions Vx, Vy, -N, Mx, My, T, (n, 2) ux, uy).

        Of the meshed part of the pile (collective: one all-reduce for every pile).
        """
        cellvals = fem.assemble_vector(self._form).array.reshape(-1, 9)
        levels, local = {}, []
        for i in self.fraction:
            cells, zc, levels[i] = self.piles.element_layers(i)
            below = zc < 0.0
            acc = np.zeros((levels[i].size, 9))
            np.add.at(acc, np.searchsorted(-levels[i], -zc[below]), cellvals[cells[below]])
            local.append(acc)
        sums = np.split(self.comm.allreduce(np.concatenate(local), op=MPI.SUM),
                        np.cumsum([a.shape[0] for a in local])[:-1])
        out = {}
        for i, acc in zip(self.fraction, sums, strict=True):
            S = acc / PileProbe.layer_heights(levels[i])[:, None]
            vol = np.where(acc[:, 8:9] > 0.0, acc[:, 8:9], 1.0)
            xp, yp = self.xy[i - 1]
            act = np.column_stack([S[:, 0], S[:, 1], S[:, 2], S[:, 4] - yp * S[:, 2],
                                   -(S[:, 3] - xp * S[:, 2]),
                                   S[:, 5] - xp * S[:, 1] + yp * S[:, 0]])
            out[i] = (-levels[i], act, acc[:, 6:8] / vol)
        return out

    def heads(self) -> dict[int, np.ndarray]:
        """Meshed pile -> the cap's action on its meshed part at the head (6,), interface only.

        Minus the soil's force and moment (about the head centre) through the interface on the
        pile's nodes (collective).
        """
        f = self.pb.interface_force()
        loc = np.array([np.concatenate([f[on].sum(axis=0), np.cross(arm, f[on]).sum(axis=0)])
                        for on, arm in self._nodes.values()])
        tot = -self.comm.allreduce(loc, op=MPI.SUM)
        return dict(zip(self._nodes, tot, strict=True))

    def _whole(self, i: int, v: np.ndarray, table: dict[str, tuple[int, ...]],
               share: bool = True) -> np.ndarray:
        """Pile ``i`` of the whole foundation from the value ``v`` of its meshed image.

        ``share``: ``v`` is the meshed part's share of a resultant (over the meshed fraction);
        else a mean, the same for the whole pile.
        """
        src = self.source[i]
        v = np.asarray(v, dtype=float) / (self.fraction[src] if share else 1.0)
        return _symmetrise(v, _on_planes(self.planes, self.xy[src - 1]),
                           _sign_flips(self.planes, self.xy[i - 1], self.xy[src - 1]), table)

    def _change(self, key: str, v: np.ndarray) -> np.ndarray:
        """``v`` minus its value at the first output time (set then)."""
        return v - self._zero.setdefault(key, v.copy())

    def write(self, t: float, stage: str) -> None:
        """Export protocol: every pile's sections, head and largest moment at ``t``."""
        secs = self.sections()
        heads = self.heads() if self.pb.interface is not None else None
        for i in range(1, len(self.xy) + 1):
            depth, act, defl = secs[self.source[i]]
            act = self._change(f"s{i}", self._whole(i, act, ANTISYMMETRIC))
            defl = self._whole(i, defl, _DEFLECTION_ANTISYMMETRIC, share=False)
            self.rows["bending"] += [
                f"{t:.6g},{i},{d:.6g},{-a[2]:.9g},{a[0]:.9g},{a[1]:.9g},{a[3]:.9g},{a[4]:.9g},"
                f"{a[5]:.9g},{u[0]:.9g},{u[1]:.9g}" for d, a, u in zip(depth, act, defl,
                                                                      strict=True)]
            if heads is not None:
                head = self._change(f"h{i}", self._whole(i, heads[self.source[i]],
                                                         ANTISYMMETRIC))
                hd = 0.0
            else:
                head, hd = act[0], depth[0]
            x, y = self.xy[i - 1]
            self.rows["heads"].append(
                f"{t:.6g},{i},{x:.6g},{y:.6g},{-head[2]:.9g},{head[0]:.9g},{head[1]:.9g},"
                f"{head[3]:.9g},{head[4]:.9g},{head[5]:.9g},{hd:.6g}")
            m = np.hypot(act[:, 3], act[:, 4])
            cand = np.concatenate([[math.hypot(head[3], head[4])], m])
            where = np.concatenate([[hd], depth])
            j = int(np.argmax(cand))
            self.rows["max"].append(f"{t:.6g},{i},{cand[j]:.9g},{where[j]:.6g}")
        self._write()

    def _write(self) -> None:
        if self.comm.rank != 0:
            return
        for name, head, key in (("pile_bending.csv", BENDING_COLUMNS, "bending"),
                                ("pile_heads.csv", HEAD_COLUMNS, "heads"),
                                ("pile_max_moment.csv", MAX_MOMENT_COLUMNS, "max")):
            write_text_atomic(self.out / name, "\n".join([head, *self.rows[key]]) + "\n")

    def close(self) -> None:
        """Nothing stays open (every table is rewritten atomically at each write)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the rows and the first output time's values."""
        return {"rows": {k: list(v) for k, v in self.rows.items()},
                "zero": {k: v.tolist() for k, v in self._zero.items()}}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.rows = {k: list(v) for k, v in data["rows"].items()}
        self._zero = {k: np.array(v, dtype=float) for k, v in data["zero"].items()}


class CapMotion:
    """``cap_motion.csv``: the loaded face's rigid motion at the action point (module doc).

    An export: rank 0 rewrites the file at every :meth:`write`.
    """

    def __init__(self, sc: Scenario, geo: ResolvedGeometry, pb: BiotProblem, out: Path) -> None:
        self.centre, self.point = np.array(sc.load_centre()), np.array(sc.action_point())
        self.probe = FaceMotion(pb, loaded_facets(sc, pb.md), self.centre)
        self.planes = geo.spec.cut_planes()
        self.path, self.comm = Path(out) / "cap_motion.csv", pb.comm
        self.rows: list[str] = []

    def __call__(self) -> np.ndarray:
        """(ux, uy, uz, rx, ry, rz) at the action point (m, rad; collective)."""
        v = _symmetrise(self.probe(), self.planes, (), ANTISYMMETRIC)
        v[:3] += np.cross(v[3:], self.point - self.centre)
        return v

    def write(self, t: float, stage: str) -> None:
        """Export protocol: the motion at ``t``."""
        v = self()
        self.rows.append(f"{t:.6g}," + ",".join(f"{a:.9g}" for a in v))
        if self.comm.rank == 0:
            write_text_atomic(self.path, "\n".join([CAP_MOTION_COLUMNS, *self.rows]) + "\n")

    def close(self) -> None:
        """Nothing stays open."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the rows."""
        return {"rows": list(self.rows)}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.rows = list(data["rows"])


__all__ = ["CapMotion", "PileSections"]
