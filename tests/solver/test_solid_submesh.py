"""Elastic impermeable solid (pressure on the soil sub-mesh only), checked against Terzaghi.

A 10 m column: the upper 5 m are soil (drained top), the lower 5 m an elastic solid without
pressure (impermeable, same E and nu). The soil then consolidates exactly like a Terzaghi layer
of 5 m with an impermeable base, while the solid compresses at once by q H_s / m_oed; the
settlement is the sum.
"""

import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.geometry.box import build_box
from pilegroup.solver import (
    GAMMA_W,
    BiotProblem,
    DisplacementBC,
    ElasticSolid,
    PressureBC,
    SoilMaterial,
    SolverStage,
    StepControl,
    SurfaceLoad,
    run_stages,
)
from pilegroup.studies.verification import eval_points as _eval_points
from pilegroup.studies.verification import terzaghi_degree, terzaghi_series


@pytest.mark.parametrize("pair", ["Q2Q1", "Q1Q1"])
def test_soil_over_impermeable_solid(pair):
    from pilegroup.solver import Discretisation

    E, nu, k, n, q, Hs = 1.0e4, 0.3, 1.0e-3, 0.4, 100.0, 5.0
    levels = np.concatenate([np.linspace(-10, -5, 5), -np.geomspace(5, 0.15, 14), [0.0]])
    levels = np.unique(np.round(levels, 12))
    md = build_box(MPI.COMM_WORLD, (0, 1), (0, 1), levels, 1, 1, layer_tops=[-5.0])
    soil = SoilMaterial(LinearElastic(E, nu), k_m_per_day=k, porosity=n)
    mats = {"soil_layer_01": soil, "soil_layer_02": ElasticSolid(E, nu)}
    pb = BiotProblem(
        md, mats, Discretisation(pair=pair),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                          DisplacementBC("bottom", 2)],
        pressure_bcs=[PressureBC("ground_surface")],
        loads=[SurfaceLoad("ground_surface", q)], self_weight=False)
    assert pb.has_solids and pb.Q.dofmap.index_map.size_global < 2 * 2 * levels.size
    m = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    p0 = q / (1 + m * soil.storage)
    cv = (k / GAMMA_W) / (soil.storage + 1 / m)
    T = 0.2
    t_end = T * Hs**2 / cv
    ts = StepControl(dt0=1e-4 * t_end, dt_min=1e-12, dt_max=2e-3 * t_end, grow=10 ** (1 / 16))
    stages = [SolverStage("load", "load", 0.0, 1.0), SolverStage("cons", "consolidation", t_end)]
    run_stages(pb, stages, ts)
    z = np.linspace(-Hs, 0.0, 101)
    ph = _eval_points(pb.p, np.column_stack([np.full_like(z, 0.5), np.full_like(z, 0.5), z]))
    pe = terzaghi_series(-z, Hs, T, p0)
    err = np.sqrt(np.trapezoid((ph - pe) ** 2, z) / np.trapezoid(pe**2, z))
    assert err < 0.01
    s_h = -float(_eval_points(pb.u, np.array([[0.5, 0.5, 0.0]]))[2])
    s_e = (q * Hs - Hs * p0 * (1 - terzaghi_degree(T))) / m + q * Hs / m
    assert s_h == pytest.approx(s_e, rel=0.01)
