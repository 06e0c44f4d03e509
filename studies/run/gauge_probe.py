"""Virtual strain gauges: the model's piles read the way the paper reads its test pile.

:class:`GaugeProbe` (an export) samples the section-mean axial strain of every pile at the
scenario's ``outputs.gauge_depths_m``, reduces it by the field method
(:func:`pilegroup.studies.results.gauges.field_reduction`, Eqs. 1-3) and writes, beside it, the
model's own values at the same sections and the error of the field method, to ``gauges.csv``
(columns in :mod:`pilegroup.studies.results.tables`) at every output time. docs/model.md ("Virtual
strain gauges") gives the conventions and why they were chosen:

* Strain: the pile's element layers are extruded prisms, so with the trilinear (Q1) displacement
  ``d u_z / d z`` does not vary with z inside a layer and its section mean equals the layer's
  volume mean ``(1/V) int d u_z/dz dV``: cell integrals, summed over the ranks. The layer means
  stand at the layer mid-heights (where they are the second-order-accurate strain of a smooth
  profile) and are interpolated linearly to the gauge depths (the end layers' values hold above
  the first and below the last mid-height). A sum of cell integrals is the same on any number of
  ranks up to rounding: no point search, no section split between ranks.
* Pile settlement at a depth (and ``w0`` at depth 0): the section-mean vertical displacement,
  exact for Q1 from the layer means of ``u_z`` and ``d u_z / d z``.
* ``A`` and ``U`` in Eqs. 1-2 are those the model's pile has: ``A`` its meshed section (volume
  over length: the polygon of the circle's area) and ``U`` the perimeter its shaft friction acts
  on (shaft facet area over length, times the interface's shaft factor: the circle's
  circumference; the polygon's with tied piles); ``E`` is the structure's modulus.
* The model's values: axial force from the pile stress (:meth:`PileProbe.axial_force`, force
  due to the loads), interface shear averaged over each gauge interval and pile-minus-soil
  displacement at each section (:meth:`PileProbe.interface_profile`); with tied piles the shear
  is ``-(1/U) dN/dz`` over the interval and the relative displacement 0.

Every pile of the foundation is reported: a pile outside a symmetry-reduced mesh takes its
mirror image's values; the means over a cut pile's meshed part are those of the whole pile by
symmetry (its ``A`` and ``U`` are the meshed part's divided by its fraction).
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import Any

import numpy as np
import ufl
from dolfinx import fem
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.geometry import groups
from pilegroup.model import Scenario
from pilegroup.solver import BiotProblem
from pilegroup.solver.probes import facet_area
from pilegroup.studies.results.gauges import field_reduction, interval_means
from pilegroup.studies.results.tables import GAUGE_COLUMNS, GAUGE_VALUES
from pilegroup.studies.run.pile_probe import PileProbe

log = logging.getLogger(__name__)


class GaugeProbe:
    """Writes ``gauges.csv``: field-method gauges and the model's values, every output time.

    An export (:class:`~pilegroup.solver.exports.Export`); every method is collective.

    Args:
        sc: the scenario (gauge depths, pile modulus).
        pb: the :class:`~pilegroup.solver.problem.BiotProblem`.
        piles: the run's :class:`~pilegroup.studies.run.pile_probe.PileProbe` (pile
            numbering, mirror images, cut fractions, the model's axial force and interface
            profiles).
        path: the CSV file to write.
    """

    def __init__(self, sc: Scenario, pb: BiotProblem, piles: PileProbe, path: Path) -> None:
        self.pb, self.piles, self.path = pb, piles, Path(path)
        self.comm = pb.comm
        self.depths = np.asarray(sc.outputs.gauge_depths_m, dtype=float)
        self.E = sc.structure.E
        self.n_piles = len(sc.piles.xy)
        body = pb.body("structure")  # the whole mesh when tied
        self.body = body
        v = ufl.TestFunction(fem.functionspace(body.mesh, ("DG", 0)))
        uz = body.u[2]
        self._forms = (fem.form(v * uz * ufl.dx), fem.form(v * uz.dx(2) * ufl.dx))
        self._vol = fem.assemble_vector(fem.form(v * ufl.dx)).array.copy()
        self._layers = {i: self._element_layers(i) for i in piles.fraction}
        self.section = {i: self._section(i) for i in piles.fraction}
        for i, (A, U) in self.section.items():
            d = sc.piles.diameters[i - 1]
            log.info("gauges, pile %d: A = %.6g m^2 (circle %.6g), U = %.6g m (circle "
                     "%.6g)", i, A, math.pi * d * d / 4, U, math.pi * d)
        self.rows: list[str] = []
        self._N0: dict[int, np.ndarray] = {}

    # ------------------------------------------------------------------ geometry
    def _element_layers(self, i: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Element layers of pile ``i`` below ground (top down, the same on every rank).

        Returns (owned cells, their layer index, layer tops z, layer bottoms z).
        """
        cells = np.zeros(0, np.int32)
        for g in self.body.qp.groups:
            if groups.pile_of(g.name) == i:
                cells = g.cells
        geo = self.body.mesh.geometry
        z = geo.x[geo.dofmaps[0][cells], 2] if cells.size else np.zeros((0, 1))
        top, bot = np.round(z.max(axis=1), 6), np.round(z.min(axis=1), 6)
        below = top <= 0.0  # the part embedded in the cap is not a pile section
        tops = np.unique(np.concatenate(self.comm.allgather(top[below])))[::-1]
        bots = np.unique(np.concatenate(self.comm.allgather(bot[below])))[::-1]
        return cells[below], np.searchsorted(-tops, -top[below]), tops, bots

    def _sums(self, arrays: list[np.ndarray]) -> dict[int, np.ndarray]:
        """Per kept pile and element layer: the sums of ``arrays`` over its cells (all-reduced)."""
        loc = {}
        for i, (cells, k, tops, _) in self._layers.items():
            acc = np.zeros((len(arrays), tops.size))
            for row, a in zip(acc, arrays, strict=True):
                np.add.at(row, k, a[cells])
            loc[i] = acc
        keys = sorted(loc)
        flat = np.concatenate([loc[i].ravel() for i in keys]) if keys else np.zeros(0)
        tot = self.comm.allreduce(flat, op=MPI.SUM)
        out, at = {}, 0
        for i in keys:
            out[i] = tot[at: at + loc[i].size].reshape(loc[i].shape)
            at += loc[i].size
        return out

    def _section(self, i: int) -> tuple[float, float]:
        """(area m^2, circumference m) of the whole meshed pile ``i``."""
        _, _, tops, bots = self._layers[i]
        length = float(np.sum(tops - bots))
        frac = self.piles.fraction[i]
        vol = float(self._sums([self._vol])[i].sum())
        md = self.pb.md
        shafts = [n for n in md.facet_names if groups.shaft_of(n) is not None
                  and groups.shaft_of(n)[0] == i]
        factor = self.pb.interface.shaft_factor if self.pb.interface is not None else 1.0
        return vol / length / frac, facet_area(md, shafts, interior=True) * factor / length / frac

    # ------------------------------------------------------------------ values
    def _pile_state(self) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Per kept pile: layer mid-heights z, section-mean u_z and d u_z / dz of each layer."""
        arrays = [self._vol] + [fem.assemble_vector(f).array for f in self._forms]
        out = {}
        for i, s in self._sums(arrays).items():
            _, _, tops, bots = self._layers[i]
            out[i] = (0.5 * (tops + bots), s[1] / s[0], s[2] / s[0])
        return out

    def _settlement(self, i: int, state: tuple, depth: np.ndarray) -> np.ndarray:
        """Section-mean settlement (m, down positive) of pile ``i`` at ``depth`` (exact for Q1)."""
        zm, u, g = state
        tops = self._layers[i][2]
        k = np.clip(np.searchsorted(-tops, depth, side="right") - 1, 0, tops.size - 1)
        return -(u[k] + (-depth - zm[k]) * g[k])

    def values(self, i: int, state: tuple, averages: dict, fields: dict | None
               ) -> dict[str, np.ndarray]:
        """Gauge columns of kept pile ``i`` (one value per section; :data:`GAUGE_COLUMNS`)."""
        zm, _, g = state
        d = self.depths
        strain = np.interp(d, -zm, -g)
        A, U = self.section[i]
        w0 = float(self._settlement(i, state, np.zeros(1))[0])
        N, f, w = field_reduction(d, strain, self.E, A, U, w0)
        dN, Nm = self.piles.axial_force(i, averages)
        Nm = (Nm - self._N0.setdefault(i, Nm.copy())) / self.piles.fraction[i]
        N_model = np.interp(d, dN, Nm)
        if fields is not None:
            dz, fr, rel = self.piles.interface_profile(i, fields)
            f_model, w_model = interval_means(dz, fr, d), np.interp(d, dz, rel)
        else:
            f_model = np.append((N_model[:-1] - N_model[1:]) / (U * np.diff(d)), np.nan)
            w_model = np.zeros_like(d)
        return {"strain": strain, "N_kN": N, "f_kPa": f, "w_mm": 1e3 * w,
                "N_model_kN": N_model, "f_model_kPa": f_model, "w_model_mm": 1e3 * w_model,
                "w_pile_mm": 1e3 * self._settlement(i, state, d),
                "N_error_kN": N - N_model, "f_error_kPa": f - f_model,
                "w_error_mm": 1e3 * (w - w_model)}

    def summary(self) -> dict[str, object]:
        """What the field method used: depths, E and each meshed pile's A and U (JSON)."""
        return {"file": self.path.name, "depths_m": self.depths.tolist(), "E_kPa": self.E,
                "section": {str(i): {"A_m2": A, "U_m": U} for i, (A, U) in self.section.items()}}

    # ------------------------------------------------------------------ export protocol
    def write(self, t: float, stage: str) -> None:
        """Every pile's gauges at output time ``t``; rank 0 rewrites the file."""
        averages = self.body.qp.cell_average("stress")
        itf = self.pb.interface
        fields = itf.nodal_fields() if itf is not None else None
        state = self._pile_state()
        kept = {i: self.values(i, state[i], averages, fields) for i in sorted(self._layers)}
        for p in range(1, self.n_piles + 1):
            vals = kept[self.piles.source[p]]
            cols = np.column_stack([vals[c] for c in GAUGE_VALUES]) + 0.0  # no "-0"
            self.rows += [f"{t:.6g},{p},{s + 1},{z:.6g}," + ",".join(_cell(x) for x in row)
                          for s, (z, row) in enumerate(zip(self.depths, cols, strict=True))]
        if self.comm.rank == 0:
            write_text_atomic(self.path, "\n".join([GAUGE_COLUMNS, *self.rows]) + "\n")

    def close(self) -> None:
        """Nothing stays open (the file is rewritten atomically at each write)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps: the rows written and the reference axial forces."""
        return {"rows": list(self.rows), "N0": {str(k): v.tolist() for k, v in self._N0.items()}}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state` (the file is rewritten at the next write)."""
        self.rows = list(data["rows"])
        self._N0 = {int(k): np.array(v, dtype=float) for k, v in data["N0"].items()}


def _cell(x: float) -> str:
    """A CSV cell: the value, or empty where the quantity does not exist (no "nan" text)."""
    return f"{x:.9g}" if np.isfinite(x) else ""
