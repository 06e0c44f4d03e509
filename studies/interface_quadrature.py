"""Nodal against Gauss-point interface quadrature, measured on the real pipeline.

``python -m pilegroup.studies.interface_quadrature [--scenario PATH]`` prints a markdown table
(rank 0): for ``shaft-capacity`` with the shaft's normal penalty as used (4e6 kPa/m) and 10x,
100x stiffer, and for ``tied-limit`` (1e9 kPa/m): the case error against its reference, Newton
iterations, accepted and rejected steps, the roughness of the shaft traction profiles
(:func:`~pilegroup.studies.verification_interface.shaft_profile_oscillation`: total variation
over range, 1 = monotonic) and the wall time. With ``--scenario`` (e.g. the coarsened single
pile of tests/conftest.py) the scenario is also run to its end with each quadrature (wall time,
Newton iterations, rejected steps, head settlement). Results: docs/solver.md.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

QUADRATURES = ("nodal", "gauss")


def shaft_rows(factors: Sequence[float] = (1.0, 10.0, 100.0)) -> list[dict[str, Any]]:
    """One row per (normal penalty factor, quadrature) of ``shaft-capacity`` and tied-limit."""
    from pilegroup.studies.verification_interface import shaft_capacity, tied_limit

    rows = []
    for f in factors:
        for q in QUADRATURES:
            r = shaft_capacity(quadrature=q, k_normal_factor=f)
            d = r.details
            rows.append({"case": "shaft-capacity", "k_normal": d["k_normal_kPa_per_m"],
                         "quadrature": q, "error": r.error, "newton": r.newton_its,
                         "steps": r.steps, "rejected": d["rejected"], "wall_s": r.wall_s,
                         "first": d["oscillation_first"], "end": d["oscillation_end"]})
    for q in QUADRATURES:
        r = tied_limit(quadrature=q)
        d = r.details
        rows.append({"case": "tied-limit", "k_normal": 1e9, "quadrature": q, "error": r.error,
                     "newton": r.newton_its, "steps": r.steps, "rejected": 0,
                     "wall_s": r.wall_s, "detached": d["interface_detached_nodes"],
                     "end": d["interface_oscillation"]})
    return rows


def scenario_rows(path: str, out: Path, factors: Sequence[float] = (1.0, 10.0, 100.0)
                  ) -> list[dict[str, Any]]:
    """Run a scenario file to its end with each interface quadrature: solver summary rows.

    ``factors`` multiply the scenario's ``interface.normal_stiffness_factor``.
    """
    import dataclasses

    from pilegroup.model import load_scenario
    from pilegroup.studies.run import run_scenario

    rows = []
    for f in factors:
        for q in QUADRATURES:
            sc = load_scenario(path)
            itf = sc.interface
            sc = dataclasses.replace(sc, interface=dataclasses.replace(
                itf, quadrature=q, normal_stiffness_factor=f * itf.normal_stiffness_factor))
            s = run_scenario(sc, out / f"{q}_{f:g}")["solver"]
            rows.append({"quadrature": q, "normal_stiffness_factor":
                         sc.interface.normal_stiffness_factor, "wall_s": s["wall_s"],
                         "newton": s["newton_total"],
                         "steps": s["steps"], "rejected": s["rejected_steps"],
                         "dofs": s["dofs"],
                         "settlement_mm": 1000.0 * s["settlement_m"][-1]["settlement_m"]})
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """Print the tables (rank 0)."""
    from mpi4py import MPI

    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default=None, help="also run this scenario file")
    ap.add_argument("--out", default="out/interface_quadrature")
    a = ap.parse_args(argv)
    rank0 = MPI.COMM_WORLD.rank == 0
    rows = shaft_rows()
    if rank0:
        print("| case | k_normal (kPa/m) | quadrature | error | Newton | steps | rejected | "
              "TV ratio σn / τ1 at 3 mm | TV ratio σn / τ1 at end | wall (s) |")
        print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for r in rows:
            first = r.get("first")
            f1 = (f"{first['sigma_n_tv_ratio']:.2f} / {first['tau1_tv_ratio']:.2f}"
                  if first else "–")
            e = r["end"]
            print(f"| {r['case']} | {r['k_normal']:.0e} | {r['quadrature']} | {r['error']:.2e} "
                  f"| {r['newton']} | {r['steps']} | {r['rejected']} | {f1} | "
                  f"{e['sigma_n_tv_ratio']:.2f} / {e['tau1_tv_ratio']:.2f} | "
                  f"{r['wall_s']:.1f} |", flush=True)
    if a.scenario:
        srows = scenario_rows(a.scenario, Path(a.out))
        if rank0:
            print(f"\nScenario {a.scenario}\n")
            print("| normal_stiffness_factor | quadrature | DOFs | steps | rejected | Newton | "
                  "settlement (mm) | wall (s) |")
            print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
            for r in srows:
                print(f"| {r['normal_stiffness_factor']:g} | {r['quadrature']} | {r['dofs']} | "
                      f"{r['steps']} | {r['rejected']} | {r['newton']} | "
                      f"{r['settlement_mm']:.4f} | {r['wall_s']:.1f} |")
    return 0


if __name__ == "__main__":
    import pilegroup  # noqa: F401

    sys.exit(main())
