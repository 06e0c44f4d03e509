"""Fixtures of the run-folder tests (checkpoints, damaged checkpoints): one per test module."""

import pytest


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
