"""The 3D view (studies.view3d) of real small runs: interface mode (soil and structure files)
and tied mode (one displacement field, soil told apart by the pressure sub-mesh)."""

import math
import shutil
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from matplotlib.image import imread

from pilegroup.studies.report.run_report import results_markdown, write_report
from pilegroup.studies.report.view3d import FILE, WINDOW, load_view_data, write_view3d

PILE_LENGTH, PILE_RADIUS, SITE = 12.0, 0.4, (16.0, 16.0, 20.0)  # bundled single_pile, m


def test_run_writes_a_readable_view(small_pile_run):
    img = imread(small_pile_run / "plots" / FILE)
    assert img.shape[:2] == (WINDOW[1], WINDOW[0])
    rgb = np.round(255 * img[..., :3]).astype(np.uint32).reshape(-1, 3)
    colours = np.unique(rgb @ np.array([1 << 16, 1 << 8, 1], dtype=np.uint32))
    assert len(colours) > 1000  # shaded colour map, not a blank picture
    assert np.any(rgb < 240, axis=1).mean() > 0.3  # the block fills a good part of the frame
    assert f"plots/{FILE}" in results_markdown(small_pile_run, "plots")


def test_view_data_at_the_last_output_time(small_pile_run):
    d = load_view_data(small_pile_run)
    assert d.t_day == 2.0
    assert d.soil.volume + d.structure.volume == pytest.approx(math.prod(SITE), rel=1e-9)
    # the pile: an 8-sided prism (n_circ_min = 8) of the circle's area, 12 m long
    assert d.structure.volume == pytest.approx(math.pi * PILE_RADIUS**2 * PILE_LENGTH, rel=1e-6)
    # the pile settles (down positive) as much as the cap settlement written at that time
    last = (small_pile_run / "settlement.csv").read_text().splitlines()[-1].split(",")
    assert float(last[0]) == 2.0
    pile = np.asarray(d.structure.point_data["settlement_mm"])
    assert 1000 * float(last[-1]) == pytest.approx(pile.max(), rel=0.05)
    assert pile.min() > 0 and d.soil.point_data["settlement_mm"].max() <= pile.max() + 1e-9


def _drop_last_time(xdmf):
    tree = ET.parse(xdmf)
    for coll in tree.getroot().iter("Grid"):
        if coll.get("CollectionType") == "Temporal":
            coll.remove(coll.findall("Grid")[-1])
    tree.write(xdmf)


def test_report_redraws_the_view_and_skips_partial_output(small_pile_run, tmp_path, caplog):
    out = shutil.copytree(small_pile_run, tmp_path / "run")
    (out / "plots" / FILE).unlink()
    assert FILE in [p.name for p in write_report(out)]  # what `pilegroup report OUT` does
    # shared between two ranks: each figure written once, the 3D view by the last
    whole = sorted(p.name for p in write_report(out))
    first, second = ([p.name for p in write_report(out, (k, 2))] for k in (0, 1))
    assert sorted(first + second) == whole and not set(first) & set(second)
    assert FILE in second and len(first) >= len(second) - 1
    tied = not (out / "results_structure.xdmf").exists()
    # an interrupted run, one output behind (interface mode: the structure file only, and the
    # view takes the last time common to both files): drawn at 0.5 day
    _drop_last_time(out / ("results.xdmf" if tied else "results_structure.xdmf"))
    assert load_view_data(out).t_day == 0.5
    # missing data or an XDMF file cut short while being rewritten: no view, a logged reason
    # (write_report draws its other figures and lists what write_view3d returns)
    (out / ("results_pressure.h5" if tied else "results_structure.h5")).unlink()
    xdmf = out / "results.xdmf"
    for damage in ("missing h5", "cut xdmf"):
        if damage == "cut xdmf":
            text = xdmf.read_text()
            xdmf.write_text(text[: len(text) // 2])
        caplog.clear()
        with caplog.at_level("INFO", logger="pilegroup.studies.report.view3d"):
            assert write_view3d(out) is None, damage
        assert f"skipping {FILE}: " in caplog.text, damage
