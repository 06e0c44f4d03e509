"""The main job: one scenario through every stage that exists, outputs to one folder."""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path
from typing import Any

from pilegroup.fileio import write_json_atomic
from pilegroup.model import Scenario

log = logging.getLogger(__name__)


def run_scenario(sc: Scenario, out: Path, mesh_size: float | None = None,
                 stop_after: str = "solve") -> dict[str, Any]:
    """Run scenario ``sc`` and write its outputs to ``out``; returns the summary.

    Stages that exist today: validate, write the resolved scenario (``scenario.json``), mesh
    (``mesh/``: XDMF with tags, PNG renders, counts and quality), ``summary.json``.
    """
    from mpi4py import MPI

    from pilegroup.geometry.adapter import geometry_spec
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.geometry.output import mesh_command
    from pilegroup.studies.pier import run_coupled

    t0 = time.perf_counter()
    if mesh_size is not None:
        sc = dataclasses.replace(sc, numerics=dataclasses.replace(
            sc.numerics, mesh=dataclasses.replace(sc.numerics.mesh, size_m=mesh_size)))
    comm = MPI.COMM_WORLD
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        write_json_atomic(out / "scenario.json", sc)
    spec = geometry_spec(sc)
    mesh = mesh_command(spec, None, out / "mesh", comm)
    solved: dict[str, Any] | None = None
    if stop_after == "solve":
        md = build_mesh(spec, comm)
        solved = run_coupled(sc, md, out)
    summary: dict[str, Any] = {
        "scenario": sc.name,
        "stages_done": ["validate", "mesh"] + ([st.name for st in sc.stages] if solved else []),
        "solver": solved,
        "mesh": {k: mesh[k] for k in ("h_m", "cells", "vertices", "min_scaled_jacobian",
                                      "shaft_groups", "files")},
        "ranks": comm.size,
        "wall_s": time.perf_counter() - t0,
    }
    if comm.rank == 0:
        write_json_atomic(out / "summary.json", summary)
        log.info("wrote %s", out / "summary.json")
        if solved is not None and sc.outputs.plots:
            from pilegroup.studies.report import write_report

            for path in write_report(out):
                log.info("wrote %s", path)
    return summary
