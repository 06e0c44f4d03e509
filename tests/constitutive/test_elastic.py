"""LinearElastic and the update protocol."""

import numpy as np
import pytest

from pilegroup.constitutive.base import ConstitutiveLaw, mandel_to_tensor, tensor_to_mandel
from pilegroup.constitutive.soil import LinearElastic
from pilegroup.errors import ConstitutiveError


def test_protocol_and_uniaxial():
    law = LinearElastic(E=3000.0, nu=0.42)
    assert isinstance(law, ConstitutiveLaw)
    assert law.state_layout() == {"stress": 6}
    st = law.initial_state(4, stress0=np.array([-10.0, -10.0, -20.0, 0, 0, 0]))
    snap = {k: v.copy() for k, v in st.items()}
    # uniaxial stress path: eps_xx = s/E, eps_yy = eps_zz = -nu s/E  ->  sigma = (s, 0, 0)
    s = 7.0
    de = np.tile([s / 3000.0, -0.42 * s / 3000.0, -0.42 * s / 3000.0, 0, 0, 0], (4, 1))
    stress, trial, tang = law.update(de, st, 1.0)
    np.testing.assert_allclose(stress - snap["stress"], np.tile([s, 0, 0, 0, 0, 0], (4, 1)),
                               atol=1e-12)
    for k in st:  # state_n not mutated
        np.testing.assert_array_equal(st[k], snap[k])
    assert tang.shape == (4, 6, 6)
    # shear: Mandel strain component 4 = sqrt2 eps_xy -> Mandel stress 2 G sqrt2 eps_xy
    G = 3000.0 / (2 * 1.42)
    de = np.zeros((1, 6))
    de[0, 3] = np.sqrt(2) * 1e-3
    stress, _, _ = law.update(de, law.initial_state(1), 1.0)
    assert stress[0, 3] / np.sqrt(2) == pytest.approx(2 * G * 1e-3, rel=1e-14)


def test_mandel_roundtrip():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(5, 6))
    np.testing.assert_allclose(tensor_to_mandel(mandel_to_tensor(v)), v, rtol=1e-15)
    t = mandel_to_tensor(v)
    # Mandel dot product = tensor double contraction
    np.testing.assert_allclose(np.einsum("pi,pi->p", v, v), np.einsum("pij,pij->p", t, t))


@pytest.mark.parametrize(("E", "nu", "word"), [(-1.0, 0.3, "E"), (1000.0, 0.5, "nu")])
def test_validation(E, nu, word):
    with pytest.raises(ConstitutiveError, match=word):
        LinearElastic(E=E, nu=nu)
