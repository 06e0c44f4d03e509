"""Pile results of a run: axial force, shaft friction and pile-soil relative displacement.

Conventions of the CSV files (studies/report/run_report.py reads them): depth in m below the ground
surface
(z = 0), positive down; axial force kN, compression positive; shaft friction kPa, positive when
the soil supports the pile (upward shear on the pile); relative displacement m, pile settlement
minus adjacent soil settlement (positive = the pile moves down relative to the soil).

* Axial force of pile ``i`` at the mid-height of each element layer of the pile:
  ``N = -(1/dz) sum_cells volume * mean(sigma_zz)`` (the exact cross-section mean of the cell
  averages of the pile's stress; stresses tension positive), minus its value after the
  geostatic stage (the wished-in-place pile starts with the in-situ stress of the soil it
  replaces): the force due to the loads, as the paper's strain gauges measure it.
* With the interface: shaft friction and relative displacement are the area-weighted means of
  the nodal interface state (``shear_traction_vertical``, ``slip_vertical``) over the ring of
  interface nodes at each node level; the stations are the node levels. Tied piles have no
  slip: the relative displacement is 0 and the friction is ``(dN/dz) / (pi d)`` at the element
  layer mid-heights (``d`` the pile's own diameter).
* Layer means per pile and soil layer: area-weighted over the layer's shaft interface nodes of
  that pile; the centre pile after every step (``layer_history.csv``), every pile at the output
  times (``interface_layers.csv``); a layer's depths are those of the pile's shaft in it (the
  toe ends the layer the pile ends in). Normal traction: effective, kPa, tension positive;
  viscoplastic slip: magnitude, m.
* The head force of each pile (``pile_loads.csv``, ``pile_heads.csv``) is
  :mod:`pilegroup.studies.run.section_probe`'s; :meth:`PileProbe.load_forces` (the capacity
  curves of single piles) reads the top element layer.

Every pile of the foundation is reported. In a symmetry-reduced model a pile outside the mesh
takes the values of its mirror image, and a pile cut by a plane reports its meshed section's
force divided by the meshed fraction (1/2 or 1/4); means over a cut pile's interface nodes are
those of the whole ring by symmetry.

Every number is all-reduced over the ranks; rank 0 writes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from dolfinx import mesh as dmesh
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.geometry import groups
from pilegroup.geometry.adapter import ResolvedGeometry
from pilegroup.geometry.plan import meshed_radii
from pilegroup.model import Scenario
from pilegroup.solver import BiotProblem
from pilegroup.solver.probes import SettlementProbe
from pilegroup.studies.results.tables import (
    LAYER_COLUMNS,
    LOAD_SETTLEMENT_COLUMNS,
    PROFILE_COLUMNS,
    SETTLEMENT_COLUMNS,
)


def _sum(comm: MPI.Comm, a: np.ndarray) -> np.ndarray:
    return comm.allreduce(a, op=MPI.SUM)


class PileProbe:
    """Collects pile profiles and per-layer histories during a run.

    An export (:class:`~pilegroup.solver.exports.Export`): :meth:`write` at every output time;
    :meth:`record_step` after every accepted step adds the centre pile's layer means.

    Args:
        sc: the scenario (pile positions and diameters, layers).
        geo: its resolved geometry (which piles the mesh holds, and in which fraction).
        pb: the :class:`~pilegroup.solver.problem.BiotProblem`.
        out: output folder for the CSV files.
    """

    def __init__(self, sc: Scenario, geo: ResolvedGeometry, pb: BiotProblem, out: Path) -> None:
        self.sc, self.pb, self.out = sc, pb, Path(out)
        self.comm = pb.comm
        self.xy = np.array(sc.piles.xy, dtype=float)
        #: every pile's diameter (m), aligned with ``xy`` (pile i at index i - 1)
        self.diameters = np.array(sc.piles.diameters, dtype=float)
        #: every pile's meshed circumradius (m): its polygon's corners lie on it
        self.radii = np.array(meshed_radii(geo.spec), dtype=float)
        # every pile of the foundation from its mirror image in a symmetry-reduced mesh, whose
        # cut piles carry their meshed fraction of the load
        spec = geo.spec
        self.source = spec.mirror_of()
        self.fraction = {i: spec.pile_fraction(i) for i in spec.kept_piles()}
        c = self.xy.mean(axis=0)
        self.centre = int(np.argmin(np.linalg.norm(self.xy - c, axis=1))) + 1
        tops = np.concatenate([[0.0], -np.cumsum([lay.thickness_m or np.inf
                                                  for lay in sc.layers])])
        self._layer_tops = tops
        body = pb.body("structure")  # the whole mesh when tied
        self.body = body
        tdim = body.mesh.topology.dim
        D0 = fem.functionspace(body.mesh, ("DG", 0))
        vol = fem.assemble_vector(fem.form(ufl.TestFunction(D0) * ufl.dx))
        self._vol = vol.array
        self._uz_form = fem.form(body.u[2] * ufl.TestFunction(D0) * ufl.dx)
        # element layers of each pile: (pile, z_mid) bins, global
        self._pile_cells: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for g in body.qp.groups:
            i = groups.pile_of(g.name)
            if i is None:
                continue
            zc = dmesh.compute_midpoints(body.mesh, tdim, g.cells)[:, 2] if g.cells.size \
                else np.zeros(0)
            self._pile_cells[i] = (g.cells, np.round(zc, 6))
        self._levels = {}
        for i in self.fraction:
            zc = self._pile_cells.get(i, (None, np.zeros(0)))[1]
            allz = np.unique(np.concatenate(self.comm.allgather(zc)))
            self._levels[i] = allz[allz < 0.0][::-1]  # below ground, top down
        self._itf = pb.interface
        if self._itf is not None:
            V = pb.body("soil").V
            nloc = V.dofmap.index_map.size_local
            x = V.tabulate_dof_coordinates()
            owned = np.arange(x.shape[0]) < nloc
            self._x = x
            r = np.linalg.norm(x[:, None, :2] - self.xy[None, :, :], axis=2)
            # a node is on pile k's shaft within its meshed radius (+0.1 %): piles do not overlap
            on = (r < self.radii[None, :] * 1.001) & owned[:, None] \
                & (self._itf.A[:, None] > 0)
            self._node_pile = np.where(on.any(axis=1), np.argmax(on, axis=1) + 1, 0)
        self.profile_rows: list[str] = []
        self.layer_rows: list[str] = []
        self.pile_layer_rows: list[str] = []
        self._last_step_t: float | None = None
        self._N0: dict[int, np.ndarray] = {}

    # ------------------------------------------------------------------ quantities
    def axial_force(self, i: int, averages: dict | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
        """(depth of the element-layer mid-heights, axial force kN) of pile ``i``.

        ``averages``: the structure's ``cell_average("stress")`` when already computed.
        """
        levels = self._levels[i]
        cells, zc = self._pile_cells.get(i, (np.zeros(0, np.int32), np.zeros(0)))
        if averages is None:
            averages = self.body.qp.cell_average("stress")
        avg = averages.get(groups.pile(i))
        loc = np.zeros(levels.size)
        if avg is not None and cells.size:
            below = zc < 0.0  # the embedded part inside the cap is not a pile section
            szz = avg[1][below, 2]
            k = np.searchsorted(-levels, -zc[below])
            np.add.at(loc, k, self._vol[cells[below]] * szz)
        tot = _sum(self.comm, loc)
        edges = self.layer_heights(levels)
        return -levels, -tot / edges

    @staticmethod
    def layer_heights(levels: np.ndarray) -> np.ndarray:
        """Element-layer heights from their mid-heights (top down, contiguous layers)."""
        h = np.zeros(levels.size)
        top = 0.0
        for k, zm in enumerate(levels):
            h[k] = 2.0 * (top - zm)
            top -= h[k]
        return h

    def _layer_of(self, depth: np.ndarray) -> np.ndarray:
        return np.searchsorted(-self._layer_tops, depth, side="right")

    def interface_profile(self, i: int, fields: dict | None = None
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(node depths, friction kPa, relative displacement m) on the shaft of pile ``i``.

        ``fields``: the interface's ``nodal_fields()`` when already computed.
        """
        f = fields if fields is not None else self._itf.nodal_fields()
        # every node of the ground-surface ring: its z is 0 up to the mesh's round-off, whose
        # sign differs between nodes, builds and partitions
        mask = (self._node_pile == i) & (np.round(self._x[:, 2], 6) <= 0.0)
        shaft_w = self._itf.W[:, : self._itf.split.n_layers].sum(axis=1)
        mask &= shaft_w > 0
        z = np.round(self._x[mask, 2], 6)
        allz = np.unique(np.concatenate(self.comm.allgather(z)))[::-1]
        k = np.searchsorted(-allz, -z)
        w = shaft_w[mask]
        acc = np.zeros((3, allz.size))
        np.add.at(acc[0], k, w)
        np.add.at(acc[1], k, w * f["shear_traction_vertical"][mask, 0])
        np.add.at(acc[2], k, w * f["slip_vertical"][mask, 0])
        acc = _sum(self.comm, acc)
        wsum = np.where(acc[0] > 0, acc[0], 1.0)
        return -allz, acc[1] / wsum, acc[2] / wsum

    def layer_means(self) -> dict[int, dict[int, tuple[float, float, float, float]]]:
        """Per pile and layer (1-based): mean friction, relative displacement, vp slip, sigma_n.

        One pass over the interface's material points and one all-reduce for all piles.
        """
        L, P = self._itf.split.n_layers, len(self.xy)
        acc = np.zeros((P + 1, L, 5))  # row 0: points on no pile
        for m in range(L):
            pts = self._itf.material_points(m)
            st = pts["state"]
            if st is None:
                continue
            w = pts["weight"]  # 0 where another rank owns the point
            vals = np.column_stack([w, w * st["traction"][:, 1], w * pts["jump_local"][:, 1],
                                    w * np.linalg.norm(st["slip_vp"], axis=1),
                                    w * st["traction"][:, 0]])
            np.add.at(acc[:, m], self._node_pile[pts["node"]], vals)
        acc = _sum(self.comm, acc)
        return {i: {m + 1: tuple(acc[i, m, 1:] / acc[i, m, 0]) for m in range(L)
                    if acc[i, m, 0] > 0} for i in range(1, P + 1)}

    def load_forces(self, averages: dict | None = None
                    ) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """Per meshed pile: (depths, axial force kN due to the loads, of the whole pile).

        The force after the geostatic stage (the first call) is subtracted; a cut pile's
        meshed section is scaled to the whole pile. Collective.
        """
        if averages is None:
            averages = self.body.qp.cell_average("stress")
        forces = {}
        for k in self.fraction:
            dN, N = self.axial_force(k, averages)
            forces[k] = (dN, (N - self._N0.setdefault(k, N.copy())) / self.fraction[k])
        return forces

    def settlement(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """(depths of the element-layer mid-heights, mean settlement m) of meshed pile ``i``.

        The volume mean of the pile's vertical displacement over each element layer, down
        positive (collective).
        """
        levels = self._levels[i]
        cells, zc = self._pile_cells.get(i, (np.zeros(0, np.int32), np.zeros(0)))
        vec = fem.assemble_vector(self._uz_form)
        acc = np.zeros((2, levels.size))
        below = zc < 0.0
        k = np.searchsorted(-levels, -zc[below])
        np.add.at(acc[0], k, self._vol[cells[below]])
        np.add.at(acc[1], k, vec.array[cells[below]])
        acc = _sum(self.comm, acc)
        return -levels, -acc[1] / np.where(acc[0] > 0, acc[0], 1.0)

    def nodal_fields(self) -> dict[str, np.ndarray] | None:
        """The interface's nodal fields (``None`` for tied piles); collective."""
        return self._itf.nodal_fields() if self._itf is not None else None

    # ------------------------------------------------------------------ recording
    def record_output(self, t: float) -> None:
        """Profiles of every pile at output time ``t`` (collective)."""
        averages = self.body.qp.cell_average("stress")
        fields = self.nodal_fields()
        forces = self.load_forces(averages)
        for i in range(1, len(self.xy) + 1):
            dN, N = forces[self.source[i]]
            if self._itf is not None:
                dz, fr, rel = self.interface_profile(self.source[i], fields)
                Nz = np.interp(dz, dN, N) if N.size else np.zeros_like(dz)
            else:
                dz, Nz = dN, N
                fr = -np.gradient(N, dN) / (math.pi * self.diameters[i - 1]) if N.size > 1 \
                    else np.zeros_like(N)
                rel = np.zeros_like(N)
            lay = self._layer_of(dz)
            self.profile_rows += [f"{t:.6g},{i},{a:.6g},{b},{c:.9g},{e:.9g},{f:.9g}"
                                  for a, b, c, e, f in zip(dz, lay, Nz, fr, rel, strict=True)]
        if self._itf is not None:
            means = self.layer_means()
            for i in range(1, len(self.xy) + 1):
                self.pile_layer_rows += self._layer_rows(t, i, means[self.source[i]])
        self._write()

    def write(self, t: float, stage: str) -> None:
        """Export protocol: the step's layer means and every pile's tables at ``t``."""
        self.record_step(t)
        self.record_output(t)

    def close(self) -> None:
        """Nothing stays open (every table is rewritten atomically at each write)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: every table's rows, the geostatic forces, the last step."""
        rows = {k: list(v) for k, v in vars(self).items() if k.endswith("_rows")}
        return {"rows": rows, "N0": {str(k): v.tolist() for k, v in self._N0.items()},
                "last_step_t": self._last_step_t}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state` (the tables are rewritten at the next write)."""
        for k, v in data["rows"].items():
            setattr(self, k, list(v))
        self._N0 = {int(k): np.array(v, dtype=float) for k, v in data["N0"].items()}
        self._last_step_t = data["last_step_t"]

    def record_step(self, t: float) -> None:
        """Layer means of the centre pile after an accepted step (collective)."""
        if self._itf is None or t == self._last_step_t:
            return
        self._last_step_t = t
        means = self.layer_means()[self.source[self.centre]]
        self.layer_rows += self._layer_rows(t, self.centre, means)

    def _layer_rows(self, t: float, i: int, means: dict) -> list[str]:
        """CSV rows (``LAYER_COLUMNS``) of pile ``i``'s layer ``means`` at time ``t``.

        A layer's depths are those of pile ``i``'s shaft in it: the bottom is the pile's toe
        where the pile ends in the layer.
        """
        rows = []
        toe = self.sc.piles.lengths[i - 1]
        for j, (fr, rel, vp, sn) in means.items():
            lay = self.sc.layers[j - 1]
            top, bot = 0.0 - self._layer_tops[j - 1], 0.0 - self._layer_tops[j]
            top, bot = min(top, toe), min(bot, toe)
            rows.append(f"{t:.6g},{i},{j},{lay.name},{top:.6g},{bot:.6g},{fr:.9g},"
                        f"{rel:.9g},{vp:.9g},{sn:.9g}")
        return rows

    def _write(self) -> None:
        if self.comm.rank != 0:
            return
        for name, head, rows in (("pile_profiles.csv", PROFILE_COLUMNS, self.profile_rows),
                                 ("layer_history.csv", LAYER_COLUMNS, self.layer_rows),
                                 ("interface_layers.csv", LAYER_COLUMNS, self.pile_layer_rows)):
            if rows:
                write_text_atomic(self.out / name, "\n".join([head, *rows]) + "\n")


class SettlementSeries:
    """``settlement.csv``: mean settlement (m, down positive) of facet groups at output times.

    An export: rank 0 rewrites the file atomically at every :meth:`write`.
    """

    def __init__(self, problem: BiotProblem, names: Sequence[str], path: Path) -> None:
        self.probe = SettlementProbe(problem, names)
        self.path = Path(path)
        self.comm = problem.comm
        self.history: list[tuple[float, str, float]] = []

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the settlement history."""
        return {"history": [list(h) for h in self.history]}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.history = [(float(t), str(s), float(w)) for t, s, w in data["history"]]

    def write(self, t: float, stage: str) -> None:
        """Record the settlement at ``t`` and rewrite the file."""
        self.history.append((t, stage, self.probe()))
        if self.comm.rank == 0:
            lines = [SETTLEMENT_COLUMNS] + [f"{a:.6g},{b},{c:.9g}" for a, b, c in self.history]
            write_text_atomic(self.path, "\n".join(lines) + "\n")

    def close(self) -> None:
        """Nothing stays open."""


class LoadSettlementCurve:
    """``load_settlement.csv``: load on the foundation against settlement, every accepted step.

    :meth:`record` after every accepted step and :meth:`write` (export protocol) at the output
    times add a point (once per time); rank 0 rewrites the file each time, so a run that stops
    (no equilibrium beyond some load) leaves the curve it reached.
    """

    def __init__(self, problem: BiotProblem, probe: SettlementProbe, total_load_kN: float,
                 path: Path) -> None:
        self.problem, self.probe, self.total = problem, probe, total_load_kN
        self.path = Path(path)
        self.rows: list[str] = []
        self._last_t: float | None = None

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the rows and the time of the last one."""
        return {"rows": list(self.rows), "last_t": self._last_t}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.rows, self._last_t = list(data["rows"]), data["last_t"]

    def record(self, t: float, stage: str) -> None:
        """Add the current point (collective: the settlement is all-reduced)."""
        if t == self._last_t:
            return
        self._last_t = t
        lam = self.problem.load_factor
        self.rows.append(f"{t:.6g},{stage},{lam:.9g},{lam * self.total:.9g},{self.probe():.9g}")
        if self.problem.comm.rank == 0:
            write_text_atomic(self.path, "\n".join([LOAD_SETTLEMENT_COLUMNS, *self.rows]) + "\n")

    def write(self, t: float, stage: str) -> None:
        """Export protocol: the point at an output time."""
        self.record(t, stage)

    def close(self) -> None:
        """Nothing stays open."""

