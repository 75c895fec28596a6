"""Joint-limit excess on the circle, and the out-of-limit share of real clips."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from upm.motion.limits import limit_excess_deg, outside_share

limits = np.array([[-160.0, 20.0], [-10.0, 170.0], [0.0, 0.0]])


def test_known_excesses():
    angles = np.array([[25.0, -30.0, 0.0], [20.0, 170.0, 1e-9], [-170.0, 200.0, 5.0]])
    np.testing.assert_allclose(limit_excess_deg(angles, limits),
                               [[5, 20, 0], [0, 0, 0], [10, 30, 5]])


def test_unwrapped_angle_compared_modulo_360():
    assert limit_excess_deg(np.array([[380.0]]), np.array([[-160.0, 20.0]]))[0, 0] == 0.0
    assert limit_excess_deg(np.array([[745.0]]), np.array([[-160.0, 20.0]]))[0, 0] == 5.0


@given(st.floats(-720, 720), st.floats(-170, 0), st.floats(0, 170))
def test_excess_is_circular_distance_to_the_arc(angle, lo, hi):
    excess = limit_excess_deg(np.array([[angle]]), np.array([[lo, hi]]))[0, 0]
    grid = np.linspace(lo, hi, 2001)
    distance = np.abs((angle - grid + 180.0) % 360.0 - 180.0).min()
    assert excess >= 0
    assert abs(excess - distance) <= (hi - lo) / 2000 + 1e-6


def test_real_clips_leave_their_limits(all_motions):
    # The CMU README: 3-17 % of samples per clip lie outside the ASF limits.
    shares = {name: outside_share(m)[0] for name, m in all_motions.items()}
    assert all(0.02 < s < 0.17 for s in shares.values()), shares
    assert shares["05_06"] > shares["16_15"]  # dance leaves them more than a walk



def test_tolerance_applies_at_both_ends():
    """A value a hair outside either end is inside (a hair below the lower end used to
    wrap to about 360 degrees: lclavicle.rz = -3.3e-14 against 0); clearly outside is not."""
    limits = np.array([[0.0, 20.0], [-160.0, 20.0]])
    for hair in (1e-14, 3.3e-14, 1e-9, 5e-7):
        below = np.array([[-hair, -160.0 - hair]])
        above = np.array([[20.0 + hair, 20.0 + hair]])
        assert limit_excess_deg(np.vstack([below, above]), limits).max() == 0.0
    outside = limit_excess_deg(np.array([[-0.5, -160.5], [20.5, 20.5]]), limits)
    np.testing.assert_allclose(outside, 0.5, atol=1e-9)
