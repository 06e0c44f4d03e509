"""What the constitutive tests share: the tangent by central differences."""

import numpy as np
import pytest


@pytest.fixture
def fd_tangent():
    """``fd_tangent(law, de, state, h, dt=0.0) -> (D, same)``: the tangent of ``law.update`` at
    the strain increments ``de`` by central differences of step ``h``; ``same`` per point,
    whether all 12 stencil evaluations stay in the centre's return branch (the trial's
    ``mode``; a stencil across a region boundary is not a test of the tangent). A law
    without ``mode`` has one branch."""
    def tangent(law, de, state, h, dt=0.0):
        _, t0, _ = law.update(de, state, dt)
        mode = t0["mode"][:, 0] if "mode" in t0 else None
        D = np.empty((de.shape[0], 6, 6))
        same = np.ones(de.shape[0], dtype=bool)
        for j in range(6):
            e = np.zeros(6)
            e[j] = h
            sp, tp, _ = law.update(de + e, state, dt)
            sm, tm, _ = law.update(de - e, state, dt)
            D[:, :, j] = (sp - sm) / (2 * h)
            if mode is not None:
                same &= (tp["mode"][:, 0] == mode) & (tm["mode"][:, 0] == mode)
        return D, same
    return tangent
