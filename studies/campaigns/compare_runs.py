"""Two runs of one foundation compared: a reduced model against the full one, or two solvers.

What a user checks before trusting a symmetry reduction or a cheaper solver, with the bounds
the reduced model must meet (docs/results.md, "Quarter model against the full model"):

* the cap settlement at every output time after the start, relative: 0.2 %;
* every pile's head force at those times, relative: 0.5 %;
* the centre pile's axial-force and shaft-friction profiles at those times, the largest
  difference over the stations relative to the profile's largest magnitude: 1 %.

``python -m pilegroup.studies.campaigns.compare_runs REFERENCE OTHER`` prints the table and exits 0
when
every difference is within its bound, 1 otherwise.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.studies.results.rundata import RunData, load_run
from pilegroup.studies.results.tables import Table

#: Quantity -> largest allowed difference (fraction; see the module doc).
BOUNDS = {"cap settlement": 2e-3, "pile head force": 5e-3,
          "centre pile axial force profile": 1e-2, "centre pile friction profile": 1e-2}


@dataclass(frozen=True)
class Difference:
    """The largest difference of one quantity between two runs, and where it is."""

    quantity: str
    value: float
    where: str

    @property
    def bound(self) -> float:
        """The largest difference allowed (fraction)."""
        return BOUNDS[self.quantity]

    @property
    def within(self) -> bool:
        """Whether the difference is within its bound."""
        return self.value <= self.bound


def _later_times(t: np.ndarray) -> np.ndarray:
    return np.unique(t[t > 0.0])


def _relative(quantity: str, a: dict, b: dict) -> Difference:
    """Largest ``|b - a| / |a|`` over the keys of ``a`` (each key must be in ``b``)."""
    missing = sorted(set(a) - set(b))
    if missing:
        raise ValueError(f"{quantity}: the other run has no value at {missing[0]}")
    worst = max(a, key=lambda k: abs(b[k] - a[k]) / max(abs(a[k]), 1e-300))
    return Difference(quantity, abs(b[worst] - a[worst]) / max(abs(a[worst]), 1e-300),
                      str(worst))


def _settlements(run: RunData) -> dict[str, float]:
    s = run.settlement
    return {f"t = {t:g} d": float(w) for t, w in zip(s["t_day"], s["settlement_m"], strict=True)
            if t > 0.0}


def _head_forces(run: RunData) -> dict[str, float]:
    ld = run.loads
    return {f"pile {int(p)}, t = {t:g} d": float(f)
            for t, p, f in zip(ld["t_day"], ld["pile"], ld["head_force_kN"], strict=True)
            if t > 0.0}


def _profile(ref: Table, other: Table, column: str, quantity: str) -> Difference:
    """Largest difference over stations and times, relative to the profile's largest value."""
    worst = Difference(quantity, 0.0, "everywhere")
    for t in _later_times(ref["t_day"]):
        ka, kb = ref["t_day"] == t, other["t_day"] == t
        if not kb.any():
            raise ValueError(f"{quantity}: the other run has no profile at t = {t:g} d")
        za, va = ref["depth_m"][ka], ref[column][ka]
        zb, vb = other["depth_m"][kb], other[column][kb]
        ok_a, ok_b = np.isfinite(va), np.isfinite(vb)
        vb_at_a = np.interp(za[ok_a], zb[ok_b], vb[ok_b])
        scale = float(np.max(np.abs(va[ok_a])))
        diff = np.abs(vb_at_a - va[ok_a])
        i = int(np.argmax(diff))
        rel = float(diff[i]) / scale if scale > 0.0 else float(diff[i])
        if rel > worst.value:
            worst = Difference(quantity, rel, f"t = {t:g} d, depth {za[ok_a][i]:.2f} m")
    return worst


def compare_runs(reference: str | Path, other: str | Path) -> list[Difference]:
    """The largest differences of ``other`` against ``reference`` (run output folders)."""
    a, b = load_run(Path(reference)), load_run(Path(other))
    for run in (a, b):
        for name in ("settlement", "loads", "profiles"):
            if getattr(run, name) is None:
                raise ValueError(f"{run.out_dir}: no {name} table to compare")
    if a.centre_pile != b.centre_pile:
        raise ValueError(f"centre piles differ: {a.centre_pile} and {b.centre_pile}")
    return [_relative("cap settlement", _settlements(a), _settlements(b)),
            _relative("pile head force", _head_forces(a), _head_forces(b)),
            _profile(a.profiles, b.profiles, "axial_force_kN",
                     "centre pile axial force profile"),
            _profile(a.profiles, b.profiles, "shaft_friction_kPa",
                     "centre pile friction profile")]


def markdown(diffs: list[Difference]) -> str:
    """The differences as a Markdown table (percent)."""
    lines = ["| quantity | largest difference | where | bound | within |",
             "| --- | ---: | --- | ---: | --- |"]
    lines += [f"| {d.quantity} | {100 * d.value:.3g} % | {d.where} | {100 * d.bound:g} % | "
              f"{'yes' if d.within else 'no'} |" for d in diffs]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Print the table of ``REFERENCE OTHER``; exit 0 within the bounds, 1 not, 2 bad input."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2:
        print("usage: python -m pilegroup.studies.campaigns.compare_runs REFERENCE_DIR OTHER_DIR",
              file=sys.stderr)
        return 2
    try:
        diffs = compare_runs(*args)
    except (ValueError, ScenarioError) as exc:
        print(f"compare_runs: {exc}", file=sys.stderr)
        return 2
    print(markdown(diffs))
    return 0 if all(d.within for d in diffs) else 1


if __name__ == "__main__":
    sys.exit(main())
