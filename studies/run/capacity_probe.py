"""``capacity.csv`` and the capacity summary of a run with a capacity stage.

An export (:class:`~pilegroup.solver.exports.Export`) over the run: the state at the last output
time before the capacity stage starts the curve; :meth:`CapacityProbe.record` adds every
accepted step of the stage (the group: cap load and cap settlement; every pile: its head force
and its settlement). :meth:`CapacityProbe.check` is the stage's stop rule (called after every
accepted step instead of the runaway check, whose failure is this stage's result), and
:meth:`CapacityProbe.result` reads the criteria
(:func:`pilegroup.studies.results.capacity.capacity_criteria`) for the group and every pile, with
the group efficiency when the scenario gives the single pile's capacity
(``single_pile_capacity_kN``). docs/model.md, "Capacity", gives the method.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pilegroup.errors import CapacityReached
from pilegroup.fileio import write_text_atomic
from pilegroup.model import Scenario
from pilegroup.model.stages import PLUNGING_STIFFNESS_RATIO
from pilegroup.solver import BiotProblem
from pilegroup.studies.results.capacity import (
    SETTLEMENT_PER_DIAMETER,
    capacity_criteria,
    group_efficiency,
    tangent_stiffness,
)
from pilegroup.studies.results.tables import CAPACITY_COLUMNS, CAPACITY_CSV
from pilegroup.studies.run.pile_probe import PileProbe

#: A capacity stage ends at the latest when the foundation has settled this many pile diameters
#: (the runaway limit of the other stages: far past both criteria, and past what a small-strain
#: model describes).
STOP_SETTLEMENT_PER_DIAMETER = 1.0


class CapacityProbe:
    """The capacity stage's curves (group and piles), stop rule and result.

    Args:
        sc: the scenario (with a capacity stage).
        pb: the problem.
        piles: the run's :class:`PileProbe` (head forces and settlements of every pile).
        settlement: the cap (or pile-head) settlement probe, m down (collective).
        out: the run folder.
    """

    def __init__(self, sc: Scenario, pb: BiotProblem, piles: PileProbe, settlement: Any,
                 out: Path) -> None:
        st = sc.capacity_stage
        assert st is not None
        self.stage, self.pb, self.piles, self.settlement = st.name, pb, piles, settlement
        self.path = Path(out) / CAPACITY_CSV
        self.total = sc.total_cap_load()
        #: every pile's diameter (m): the scale of its own settlement criterion
        self.diameters = sc.piles.diameters
        #: the group's scale: the smallest diameter (a group of equal piles: their diameter)
        self.d = min(self.diameters)
        self.n = sc.piles.count
        self.ratio = st.plunging_stiffness_ratio or PLUNGING_STIFFNESS_RATIO
        self.single = st.single_pile_capacity_kN
        #: (t, load factor, group load, group settlement, head forces, pile settlements)
        self.points: list[list[Any]] = []
        self.start: list[Any] | None = None
        self.end: dict[str, Any] | None = None

    # ------------------------------------------------------------------ recording
    def _point(self, t: float) -> list[Any]:
        """The current point (collective)."""
        forces = self.piles.load_forces()
        heads, sett = [], []
        for i in range(1, self.n + 1):
            k = self.piles.source[i]
            N = forces[k][1]
            heads.append(float(N[0]) if N.size else 0.0)
            w = self.piles.settlement(k)[1]
            sett.append(float(w[0]) if w.size else 0.0)
        lam = self.pb.load_factor
        return [t, lam, lam * self.total, float(self.settlement()), heads, sett]

    def record(self, t: float, stage: str) -> None:
        """After an accepted step: a point of the curve when ``stage`` is the capacity stage."""
        if stage != self.stage:
            return
        if self.points and self.points[-1][0] == t:
            return
        self.points.append(self._point(t))
        self._write()

    def write(self, t: float, stage: str) -> None:
        """Export protocol: before the stage, the start of the curve; in it, a point."""
        if stage == self.stage:
            self.record(t, stage)
        else:
            self.start = self._point(t)

    def close(self) -> None:
        """Nothing stays open (the file is rewritten at each point)."""

    def saved_state(self) -> dict[str, Any]:
        """What a checkpoint keeps."""
        return {"points": self.points, "start": self.start}

    def restore_state(self, data: dict[str, Any]) -> None:
        """Continue from :meth:`saved_state`."""
        self.points, self.start = list(data["points"]), data["start"]

    # ------------------------------------------------------------------ reading
    def curve(self) -> list[list[Any]]:
        """The points of the curve: the start (if any) and every step of the stage."""
        return ([self.start] if self.start is not None else []) + self.points

    def check(self, t: float, stage: str) -> None:
        """The stop rule after an accepted step of the capacity stage.

        Raises :class:`CapacityReached` once the settlement exceeds
        :data:`STOP_SETTLEMENT_PER_DIAMETER` pile diameters (the smallest one), or once both
        criteria are found on the group's curve (nothing more to learn by loading further).
        """
        if stage != self.stage or not self.points:
            return
        t, lam, _, w = self.points[-1][:4]
        if w > STOP_SETTLEMENT_PER_DIAMETER * self.d:
            raise CapacityReached(f"settlement {w:.4g} m > {STOP_SETTLEMENT_PER_DIAMETER:g} pile"
                                  " diameter", t, lam)
        crit = self.group_criteria()
        if crit["plunging"]["load_kN"] is not None \
                and crit["settlement_10pct_d"]["load_kN"] is not None:
            raise CapacityReached("both criteria reached", t, lam)

    def group_criteria(self) -> dict[str, Any]:
        """The criteria on the group's curve (cap load against cap settlement).

        The group's settlement criterion is 10 % of the smallest pile diameter: with piles of
        different diameters the foundation has failed once its thinnest pile has (the cap
        settles with all of them); each pile's own curve uses its own diameter
        (:meth:`result`).
        """
        c = self.curve()
        return capacity_criteria(np.array([p[2] for p in c]), np.array([p[3] for p in c]),
                                 self.d, self.ratio, self.end, self.total)

    def result(self) -> dict[str, Any]:
        """The capacity summary: criteria of the group and of every pile, efficiency, method."""
        c = self.curve()
        group = self.group_criteria()
        piles = []
        for i in range(self.n):
            crit = capacity_criteria(np.array([p[4][i] for p in c]),
                                     np.array([p[5][i] for p in c]), self.diameters[i],
                                     self.ratio)
            at = c[-1][4][i] if c else None
            piles.append({"pile": i + 1, "head_force_at_end_kN": at, **crit})
        return {
            "stage": self.stage, "end": self.end, "group": group, "piles": piles,
            "pile_count": self.n, "single_pile_capacity_kN": self.single,
            "group_efficiency": group_efficiency(group["ultimate_kN"], self.n, self.single),
            "plunging_stiffness_ratio": self.ratio,
            "settlement_criterion_m": SETTLEMENT_PER_DIAMETER * self.d,
            "csv": CAPACITY_CSV,
            "method": "load control; plunging where the tangent stiffness falls below the "
                      "ratio x the initial, or the last equilibrium where the stepper's "
                      "cut-backs find none (bracketed by the failed step's load); settlement "
                      "criterion 10 % of the pile diameter (each pile's own; the group: the "
                      "smallest) (docs/model.md, Capacity)",
        }

    def finish(self, end: dict[str, Any] | None) -> dict[str, Any]:
        """Set how the stage ended, rewrite the file, and return :meth:`result`."""
        self.end = end
        self._write()
        return self.result()

    def _write(self) -> None:
        """Rank 0 rewrites ``capacity.csv``: the group (pile 0), then every pile."""
        if self.pb.comm.rank != 0:
            return
        c = self.curve()
        lines = [CAPACITY_COLUMNS]
        series = [(0, [p[2] for p in c], [p[3] for p in c])]
        series += [(i + 1, [p[4][i] for p in c], [p[5][i] for p in c]) for i in range(self.n)]
        for pile, q, w in series:
            k = tangent_stiffness(np.array(q), np.array(w))
            for p, qi, wi, ki in zip(c, q, w, k, strict=True):
                ks = f"{ki:.9g}" if np.isfinite(ki) else ""
                lines.append(f"{p[0]:.9g},{pile},{p[1]:.9g},{qi:.9g},{wi:.9g},{ks}")
        write_text_atomic(self.path, "\n".join(lines) + "\n")


__all__ = ["STOP_SETTLEMENT_PER_DIAMETER", "CapacityProbe"]
