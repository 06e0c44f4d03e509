"""Nodal against Gauss-point interface quadrature, measured on the real pipeline.

``python -m pilegroup.studies.bench.interface_quadrature [--scenario PATH]`` prints a markdown table
(rank 0): for ``shaft-capacity`` with the shaft's normal penalty as used (4e6 kPa/m) and 10x,
100x stiffer, and for ``tied-limit`` (1e9 kPa/m, x 10, x 100): the case error against its
reference, Newton iterations, accepted and rejected steps, the roughness of the shaft traction
profiles (:func:`~pilegroup.studies.verification.shaft_profile_oscillation`: total
variation over range, 1 = monotonic) and the wall time. With ``--scenario`` (e.g. the coarsened
single pile of tests/conftest.py) the scenario is also run to its end with each quadrature and
its normal penalty factor x 1, 10, 100 (wall time, Newton iterations, rejected steps, head
settlement, roughness). Results: docs/solver.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from collections.abc import Sequence
from typing import Any

from mpi4py import MPI

from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.solver.probes import SettlementProbe
from pilegroup.solver.stepping import run_stages
from pilegroup.studies.run.cap_loads import loaded_facets
from pilegroup.studies.run.pipeline import (
    GEOSTATIC_TOL_M,
    build_problem,
    solver_stages,
    time_stepping,
)
from pilegroup.studies.verification import shaft_capacity, shaft_profile_oscillation, tied_limit

QUADRATURES = ("nodal", "gauss")


def _row(case: str, q: str, k_normal: float, r: Any, osc: dict, **extra: Any
         ) -> dict[str, Any]:
    return {"case": case, "quadrature": q, "k_normal": k_normal, "error": r.error,
            "newton": r.newton_its, "steps": r.steps, "wall_s": r.wall_s, "osc": osc, **extra}


def case_rows(factors: Sequence[float] = (1.0, 10.0, 100.0)) -> list[dict[str, Any]]:
    """One row per (case, normal penalty factor, quadrature): shaft-capacity and tied-limit."""
    rows = []
    for f in factors:
        for q in QUADRATURES:
            r = shaft_capacity(quadrature=q, k_normal_factor=f)
            d = r.details
            rows.append(_row("shaft-capacity", q, d["k_normal_kPa_per_m"], r,
                             d["oscillation_end"], rejected=d["rejected"],
                             detached=0))
    for f in factors:
        for q in QUADRATURES:
            r = tied_limit(quadrature=q, k_normal_factor=f)
            d = r.details
            rows.append(_row("tied-limit", q, 1e9 * f, r, d["interface_oscillation"],
                             rejected=0, detached=d["interface_detached_nodes"]))
    return rows


def scenario_rows(path: str, factors: Sequence[float] = (1.0, 10.0, 100.0)
                  ) -> list[dict[str, Any]]:
    """Run a scenario file's stages with each interface quadrature (no output files).

    ``factors`` multiply the scenario's ``interface.normal_stiffness_factor``. The problem,
    stages and time stepping are those of ``pilegroup run`` (studies/run/pipeline.py).
    """
    sc0 = load_scenario(path)
    geo = resolve_geometry(sc0)
    md = build_mesh(geo.spec, MPI.COMM_WORLD)
    rows = []
    for f in factors:
        for q in QUADRATURES:
            itf = sc0.interface
            sc = dataclasses.replace(sc0, interface=dataclasses.replace(
                itf, quadrature=q, normal_stiffness_factor=f * itf.normal_stiffness_factor))
            t0 = time.perf_counter()
            pb = build_problem(sc, geo, md)
            probe = SettlementProbe(pb, loaded_facets(sc, md))
            log = run_stages(pb, solver_stages(sc), time_stepping(sc),
                             geostatic_tol=GEOSTATIC_TOL_M)
            rows.append({"case": sc.name, "quadrature": q,
                         "k_normal": sc.interface.normal_stiffness_factor, "error": None,
                         "newton": log.newton_total, "steps": len(log.steps),
                         "rejected": log.rejected, "wall_s": time.perf_counter() - t0,
                         "osc": shaft_profile_oscillation(pb.interface, md.mesh.comm),
                         "detached": None, "settlement_mm": 1000.0 * probe(),
                         "dofs": pb.num_dofs})
    return rows


def main(argv: Sequence[str] | None = None) -> int:
    """Print the tables (rank 0)."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", action="append", default=[],
                    help="also run this scenario (file or bundled name); repeatable")
    ap.add_argument("--skip-cases", action="store_true", help="only the scenarios")
    a = ap.parse_args(argv)
    rank0 = MPI.COMM_WORLD.rank == 0
    if rank0:
        print("| case | k_normal | quadrature | error | settlement (mm) | Newton | steps | "
              "rejected | detached points | TV ratio σn | TV ratio τ1 | σn / τ1 sign changes "
              "| wall (s) |")
        print("| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: "
              "| ---: |")
    rows = ([] if a.skip_cases else case_rows()) + [
        r for path in a.scenario for r in scenario_rows(path)]
    for r in rows:
        o = r["osc"]
        err = f"{r['error']:.2e}" if r["error"] is not None else "–"
        sett = f"{r['settlement_mm']:.3f}" if "settlement_mm" in r else "–"
        det = str(r["detached"]) if r["detached"] is not None else "–"
        if rank0:
            print(f"| {r['case']} | {r['k_normal']:.3g} | {r['quadrature']} | {err} | {sett} "
                  f"| {r['newton']} | {r['steps']} | {r['rejected']} | {det} | "
                  f"{o['sigma_n_tv_ratio']:.2f} | {o['tau1_tv_ratio']:.2f} | "
                  f"{o['sigma_n_sign_changes']:.0f} / {o['tau1_sign_changes']:.0f} | "
                  f"{r['wall_s']:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
