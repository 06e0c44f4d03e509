"""Fixtures of the run-folder tests (checkpoints, damaged checkpoints): one per test module;
and the laboratory tests' noisy copies of a curve."""

import csv

import numpy as np
import pytest


@pytest.fixture
def noisy():
    """``noisy(path, column, seed, out)``: ``path`` with ``column`` times (1 + 0.02 N(0, 1)),
    written to ``out`` (the CSV layout of ``pilegroup lab``); returns ``out``."""
    def write(path, column, seed, out):
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        i = rows[0].index(column)
        rng = np.random.default_rng(seed)
        for r in rows[1:]:
            r[i] = f"{float(r[i]) * (1.0 + 0.02 * rng.standard_normal()):.10g}"
        with open(out, "w", newline="") as fh:
            csv.writer(fh, lineterminator="\n").writerows(rows)
        return out
    return write


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """A mesh cache shared by the module's runs."""
    return tmp_path_factory.mktemp("mesh_cache")


@pytest.fixture(scope="module")
def scenario(tmp_path_factory, small_pile_source):
    """The small pile's scenario file (tests/conftest.py), one per module."""
    f = tmp_path_factory.mktemp("scenario") / "small_pile.toml"
    f.write_text(small_pile_source)
    return f
