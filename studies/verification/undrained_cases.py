"""Undrained response to a uniform surface load on the meshes the mesher makes.

``undrained-loading``: a site-wide fill ``q`` placed in a time short against consolidation
(``c_v t / h^2`` below 1e-3 in every layer: the permeability of every layer is lowered to
1e-6 m/day and the fill placed over 0.01 day) on the graded, stretched meshes of pile groups,
run through the whole pipeline (``pilegroup run``: geostatic stage, the fill's pressure on the
pile heads, then on the ground; the default discretisation). The loading is then 1D, and with
incompressible grains (Biot coefficient 1) the excess pore pressure is
``p = q / (1 + S E_oed)`` (``S = n / K_w`` the storage, ``E_oed`` the layer's constrained
modulus; Skempton's ``B`` for 1D loading, e.g. Verruijt, "Theory and Problems of Poroelasticity",
2016, ch. 2): 0.999 q in a soft clay, 0.99 q in a dense sand. The error of a mesh is the
largest ``|p_h - p| / q`` over every soil node below the drained ground surface; tolerance
2 %. The piles take their share of the fill on their heads and their shafts slide (the
interface at its least shear stiffness): unloaded, a pile would shield the ground below its toe
(measured under the toes of ``group3x3_downdrag``'s layout: 56.6 kPa with Q1-Q1 and 56.1 kPa
with Q2-Q1 for q = 60 kPa), a response that is right but not 1D.

Meshes: the layouts of the bundled scenarios (their plan, layers and piles, Pier 667 in the
``bench`` size) and layouts drawn by a seeded random generator
(:func:`random_layout`: 1-4 x 1-3 piles of 0.5-1.5 m at 2.5-4 diameters, two to four
layers), each with the default mesh sizes of
:mod:`pilegroup.model.mesh_defaults`.
"""

from __future__ import annotations

import shutil
import tempfile
import time
import tomllib
from pathlib import Path
from typing import Any

import h5py
import numpy as np
from mpi4py import MPI

from pilegroup.errors import ScenarioError
from pilegroup.model import Scenario, scenario_from_dict
from pilegroup.model.loader import build_dataclass, bundled_text
from pilegroup.model.piles import Piles
from pilegroup.model.units import K_WATER
from pilegroup.studies.run.job import run_scenario
from pilegroup.studies.verification.common import world
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["fill_scenario", "random_layout", "undrained_loading", "undrained_spread"]

#: The fill (kPa), its duration (day) and the permeability of every layer (m/day).
FILL_KPA, FILL_DAY, K_UNDRAINED = 60.0, 0.01, 1.0e-6
#: Tolerance on ``|p_h - p| / q`` at every node checked.
TOLERANCE = 0.02
#: The bundled layouts of each size, and the random layouts' seeds.
LAYOUTS = {"fast": ("single_pile", "group3x3_downdrag", "group2x3_lateral"),
           "bench": ("single_pile", "group3x3_downdrag", "group2x3_lateral", "pier667")}
SEEDS = {"fast": (1, 2), "bench": (1, 2, 3, 4)}


