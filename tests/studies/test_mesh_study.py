"""``pilegroup study mesh``: size checks, the cases, and the report against batch.csv.

A published mesh study appears in the report, its CSV and its figures only where the scenario's
``[reference]`` carries one (``pier667``: the paper's Table 2); the report tests use made-up
batch rows, no runs.
"""

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.model import load_scenario
from pilegroup.studies.campaigns.gci import gci
from pilegroup.studies.campaigns.mesh_records import StudyInfo
from pilegroup.studies.campaigns.mesh_report import (
    error_figure,
    settlement_figure,
    size_results,
    write_mesh_report,
)
from pilegroup.studies.campaigns.mesh_study import (
    PENALTY_KEY,
    SizeCheck,
    StudyCase,
    check_size,
    study_cases,
    study_plan,
)
from pilegroup.studies.run.memory_check import estimated_peak_mb, run_estimate

BIN = Path(sys.executable).parent


def _csv(path):
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_size_that_does_not_fit_is_reported_with_the_reason(small_pile):
    ok = check_size(small_pile, {}, 0.6, ranks=1, groups=1, memory_mb=1e6)
    assert ok.runnable and ok.reason == "" and ok.estimated_unknowns > 0
    sc = load_scenario(small_pile, {"numerics.mesh.size_m": 0.6})
    _, unknowns, _, per_rank = run_estimate(sc, resolve_geometry(sc), 1)
    assert ok.estimated_unknowns == pytest.approx(unknowns)
    assert ok.estimated_memory_mb == pytest.approx(per_rank)  # one rank: the run's own estimate
    low = check_size(small_pile, {}, 0.6, ranks=1, groups=2, memory_mb=1000.0)
    assert not low.runnable and "GB per case (1.0 GB of memory / 2 cases at once)" in low.reason
    bad = check_size(small_pile, {}, 9.0, ranks=1, groups=1, memory_mb=1e6)
    assert not bad.runnable and bad.reason.startswith("invalid: numerics.mesh.")


def test_a_size_that_fits_only_out_of_core_runs_out_of_core():
    """The quarter pier at 1 m on one rank: with a share of memory between the out-of-core and
    the in-core estimates of the kept LU the size runs (its case takes the out-of-core LU);
    below the out-of-core estimate it is reported, not run."""
    n = check_size("pier667", {}, 1.0, ranks=1, groups=1, memory_mb=1e6).estimated_unknowns
    in_core = estimated_peak_mb(n, "direct_reuse", 1)
    ooc = estimated_peak_mb(n, "direct_reuse_ooc", 1)
    assert ooc < in_core
    mid = check_size("pier667", {}, 1.0, ranks=1, groups=2, memory_mb=ooc + in_core)
    assert mid.runnable and mid.estimated_memory_mb == pytest.approx(ooc)
    low = check_size("pier667", {}, 1.0, ranks=1, groups=2, memory_mb=1.9 * ooc)
    assert not low.runnable and low.estimated_memory_mb == pytest.approx(ooc)


def test_memory_grows_with_the_unknowns():
    """Per case (all its ranks): more unknowns, more memory; more ranks, more in all."""
    def case_mb(n, ranks):
        return ranks * estimated_peak_mb(n, "direct_reuse", ranks)

    assert case_mb(2e5, 2) > case_mb(1e5, 2) > case_mb(1e5, 1)


def test_penalty_cases_at_the_coarsest_and_finest_size(small_pile):
    sc = load_scenario(small_pile)
    checks = [SizeCheck(1.0, True), SizeCheck(0.5, True), SizeCheck(0.1, False, "memory")]
    cases = study_cases(sc, checks, 10.0)
    assert [(c.name, c.h, c.penalty) for c in cases] == [
        ("h1", 1.0, 1.0), ("h0.5", 0.5, 1.0), ("h1_penalty_x10", 1.0, 10.0),
        ("h0.5_penalty_x10", 0.5, 10.0)]
    plan = study_plan(small_pile, {"outputs.xdmf": False}, sc, cases)
    assert dict(plan.cases[2].overrides)[PENALTY_KEY] == 10.0 * (
        sc.interface.normal_stiffness_factor)
    tied = load_scenario(small_pile, {"interface.mode": "tied"})
    assert [c.name for c in study_cases(tied, checks, 10.0)] == ["h1", "h0.5"]


