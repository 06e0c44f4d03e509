"""Test configuration: import pilegroup before any test module.

So dolfinx_solver is imported before dolfinx/petsc4py, whatever a test module's import order.
"""

import pytest  # noqa: E402

import pilegroup  # noqa: F401


@pytest.fixture
def small_pile(tmp_path):
    """The bundled single_pile scenario coarsened for the fast tier (same physics): its path."""
    from pilegroup.model import bundled_text

    text = bundled_text("single_pile")
    for old, new in [("size_m = 0.5", "size_m = 1.0\nn_circ_min = 8"),
                     ("far_field_size_m = 4.0", "far_field_size_m = 8.0"),
                     ("dz_max_m = 2.0", "dz_max_m = 4.0\ndz_surface_m = 2.0\ndz_toe_m = 2.0"),
                     ("dz_max_deep_m = 4.0", "dz_max_deep_m = 8.0"),
                     ("end_day = 10.0", "end_day = 2.0"),
                     ("output_days = [0.0, 0.5, 10.0]", "output_days = [0.0, 0.5, 2.0]")]:
        assert old in text, old
        text = text.replace(old, new)
    f = tmp_path / "small_pile.toml"
    f.write_text(text)
    return str(f)
