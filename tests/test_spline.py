"""The key-frame spline as a cached weight matrix equals scipy's interpolating spline."""

import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from upm.transitions.spline import keyframe_spline, spline_weights


@pytest.mark.parametrize("times", [[0.0, 5.5], [-1.0, 0.0, 10.5], [-2, -1, 0, 10.5, 21, 22, 23],
                                   [0, 3.0, 4.0, 9.0, 9.5]])
def test_weights_reproduce_scipy(times):
    rng = np.random.default_rng(len(times))
    values = rng.normal(scale=90.0, size=(len(times), 63))
    query = np.linspace(min(times), max(times), 17)
    expected = make_interp_spline(times, values, k=min(3, len(times) - 1), axis=0)(query)
    np.testing.assert_allclose(keyframe_spline(times, values, query), expected,
                               rtol=0, atol=1e-9)
    # The spline passes through its keys, and the weights are cached read-only.
    np.testing.assert_allclose(keyframe_spline(times, values, times), values, atol=1e-9)
    w = spline_weights(times, query)
    assert w is spline_weights(np.asarray(times), query) and not w.flags.writeable