@pytest.mark.mpi
def test_study_report_agrees_with_the_batch(tmp_path, small_pile):
    out = tmp_path / "study"
    cmd = [str(BIN / "mpirun"), "-n", "2", str(BIN / "pilegroup"), "study", "mesh", small_pile,
           "--sizes", "1.0", "0.6", "0.3", "9.0", "--out", str(out), "--no-progress",
           "--set", "outputs.xdmf=false", "--set", "outputs.plots=false"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")})
    assert r.returncode == 0, r.stderr[-3000:]
    for name in ("mesh_study.md", "mesh_study.csv", "gci.csv", "settlement_vs_h.png",
                 "error_vs_time.png", "friction_profiles_sizes.png",
                 "relative_displacement_profiles_sizes.png"):
        assert (out / name).stat().st_size > 0, name
    batch = {row["name"]: row for row in _csv(out / "batch.csv")}
    assert set(batch) == {"h1", "h0.6", "h0.3", "h1_penalty_x10", "h0.3_penalty_x10"}
    assert all(row["status"] == "complete" for row in batch.values())
    assert float(batch["h0.3_penalty_x10"][PENALTY_KEY]) == 1000.0
    # the GCI table is the GCI of the batch's values at the last output time
    table = {row["quantity"]: row for row in _csv(out / "gci.csv")}
    h = (0.3, 0.6, 1.0)
    for quantity, column in (("settlement_m", "settlement_m@2d"),
                             ("friction_kPa[layer 1 mud]", "shaft_friction_kPa[1 mud]@2d"),
                             ("friction_kPa[layer 2 silty_clay]",
                              "shaft_friction_kPa[2 silty_clay]@2d")):
        phi = tuple(float(batch[f"h{x:g}"][column]) for x in h)
        want = gci(h, phi)
        row = table[quantity]
        assert [float(row[k]) for k in ("phi1", "phi2", "phi3")] == list(phi)
        for k in ("p", "phi_ext", "gci_fine21"):
            assert float(row[k]) == pytest.approx(getattr(want, k), rel=1e-12), (quantity, k)
    assert {f"friction_kPa[gauge {z:g} m]" for z in (1, 4, 8, 11.5)} <= set(table)
    sizes = {float(row["h_m"]): row for row in _csv(out / "mesh_study.csv")}
    assert sizes[9.0]["status"].startswith("not run: invalid: numerics.mesh.")
    assert set(sizes) == {9.0, 1.0, 0.6, 0.3} and sizes[0.3]["status"] == "complete"
    assert not any(k.startswith("published") for k in sizes[0.3])  # no [reference]
    assert float(sizes[0.3]["settlement_cm"]) == pytest.approx(
        100 * float(batch["h0.3"]["settlement_m@2d"]), rel=1e-12)
    assert int(sizes[0.3]["unknowns"]) == int(batch["h0.3"]["unknowns"])
    text = (out / "mesh_study.md").read_text()
    assert "* h = 9 m: not run: invalid:" in text and "## Interface normal penalty" in text
    assert "the answer depends on it" in text or "the answer does not depend on it" in text
    assert not {"paper", "table 2", "abaqus", "published"} & _words(text)


#: Made-up settlements (m) and layer-1 friction (kPa) at the last output time, by size.
FAKE = {1.0: (0.01389, 1.14), 0.6: (0.013928, 1.144), 0.3: (0.013955, 1.158),
        0.1: (0.013947, 1.16)}


def _words(text: str) -> set[str]:
    """Which of the words that name a published study ``text`` holds (lower case)."""
    low = text.lower()
    return {w for w in ("paper", "table 2", "abaqus", "published", "li et al") if w in low}


def _fake_study(tmp_path, scenario, sizes=(1.0, 0.6, 0.3, 0.1)):
    """A study's records and made-up batch rows (complete cases, no run folders)."""
    cases = tuple(StudyCase(f"h{h:g}", h) for h in sizes)
    rows = [{"name": c.name, "status": "complete", "cells": 1000 * (i + 1), "symmetry": "quarter",
             "unknowns": 4000 * (i + 1), "wall_s": 60.0 * (i + 1), "peak_rss_mb_max": 900.0,
             "output_days": [0.0, 317.0], "settlement_m": [0.0, FAKE[c.h][0]],
             "layer_friction_kPa": {"1 clay": [0.0, FAKE[c.h][1]]},
             "run_dir": str(tmp_path / "no_run" / c.name)} for i, c in enumerate(cases)]
    info = StudyInfo(scenario, tuple(SizeCheck(h, True) for h in sizes), cases, 2, 1, 8192.0,
                     10.0)
    return info, rows


def _figure_text(fig) -> str:
    """Every title, axis label and legend entry of ``fig``."""
    parts = []
    for ax in fig.axes:
        parts += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        legend = ax.get_legend()
        if legend is not None:
            parts += [t.get_text() for t in legend.get_texts()]
    return "\n".join(parts)


def test_a_study_without_a_reference_says_nothing_of_a_publication(tmp_path, small_pile):
    sc = load_scenario(small_pile)
    assert sc.reference is None
    info, rows = _fake_study(tmp_path, sc)
    write_mesh_report(tmp_path / "study", info, rows)
    text = (tmp_path / "study" / "mesh_study.md").read_text()
    assert "## The sizes" in text and "GCI_fine21" in text and not _words(text)
    table = _csv(tmp_path / "study" / "mesh_study.csv")
    assert [float(r["h_m"]) for r in table] == [1.0, 0.6, 0.3, 0.1]  # the study's sizes only
    assert not _words(",".join(table[0]))
    done = size_results(info, rows)
    for fig in (settlement_figure(done, None, sc.name, info.published),
                error_figure(done, None, info.published)):
        assert not _words(_figure_text(fig))


def test_pier667_sets_the_papers_table_2_beside_ours(tmp_path):
    sc = load_scenario("pier667")
    pub = sc.reference.mesh_study
    assert pub.sizes_m == (1.0, 0.8, 0.6, 0.3, 0.1) and pub.settlements_m[3] == 0.303
    info, rows = _fake_study(tmp_path, sc)
    write_mesh_report(tmp_path / "study", info, rows)
    text = (tmp_path / "study" / "mesh_study.md").read_text()
    assert {"paper", "table 2", "abaqus", "published"} <= _words(text)
    assert "| 0.8 | 63,553 | 0.9 | 35.2 | – |" in text  # the paper's size we did not run
    assert "| 0.3 | 105,522 | 6.8 | 30.3 | 3,000 (quarter) |" in text
    # the paper's own extrapolation from 0.6, 0.3 and 0.1 m
    assert "published settlements (paper Table 2 (Pier 667, ABAQUS); 0.6, 0.3, 0.1 m)" in text
    assert "extrapolated 30.2 cm" in text
    table = {float(r["h_m"]): r for r in _csv(tmp_path / "study" / "mesh_study.csv")}
    assert set(table) == set(pub.sizes_m) and table[0.8]["status"] == "not in the study"
    assert int(table[1.0]["published_elements"]) == 57108
    assert float(table[0.1]["published_hours"]) == 42.6
    assert float(table[0.6]["published_settlement_cm"]) == pytest.approx(34.6, rel=1e-12)
    done = size_results(info, rows)
    for fig in (settlement_figure(done, None, sc.name, info.published),
                error_figure(done, None, info.published)):
        assert "paper Table 2 (Pier 667, ABAQUS)" in _figure_text(fig)