def fill_scenario(doc: dict[str, Any]) -> dict[str, Any]:
    """The undrained fill on the site, layers and piles of scenario document ``doc``.

    The layers keep their names, thicknesses, unit weights, elastic moduli and void ratios;
    the soil is linear elastic and nearly impermeable, no layer drained; the piles are joined
    to the soil by the elastic interface at its least shear stiffness (the shafts slide),
    their heads free at the ground and loaded by the fill's pressure first (the pile under
    its share of the fill carries it to the toe; unloaded, it would shield the ground below
    its toe), then the fill on the ground; no cap (it would shield the ground under it); no
    ``[numerics]`` (the default discretisation).
    """
    keep = ("name", "thickness_m", "gamma_kN_per_m3", "E_MPa", "nu", "phi_deg", "c_kPa", "e0",
            "interface")
    layers = [{k: v for k, v in lay.items() if k in keep} | {"k_m_per_day": K_UNDRAINED}
              for lay in doc["layers"]]
    piles = build_dataclass(Piles, doc["piles"], "piles")
    heads = sum(np.pi * d ** 2 / 4 for d in piles.diameters)  # m^2
    for lay in layers:  # the shafts slide: the piles carry their heads' share, no more
        if "interface" in lay:
            lay["interface"] = lay["interface"] | {"K": 1.0, "n": 0.0, "R_f": 0.0}
    out = {
        "scenario": {"name": f"undrained_{doc['scenario']['name']}"},
        "site": doc["site"] | {"water_table_depth_m": 0.0},
        "piles": {k: v for k, v in doc["piles"].items() if k != "embedment_m"},
        "structure": doc["structure"],
        "soil": {"model": "linear_elastic"},
        "interface": {"mode": "elastic"},
        "stages": [{"name": "geostatic", "kind": "geostatic"},
                   {"name": "heads", "kind": "load", "cap_load_kN": FILL_KPA * heads,
                    "duration_day": FILL_DAY / 2},
                   {"name": "fill", "kind": "surcharge", "surcharge_kPa": FILL_KPA,
                    "duration_day": FILL_DAY / 2}],
        "time": {"end_day": FILL_DAY, "output_days": [0.0, FILL_DAY]},
        "outputs": {"xdmf": True, "plots": False},
        "layers": layers,
    }
    return out


def random_layout(seed: int) -> dict[str, Any]:
    """A valid pile-group site drawn from ``seed`` (a scenario document, as TOML gives it)."""
    rng = np.random.default_rng(seed)
    tries = 0
    while True:
        nx, ny = int(rng.integers(1, 5)), int(rng.integers(1, 4))
        d = float(np.round(rng.uniform(0.5, 1.5), 2))
        s = float(np.round(d * rng.uniform(2.5, 4.0), 2))
        length = float(np.round(rng.uniform(8.0, 25.0), 1))
        depth = float(np.round(length * rng.uniform(1.4, 2.0), 1))
        width = max(nx, ny) * s + 2.0 * length
        n_layers = int(rng.integers(2, 5))
        cuts = np.sort(rng.uniform(0.1, 0.9, n_layers - 1)) * depth
        tops = np.concatenate([[0.0], np.round(cuts, 1)])
        layers = []
        for j in range(n_layers):
            lay = {"name": f"layer_{j + 1}", "gamma_kN_per_m3": 18.0,
                   "E_MPa": float(np.round(rng.uniform(2.0, 40.0), 1)),
                   "nu": float(np.round(rng.uniform(0.25, 0.42), 2)), "phi_deg": 20.0,
                   "c_kPa": 10.0, "e0": float(np.round(rng.uniform(0.6, 1.4), 2)),
                   "interface": {"delta_deg": 15.0, "K": 400.0, "n": 0.4, "R_f": 0.5,
                                 "eta_MPa_day": 10.0}}
            if j < n_layers - 1:
                lay["thickness_m"] = float(np.round(tops[j + 1] - tops[j], 1))
            layers.append(lay)
        doc: dict[str, Any] = {
            "scenario": {"name": f"random_{seed}"},
            "site": {"size_x_m": float(np.round(width, 1)), "size_y_m": float(np.round(width, 1)),
                     "depth_m": depth},
            "piles": {"diameter_m": d, "length_in_soil_m": length, "grid": [nx, ny],
                      "spacing_m": [s, s]},
            "structure": {"E_MPa": 32300.0, "nu": 0.17, "density_kg_per_m3": 2500.0},
            "stages": [{"name": "geostatic", "kind": "geostatic"}],
            "time": {"end_day": 1.0},
            "layers": layers,
        }
        try:
            scenario_from_dict(fill_scenario(doc))
        except ScenarioError as exc:
            tries += 1
            if tries > 100:  # a programming error, not bad luck
                raise RuntimeError(f"no valid layout in 100 draws; the last: {exc}") from exc
            continue
        return doc


