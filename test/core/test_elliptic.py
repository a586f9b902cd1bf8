"""Carlson's integrals and the AGM Jacobi functions of core/elliptic.py against scipy."""

import math

import numpy as np
import pytest
from scipy.special import ellipj, elliprf, elliprj

from rigid_rot_sim.core import elliptic
from rigid_rot_sim.core.elliptic import agm_buffers, agm_tables, carlson_rf, carlson_rj, jacobi


def test_carlson_integrals_match_scipy_to_a_few_ulps():
    rng = np.random.default_rng(0)
    for _ in range(500):
        x, y, z = rng.uniform(0.0, 3.0, 3) ** rng.integers(1, 4, 3)
        p = rng.uniform(0.01, 5.0)
        if rng.random() < 0.2:
            x = 0.0  # the exact flow calls R_J(0, 1 - m, 1, 1 - n)
        assert abs(carlson_rf(x, y, z) / elliprf(x, y, z) - 1.0) < 2e-15
        assert abs(carlson_rj(x, y, z, p) / elliprj(x, y, z, p) - 1.0) < 4e-15


def test_jacobi_functions_match_scipy():
    a, c = agm_buffers()
    for m in (0.1, 0.5, 0.9, 0.999999):
        levels = agm_tables(m, 1.0 - m, a, c)
        quarter_period = np.pi / (2.0 * a[levels])
        for r in np.linspace(-quarter_period, quarter_period, 11):
            sn, cn, dn = jacobi(r, a, c, levels, 1.0 - m)
            expected = ellipj(r, m)[:3]
            np.testing.assert_allclose((sn, cn, dn), expected, rtol=0, atol=1e-13)


@pytest.mark.parametrize("bad", [math.inf, math.nan])
def test_carlson_integrals_return_nan_for_non_finite_arguments_instead_of_looping(bad):
    # an overflowed phase (exact flow at an absurd step) once made the duplication loop forever
    assert math.isnan(elliptic.carlson_rf(1.0, bad, 2.0))
    assert math.isnan(elliptic.carlson_rc(bad, 1.0))
    assert math.isnan(elliptic.carlson_rj(1.0, 2.0, 3.0, bad))


def test_compiled_two_product_gives_the_bits_of_dekkers_split():
    """The kernels' two_product (one FMA) and the interpreted one (Dekker's split) agree bit for bit."""
    from numba import njit

    @njit(cache=False)
    def compiled(a, b, out):
        for k in range(a.size):
            out[k, 0], out[k, 1] = elliptic.two_product(a[k], b[k])

    rng = np.random.default_rng(21)
    a = rng.standard_normal(2000) * 10.0 ** rng.integers(-150, 150, 2000)
    b = rng.standard_normal(2000) * 10.0 ** rng.integers(-150, 150, 2000)
    a[:4] = (1.0 + 2.0**-52, 0.1, 3.0, -0.0)
    b[:4] = (1.0 - 2.0**-53, 0.7, 1.0 / 3.0, 5.0)
    out = np.empty((a.size, 2))
    compiled(a, b, out)
    for k in range(a.size):
        p, e = elliptic.two_product(float(a[k]), float(b[k]))
        assert (out[k, 0], out[k, 1]) == (p, e)
        assert abs(e) <= 0.5 * math.ulp(p)
