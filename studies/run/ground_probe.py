"""Ground movement around the piles: neutral plane, dragload, downdrag, free field and trough.

:class:`GroundProbe` (an export) writes at every output time, for the whole foundation:

* ``neutral_plane.csv``: per pile, the neutral plane (the depth of the largest axial force, where
  the shaft friction changes from negative above to positive below), the dragload (largest axial
  force minus the head load), the downdrag (the pile's settlement at the neutral plane), and the
  head load and settlement (:func:`~pilegroup.studies.results.downdrag.neutral_plane`);
* ``settlement_profiles.csv``: per pile, at the element-layer mid-heights of its shaft, the
  axial force, the pile's settlement (mean over the element layer) and the settlement of the
  soil beside it (the pile's minus the interface's relative displacement), and, with ``pile =
  0``, the free field: the soil's settlement along the vertical farthest from the piles in the
  modelled block (a corner; the block's sides are on rollers, so it settles as a wide site);
  and the excess pore pressure in the soil at the shaft (free field: on that vertical). Piles
  installed after the start (an ``installation`` stage) settle from then on, and so does the
  soil beside them (the interface's jump counts from then) and, from then on, the free field:
  the settlements of the unified method's diagram since the installation;
* ``surface_trough.csv``: the ground surface's settlement along the line through the group's
  centre parallel to x, across the whole block (points inside a pile left out).

These are the two diagrams of Fellenius' unified method (axial force and settlement against
depth; docs/model.md, "Ground that moves"). Depths m below the ground surface, positive down;
settlements m, down positive; forces kN, compression positive. Every number is all-reduced;
rank 0 writes.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.model import Scenario
from pilegroup.solver import BiotProblem
from pilegroup.solver.probes import PointSampler
from pilegroup.studies.results.downdrag import neutral_plane
from pilegroup.studies.results.tables import (
    NEUTRAL_PLANE_COLUMNS,
    SETTLEMENT_PROFILE_COLUMNS,
    TROUGH_COLUMNS,
)
from pilegroup.studies.run.pile_probe import PileProbe

#: Points of the free-field vertical and of the surface trough.
N_FREE_FIELD, N_TROUGH = 61, 121


class GroundProbe:
    """The downdrag tables of a run (see the module doc); an export.

    Args:
        sc: the scenario.
        pb: the problem.
        piles: the run's :class:`~pilegroup.studies.run.pile_probe.PileProbe` (pile numbering,
            mirror images, axial force and interface profiles).
        out: output folder.
    """

    def __init__(self, sc: Scenario, pb: BiotProblem, piles: PileProbe, out: Path) -> None:
        self.piles, self.out = piles, Path(out)
        self.comm = pb.comm
        soil = pb.body("soil")
        x = soil.mesh.geometry.x
        lo = [self.comm.allreduce(float(x[:, k].min(initial=np.inf)), op=MPI.MIN)
              for k in range(2)]
        hi = [self.comm.allreduce(float(x[:, k].max(initial=-np.inf)), op=MPI.MAX)
              for k in range(2)]
        inset = [1e-6 * (b - a) for a, b in zip(lo, hi, strict=True)]
        corners = [(cx, cy) for cx in (lo[0] + inset[0], hi[0] - inset[0])
                   for cy in (lo[1] + inset[1], hi[1] - inset[1])]
        far = max(corners, key=lambda c: np.min(np.hypot(*(piles.xy - np.array(c)).T)))
        self.free_depth = np.linspace(0.0, sc.site.depth_m, N_FREE_FIELD)
        self._free = PointSampler(soil.u, np.column_stack(
            [np.full(N_FREE_FIELD, far[0]), np.full(N_FREE_FIELD, far[1]), -self.free_depth]))
        half = sc.site.size_x_m / 2
        self.trough_x = np.linspace(-half, half, N_TROUGH)
        y0 = float(np.clip(piles.xy[:, 1].mean(), lo[1], hi[1]))
        # a model reduced about x = 0 holds x >= 0: the trough's other half is its mirror image
        xs = np.abs(self.trough_x) if lo[0] > -1e-9 * half else self.trough_x
        self._trough = PointSampler(soil.u, np.column_stack(
            [xs, np.full(N_TROUGH, y0), np.zeros(N_TROUGH)]))
        self.rows: dict[str, list[str]] = {"plane": [], "profiles": [], "trough": []}
        #: the piles' installation stage (a scenario that installs them after the start): from
        #: it on the free field's settlement counts from its value then, as the piles' does
        self._install = None if sc.installation_stage is None else sc.installation_stage.name
        self._free_origin: np.ndarray | None = None
        self._p = pb.layout.p
        self._free_p = PointSampler(self._p, self._free.pts)
        self._shaft_p: dict[int, PointSampler] = {}

    def _shaft_pressure(self, k: int, depth: np.ndarray) -> np.ndarray:
        """Excess pore pressure (kPa) in the soil at pile ``k``'s shaft at ``depth`` (collective).

        Sampled just outside the shaft (0.1 % of the meshed radius, beyond the polygon's corner)
        on the side at 45 degrees to x and y, which a reduced model keeps (it holds x >= 0 and
        y >= 0 about its mirror planes).
        """
        if k not in self._shaft_p:
            x, y = self.piles.xy[k - 1]
            rho = self.piles.radii[k - 1] * 1.001 / np.sqrt(2.0)
            self._shaft_p[k] = PointSampler(self._p, np.column_stack(
                [np.full(depth.size, x + rho), np.full(depth.size, y + rho), -depth]))
        return self._shaft_p[k]()

    def write(self, t: float, stage: str) -> None:
        """Export protocol: every table at output time ``t`` (collective)."""
        p = self.piles
        fields = p.nodal_fields()
        per_source = {}
        for k, (depth, N) in p.load_forces().items():
            _, s_pile = p.settlement(k)
            s_soil = s_pile.copy()
            if fields is not None:
                dz, _, rel = p.interface_profile(k, fields)
                if dz.size > 1:
                    s_soil = s_pile - np.interp(depth, dz, rel)
            per_source[k] = (depth, N, s_pile, s_soil,
                             np.atleast_1d(self._shaft_pressure(k, depth)))
        for i in range(1, len(p.xy) + 1):
            depth, N, s_pile, s_soil, u = per_source[p.source[i]]
            if not depth.size:
                continue
            npl = neutral_plane(depth, N, s_pile, s_soil)
            self.rows["plane"].append(
                f"{t:.6g},{i},{npl.depth_m:.6g},{npl.dragload_kN:.9g},{npl.downdrag_m:.9g},"
                f"{npl.head_load_kN:.9g},{npl.max_force_kN:.9g},{s_pile[0]:.9g}")
            self.rows["profiles"] += [f"{t:.6g},{i},{a:.6g},{b:.9g},{c:.9g},{d:.9g},{_num(e)}"
                                      for a, b, c, d, e in zip(depth, N, s_pile, s_soil, u,
                                                               strict=True)]
        free, free_p = -self._free()[:, 2], self._free_p()
        if stage == self._install:
            self._free_origin = free.copy()
        if self._free_origin is not None:
            free = free - self._free_origin
        self.rows["profiles"] += [f"{t:.6g},0,{a:.6g},,,{b:.9g},{_num(c)}"
                                  for a, b, c in zip(self.free_depth, free, free_p, strict=True)
                                  if np.isfinite(b)]
        trough = -self._trough()[:, 2]  # NaN inside a pile: not a point of the ground
        self.rows["trough"] += [f"{t:.6g},{a:.6g},{b:.9g}"
                                for a, b in zip(self.trough_x, trough, strict=True)
                                if np.isfinite(b)]
        self._write()

    def _write(self) -> None:
        if self.comm.rank != 0:
            return
        for name, head, key in (("neutral_plane.csv", NEUTRAL_PLANE_COLUMNS, "plane"),
                                ("settlement_profiles.csv", SETTLEMENT_PROFILE_COLUMNS,
                                 "profiles"),
                                ("surface_trough.csv", TROUGH_COLUMNS, "trough")):
            write_text_atomic(self.out / name, "\n".join([head, *self.rows[key]]) + "\n")

    def close(self) -> None:
        """Nothing stays open (every table is rewritten atomically at each write)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: every table's rows."""
        return {"rows": {k: list(v) for k, v in self.rows.items()},
                "free_origin": None if self._free_origin is None else self._free_origin.tolist()}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.rows = {k: list(v) for k, v in data["rows"].items()}
        origin = data.get("free_origin")
        self._free_origin = None if origin is None else np.array(origin, dtype=float)

    def summary(self) -> list[dict[str, float]]:
        """The last output time's neutral plane of every pile (for ``summary.json``)."""
        keys = NEUTRAL_PLANE_COLUMNS.split(",")
        last = self.rows["plane"][-len(self.piles.xy):] if self.rows["plane"] else []
        return [dict(zip(keys, map(float, r.split(",")), strict=True)) for r in last]


def _num(v: float) -> str:
    """A CSV cell: the number, or empty where it does not exist (NaN)."""
    return f"{v:.9g}" if np.isfinite(v) else ""