def _reference(sc: Scenario, z: np.ndarray) -> np.ndarray:
    """``q / (1 + S E_oed)`` of the layer above and below each depth ``z`` (m, up), (n, 2)."""
    tops = np.array(sc.layer_depths()[:-1])
    values = []
    for lay in sc.layers:
        e_oed = lay.E * (1 - lay.nu) / ((1 + lay.nu) * (1 - 2 * lay.nu))
        values.append(FILL_KPA / (1.0 + lay.porosity / K_WATER * e_oed))
    values = np.array(values)
    depth = -z
    below = np.clip(np.searchsorted(tops, depth, side="right") - 1, 0, len(values) - 1)
    above = np.clip(np.searchsorted(tops, depth, side="left") - 1, 0, len(values) - 1)
    return np.column_stack([values[above], values[below]])


def undrained_spread(doc: dict[str, Any], comm: MPI.Comm, pair: str | None = None
                     ) -> dict[str, Any]:
    """Run the fill on layout ``doc`` and measure ``max |p_h - p| / q`` (see the module).

    ``pair``: the element pair instead of the default discretisation's.
    """
    case = fill_scenario(doc)
    if pair is not None:
        case["numerics"] = {"element": pair}
    sc = scenario_from_dict(case)
    tmp = tempfile.mkdtemp(prefix="pilegroup-undrained-") if comm.rank == 0 else None
    out = Path(comm.bcast(tmp, root=0))
    try:
        summary = run_scenario(sc, out, comm=comm)
        result = None
        if comm.rank == 0:
            with h5py.File(out / "results.h5", "r") as f:
                key = next(k for k in f["Function"] if "pressure" in k)
                series = f["Function"][key]
                last = max(series, key=lambda s: float(s.replace("_", ".")))
                p = series[last][:].ravel()
                mesh = f["Mesh"][next(iter(f["Mesh"]))]["geometry"][:]
            xyz = mesh[: len(p)]
            checked = xyz[:, 2] < -1e-6  # every node below the drained ground surface
            ref = _reference(sc, xyz[:, 2])
            err = np.min(np.abs(p[:, None] - ref), axis=1) / FILL_KPA
            worst = int(np.argmax(np.where(checked, err, -1.0)))
            result = {"layout": doc["scenario"]["name"], "error": float(err[worst]),
                      "nodes": int(checked.sum()), "worst_node_m": xyz[worst].tolist(),
                      "p_min_kPa": float(p[checked].min()), "p_max_kPa": float(p[checked].max()),
                      "element": sc.numerics.element,
                      "dofs": int((summary.get("solver") or {}).get("dofs", 0)),
                      "newton": int((summary.get("solver") or {}).get("newton_iterations", 0))}
        return comm.bcast(result, root=0)
    finally:
        if comm.rank == 0:
            shutil.rmtree(out, ignore_errors=True)


@register("undrained-loading", options=("pair",))
def undrained_loading(size: str = "fast", comm: MPI.Comm | None = None,
                      pair: str | None = None) -> CaseResult:
    """A uniform fill, undrained, on bundled and random layouts: uniform pressure within 2 %.

    ``pair``: the element pair instead of the default discretisation's (a benchmark's option).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    docs = [tomllib.loads(bundled_text(name)) for name in LAYOUTS[size]]
    docs += [random_layout(seed) for seed in SEEDS[size]]
    rows = [undrained_spread(doc, comm, pair) for doc in docs]
    err = max(r["error"] for r in rows)
    return CaseResult(
        "undrained-loading", err, TOLERANCE, bool(err <= TOLERANCE), time.perf_counter() - t0,
        sum(r["dofs"] for r in rows), sum(r["newton"] for r in rows), len(rows),
        reference="1D undrained loading, incompressible grains: p = q / (1 + S E_oed) "
                  "(Skempton's B for 1D loading)",
        details={"meshes": rows, "ranks": comm.size})
