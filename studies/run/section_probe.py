"""Pile sections and cap motion: what a lateral design reads off a run.

Sign conventions (global axes, x and y horizontal, z up; moments by the right-hand rule):

* A **section** of a pile at depth ``d`` carries the action of the part above on the part
  below: shear ``Vx``, ``Vy`` (kN), axial force ``N`` (kN, compression positive), bending
  moments ``Mx``, ``My`` about the section centre on the pile axis and torque ``T`` (kN m): for
  a stress ``sigma`` on the section, ``Vx = int sigma_xz``, ``Vy = int sigma_yz``, ``N = -int
  sigma_zz``, ``Mx = int (y - y_p) sigma_zz``, ``My = -int (x - x_p) sigma_zz``, ``T = int
  ((x - x_p) sigma_yz - (y - y_p) sigma_xz)``. Sections are the planes of the pile's mesh: the
  **head** (depth 0, the ground surface, where the pile enters the cap, or its loaded top
  without a cap) and every element-layer boundary down to the toe. Each is the force the
  cells above the plane exert on its nodes (:mod:`pilegroup.studies.run.plane_sections`): the
  finite element's own equilibrium of the pile below the plane, exact to the Newton residual,
  for tied piles as for piles with an interface. The head is the cap's action on the pile:
  the heads balance the applied actions. ``ux``, ``uy`` (m): the deflection of the pile axis
  at the plane.
* ``pile_bending.csv`` holds every section, ``pile_heads.csv`` the head (``depth_m`` 0),
  ``pile_max_moment.csv`` the largest resultant ``sqrt(Mx^2 + My^2)`` of the same rows and
  its depth, ``pile_loads.csv`` the head's axial force (the same number as ``pile_heads.csv``'s
  ``N_kN``).
* Every force and moment is the change since the first output time (the geostatic state), as
  the axial force of ``pile_profiles.csv``: the effect of the loads and of the ground's
  movement.
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

from pathlib import Path
from typing import Any

import numpy as np

from pilegroup.errors import ScenarioError
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
    LOAD_COLUMNS,
    MAX_MOMENT_COLUMNS,
)
from pilegroup.studies.run.cap_loads import loaded_facets
from pilegroup.studies.run.pile_probe import PileProbe
from pilegroup.studies.run.plane_sections import PlaneForces

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
    """``pile_bending.csv``, ``pile_heads.csv``, ``pile_max_moment.csv``, ``pile_loads.csv``.

    One recovery for all four (module docstring): the sections of
    :class:`~pilegroup.studies.run.plane_sections.PlaneForces`, the head its first. An export:
    :meth:`write` at every output time rewrites the files.
    """

    def __init__(self, sc: Scenario, geo: ResolvedGeometry, pb: BiotProblem,
                 piles: PileProbe, out: Path) -> None:
        self.out, self.comm = Path(out), pb.comm
        self.xy = [tuple(map(float, p)) for p in sc.piles.xy]
        spec = geo.spec
        self.planes = spec.cut_planes()
        self.source = spec.mirror_of()
        self.fraction = {i: spec.pile_fraction(i) for i in spec.kept_piles()}
        self.forces = PlaneForces(sc, pb, list(self.fraction), list(piles.radii))
        self.rows: dict[str, list[str]] = {"bending": [], "heads": [], "max": []}
        self._zero: dict[str, np.ndarray] = {}

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
        secs = self.forces()
        for i in range(1, len(self.xy) + 1):
            depth, act, defl = secs[self.source[i]]
            act = self._change(f"plane{i}", self._whole(i, act, ANTISYMMETRIC))
            defl = self._whole(i, defl, _DEFLECTION_ANTISYMMETRIC, share=False)
            self.rows["bending"] += [
                f"{t:.6g},{i},{d:.6g},{-a[2]:.9g},{a[0]:.9g},{a[1]:.9g},{a[3]:.9g},{a[4]:.9g},"
                f"{a[5]:.9g},{u[0]:.9g},{u[1]:.9g}" for d, a, u in zip(depth, act, defl,
                                                                      strict=True)]
            head = act[0]
            x, y = self.xy[i - 1]
            self.rows["heads"].append(
                f"{t:.6g},{i},{x:.6g},{y:.6g},{-head[2]:.9g},{head[0]:.9g},{head[1]:.9g},"
                f"{head[3]:.9g},{head[4]:.9g},{head[5]:.9g},{depth[0]:.6g}")
            m = np.hypot(act[:, 3], act[:, 4])
            j = int(np.argmax(m))
            self.rows["max"].append(f"{t:.6g},{i},{m[j]:.9g},{depth[j]:.6g}")
        self._write()

    def _write(self) -> None:
        if self.comm.rank != 0:
            return
        loads = [",".join(r.split(",")[:5] + ["0"]) for r in self.rows["heads"]]
        for name, head, rows in (("pile_bending.csv", BENDING_COLUMNS, self.rows["bending"]),
                                 ("pile_heads.csv", HEAD_COLUMNS, self.rows["heads"]),
                                 ("pile_max_moment.csv", MAX_MOMENT_COLUMNS, self.rows["max"]),
                                 ("pile_loads.csv", LOAD_COLUMNS, loads)):
            write_text_atomic(self.out / name, "\n".join([head, *rows]) + "\n")

    def close(self) -> None:
        """Nothing stays open (every table is rewritten atomically at each write)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the rows and the first output time's values."""
        return {"rows": {k: list(v) for k, v in self.rows.items()},
                "zero": {k: v.tolist() for k, v in self._zero.items()}}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`.

        A checkpoint of the element-layer means these files held before (its zeros named
        ``s1``, ``h1``, ...) cannot continue them: refused, the run is to be started again.
        """
        zero = data["zero"]
        if zero and not any(k.startswith("plane") for k in zero):
            raise ScenarioError("--resume", "checkpoint", "its pile sections are element-layer "
                                "means, which pile_bending.csv no longer holds; run again "
                                "without --resume")
        self.rows = {k: list(v) for k, v in data["rows"].items()}
        self._zero = {k: np.array(v, dtype=float) for k, v in zero.items()}


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
