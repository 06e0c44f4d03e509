"""Run verification cases: the real pipeline against closed-form solutions.

Each case returns a :class:`~pilegroup.studies.verification.registry.CaseResult` with its
error, the tolerance and the source of the reference. Run
``python -m pilegroup.studies.verification [CASE ...] [--size fast|bench] [--json]`` or
``pilegroup verify`` (also under ``mpirun -n 2``).
"""

from __future__ import annotations

import argparse
import json as _json
import sys
from collections.abc import Sequence
from dataclasses import asdict
from typing import TextIO

from pilegroup.fileio import json_default
from pilegroup.studies.verification.common import world
from pilegroup.studies.verification.registry import CaseResult, case_names, run_case

__all__ = ["main", "run_cases"]


def run_cases(names: Sequence[str] | None = None, size: str = "fast",
              json: bool = False, out: TextIO | None = None, pair: str | None = None,
              preset: str | None = None, quadrature: str | None = None) -> list[CaseResult]:
    """Run the named cases (all when empty); print one line each, or one JSON object each.

    ``pair`` (``"Q2Q1"``/``"Q1Q1"``) and ``preset`` (``"direct"``/``"fieldsplit_gamg"``)
    override the cases' defaults; ``quadrature`` (``"nodal"``/``"gauss"``) the interface
    quadrature of the interface cases. Only rank 0 prints. Returns the results (on every rank).

    Raises:
        KeyError: an unknown case name.
    """
    comm = world()
    out = out or sys.stdout
    results = []
    for name in case_names(names):
        res = run_case(name, size, pair=pair, preset=preset, quadrature=quadrature)
        results.append(res)
        if comm.rank == 0:
            if json:
                print(_json.dumps(asdict(res), default=json_default), file=out, flush=True)
            else:
                print(res.line(), file=out, flush=True)
    return results


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m pilegroup.studies.verification [CASE ...] [--json]``."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--size", default="fast", choices=["fast", "bench"])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--pair", choices=["Q2Q1", "Q1Q1"], default=None)
    ap.add_argument("--preset", choices=["direct", "fieldsplit_gamg"], default=None)
    ap.add_argument("--interface-quadrature", choices=["nodal", "gauss"], default=None)
    a = ap.parse_args(argv)
    res = run_cases(a.cases, size=a.size, json=a.json, pair=a.pair, preset=a.preset,
                    quadrature=a.interface_quadrature)
    return 0 if all(r.passed for r in res) else 1
