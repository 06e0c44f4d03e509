"""Throughput of the constitutive laws (points per second), a program, not a test.

``python -m pilegroup.studies.bench.laws [n ...]`` prints a table; results are kept in
docs/benchmarks.md ("Constitutive laws"). Each law is timed on one call of ``update`` over
``n`` points (best of ``repeat``), inputs prepared beforehand, for three load cases:

* ``elastic``: small increments from an in-situ state, no point yields;
* ``mixed``: increments sized so that roughly a third (MC) or a sixth (DP) of the points yield;
* ``plastic``: large increments, nearly all points yield (all branches of the MC return).

For the interface the cases are: ``elastic`` (below the DP surface), ``creep`` (all points
above it: implicit return with scalar Newton), and ``detached`` (opening).
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.constitutive.paper import interface_kwargs, soil_kwargs
from pilegroup.constitutive.soil import DruckerPrager, LinearElastic, MohrCoulomb


def _time(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def run_benchmark(sizes=(100_000, 1_000_000), repeat: int = 3, seed: int = 0) -> list[dict]:
    """Time ``update`` of each law.

    Returns rows with law, case, n, seconds (best of ``repeat``), points_per_s and the fraction
    of points that yielded (soil) or crept (interface).
    """
    rng = np.random.default_rng(seed)
    kw = soil_kwargs(5)  # silt: phi = 25 deg, c = 7.4 kPa, E = 21.5 MPa
    soil_laws = {
        "LinearElastic": LinearElastic(E=kw["E"], nu=kw["nu"]),
        "MohrCoulomb": MohrCoulomb(**kw),
        "DruckerPrager": DruckerPrager(**kw),
    }
    rows = []
    for n in sizes:
        stress0 = np.tile([-100.0, -100.0, -150.0, 0.0, 0.0, 0.0], (n, 1))
        base = rng.normal(size=(n, 6))
        for name, law in soil_laws.items():
            state = law.initial_state(n, stress0)
            cases = (("elastic", 2e-5), ("mixed", 1.5e-3), ("plastic", 1e-2))
            if name == "LinearElastic":
                cases = cases[:1]
            for case, amp in cases:
                de = base * amp
                _, trial, _ = law.update(de, state, 1.0)
                frac = float(np.mean(trial["mode"] > 0)) if "mode" in trial else 0.0
                sec = _time(lambda law=law, de=de, state=state: law.update(de, state, 1.0),
                            repeat)
                rows.append({"law": name, "case": case, "n": n, "seconds": sec,
                             "points_per_s": n / sec, "plastic_fraction": frac})
        ilaw = PileSoilInterface(**interface_kwargs(2))
        sig = -rng.uniform(80.0, 200.0, n)
        st0 = ilaw.initial_state(n, np.column_stack([sig, np.zeros(n), np.zeros(n)]))
        a, b = ilaw.hyperbola(sig)
        tau_y = ilaw.k - 3.0 * ilaw.alpha * sig
        for case in ("elastic", "creep", "detached"):
            if case == "elastic":
                t = 0.5 * tau_y
            else:
                t = tau_y + 0.5 * (1.0 / b - tau_y)
            r = a * t / (1.0 - b * t)
            d = np.column_stack([np.zeros(n), r, 0.1 * r])
            if case == "detached":
                d[:, 0] = -2.0 * sig / ilaw.k_normal
            _, trial, _ = ilaw.update(d, st0, 10.0)
            frac = float(np.mean(np.abs(trial["slip_vp"]).sum(axis=1) > 0))
            sec = _time(lambda d=d, law=ilaw, s0=st0: law.update(d, s0, 10.0), repeat)
            rows.append({"law": "PileSoilInterface", "case": case, "n": n, "seconds": sec,
                         "points_per_s": n / sec, "plastic_fraction": frac})
    return rows


def format_table(rows: list[dict]) -> str:
    """Markdown table of :func:`run_benchmark` rows."""
    lines = ["| law | case | points | yielded/crept | time (s) | points/s |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['law']} | {r['case']} | {r['n']:,} | {r['plastic_fraction']:.0%} | "
                     f"{r['seconds']:.3f} | {r['points_per_s']:.3g} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: optional sizes as arguments."""
    args = sys.argv[1:] if argv is None else argv
    sizes = tuple(int(a) for a in args) or (100_000, 1_000_000)
    print(f"threads: OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')}")
    print(format_table(run_benchmark(sizes)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
