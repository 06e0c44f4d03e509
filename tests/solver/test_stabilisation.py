"""The pressure stabilisation parameter of each soil material: tau = 3 / (lambda + 2 mu) for
Q1-Q1, 2 / (lambda + 2 mu) for Q2-Q1.

``lambda + 2 mu`` is the constrained (oedometric) modulus ``E (1 - nu) / ((1 + nu)(1 - 2 nu))``
of the material's elastic part, the elastic moduli for a Mohr-Coulomb soil (docs/solver.md).
"""

import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.constitutive.soil import LinearElastic, MohrCoulomb
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box
from pilegroup.solver import BiotProblem, Discretisation, SoilMaterial
from pilegroup.studies.verification.common import box_bcs

#: (E kPa, nu) of the upper (linear elastic) and lower (Mohr-Coulomb) layer.
UPPER, LOWER = (3.0e3, 0.42), (2.15e4, 0.30)


def constrained_modulus(E, nu):
    return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))


@pytest.mark.parametrize(("pair", "scale"), [("Q1Q1", 3.0), ("Q2Q1", 2.0)])
@pytest.mark.parametrize("factor", [1.0, 0.5])
def test_tau_of_each_layer_from_its_elastic_moduli(factor, pair, scale):
    md = build_box(MPI.COMM_WORLD, (0.0, 1.0), (0.0, 1.0), np.linspace(-4.0, 0.0, 5), 1, 1,
                   layer_tops=[-2.0])
    upper = SoilMaterial(LinearElastic(*UPPER), k_m_per_day=1e-3, porosity=0.5)
    lower = SoilMaterial(MohrCoulomb(E=LOWER[0], nu=LOWER[1], c=7.4, phi_deg=25.0,
                                     psi_deg=0.0), k_m_per_day=6e-2, porosity=0.4)
    pb = BiotProblem(md, {groups.soil_layer(1): upper, groups.soil_layer(2): lower},
                     Discretisation(pair=pair, stab_factor=factor),
                     displacement_bcs=box_bcs(), self_weight=False)
    for j, (E, nu) in enumerate((UPPER, LOWER), start=1):
        cells = md.cell_tags.find(md.cell_tag(groups.soil_layer(j)))
        assert cells.size > 0
        np.testing.assert_allclose(pb.coef.tau.x.array[cells],
                                   factor * scale / constrained_modulus(E, nu), rtol=1e-12)
