"""The periodic spline of the gait: the curve scipy's periodic cubic spline gives."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import CubicSpline

from havln_mj.humans.motion.gait import PeriodicSpline


@pytest.mark.parametrize("seed", range(5))
def test_periodic_spline_matches_scipy(seed):
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.uniform(0.05, 1.0, 14))
    y = rng.normal(size=14)
    y[-1] = y[0]
    u = np.linspace(x[0] - 3.0, x[-1] + 3.0, 4001)  # outside the knots too: it repeats
    want = CubicSpline(x, y, bc_type="periodic")(u)
    np.testing.assert_allclose(PeriodicSpline(x, y)(u), want, rtol=0, atol=1e-12)


def test_periodic_spline_passes_through_its_knots():
    x = np.array([0.0, 0.2, 0.5, 0.7, 1.0])
    y = np.array([1.0, -2.0, 0.5, 3.0, 1.0])
    np.testing.assert_allclose(PeriodicSpline(x, y)(x), y, atol=1e-12)
