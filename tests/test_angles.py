"""Angle maths: wrapping, shortest-way interpolation (paper Table 3), unwrapping."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from upm.ops.angles import (
    angle_diff_deg,
    angular_distance_sq,
    interpolate_deg,
    unwrap_deg,
    wrap_deg,
)

angles = st.floats(min_value=-5000, max_value=5000, allow_nan=False)
ratios = st.floats(min_value=0.0, max_value=1.0)


def paper_angular_medium(ratio, a, b):
    """Table 3 of the paper, verbatim: its ratio weights A (ratio 1 is A)."""
    if abs(a - b) > 180:
        if a < b:
            a += 360
        else:
            b += 360
    medium = a * ratio + b * (1 - ratio)
    if medium > 180:
        medium -= 360
    return medium


@given(angles)
def test_wrap_range_and_congruence(a):
    w = float(wrap_deg(a))
    assert -180.0 <= w < 180.0
    assert abs((a - w) / 360.0 - round((a - w) / 360.0)) < 1e-9


def test_wrap_known_values():
    np.testing.assert_allclose(wrap_deg([180, -180, 190, 1251, -540, 359.5]),
                               [-180, -180, -170, 171, -180, -0.5])


@given(angles, angles)
def test_diff_is_short_and_consistent(a, b):
    d = float(angle_diff_deg(a, b))
    assert -180.0 <= d < 180.0
    assert abs(float(wrap_deg(b + d - a))) < 1e-7


@given(angles, angles)
def test_interpolate_endpoints(a, b):
    assert float(interpolate_deg(a, b, 0.0)) == a
    assert abs(float(angle_diff_deg(interpolate_deg(a, b, 1.0), b))) < 1e-7


@given(angles, angles, ratios)
def test_interpolate_goes_the_short_way(a, b, alpha):
    c = float(interpolate_deg(a, b, alpha))
    total = abs(float(angle_diff_deg(b, a)))
    # C lies on the short arc: its distances to A and B add up to the arc length.
    to_a = abs(float(angle_diff_deg(c, a)))
    to_b = abs(float(angle_diff_deg(b, c)))
    assert to_a + to_b == pytest.approx(total, abs=1e-6)
    assert to_a == pytest.approx(alpha * total, abs=1e-6)


@given(st.floats(-180, 179.99), st.floats(-180, 179.99), ratios)
def test_interpolate_matches_paper_table3_with_swapped_ratio(a, b, alpha):
    if abs(abs(a - b) - 180) < 1e-6:
        return  # exactly opposite: both ways are equally short
    ours = float(interpolate_deg(a, b, alpha))
    theirs = paper_angular_medium(1 - alpha, a, b)
    assert abs(float(angle_diff_deg(ours, theirs))) < 1e-6


def test_interpolate_crosses_180_not_0():
    mid = float(interpolate_deg(170.0, -170.0, 0.5))
    assert abs(float(angle_diff_deg(mid, 180.0))) < 1e-12
    path = interpolate_deg(170.0, -170.0, np.linspace(0, 1, 11))
    assert np.all(np.abs(wrap_deg(path)) >= 170.0 - 1e-9)


@given(arrays(float, st.integers(2, 40), elements=st.floats(-179, 179)))
def test_unwrap_removes_jumps(samples):
    # Build an unwrapped signal with steps below 180 deg, wrap it, and unwrap it back.
    steps = np.clip(np.diff(samples), -170, 170)
    signal = np.concatenate([[samples[0]], samples[0] + np.cumsum(steps)])
    recovered = unwrap_deg(wrap_deg(signal))
    assert np.all(np.abs(np.diff(recovered)) < 180.0)
    np.testing.assert_allclose(recovered - recovered[0], signal - signal[0], atol=1e-8)


@given(arrays(float, (2, 5), elements=angles))
def test_distance_uses_wrapped_differences(pair):
    x, w = pair
    assert angular_distance_sq(x, w) == pytest.approx(angular_distance_sq(x + 360.0, w))
    assert angular_distance_sq(x, w) <= 5 * 180.0**2 + 1e-6
