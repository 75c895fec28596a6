"""The fall rule: below half the standing height, the reference not, and well below it."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from controller.config import DEFAULT
from controller.falls import fall_frame, fall_rule, fallen

FALL_FRACTION, FALL_MARGIN = DEFAULT.falls.fraction, DEFAULT.falls.margin

FIGURES = SimpleNamespace(pelvis_height_m=1.0, head_height_m=1.6)


@pytest.mark.parametrize("pelvis, reference, down", [
    (0.40, 1.00, True),    # the reference stands: down
    (0.48, 0.52, False),   # following a reference that bends through half height
    (0.48, 0.62, True),    # 14 cm under it: down
    (0.10, 0.45, False),   # the reference lies down too
    (np.nan, 1.00, False),  # not simulated
])
def test_pelvis_down_only_well_below_a_reference_that_is_up(pelvis, reference, down):
    head, ref_head = np.array([1.5]), np.array([1.5])
    got = fallen(np.array([pelvis]), head, np.array([reference]), ref_head, FIGURES)
    assert got.tolist() == [down]


@given(st.floats(0.0, 2.0), st.floats(0.0, 2.0))
def test_the_head_is_judged_by_the_same_rule(head_m, reference_m):
    got = fallen(np.array([0.9]), np.array([head_m]), np.array([0.9]),
                 np.array([reference_m]), FIGURES)[0]
    low = FALL_FRACTION * FIGURES.head_height_m
    want = (head_m < low and reference_m >= low
            and reference_m - head_m > FALL_MARGIN * FIGURES.head_height_m)
    assert got == want


def test_the_first_frame_down_and_the_rule_in_words():
    reference = np.array([1.0, 0.8, 0.55, 0.55, 0.9])
    pelvis = np.array([1.0, 0.75, 0.47, 0.40, 0.40])
    head = np.full(5, 1.5)
    assert fall_frame(pelvis, head, reference, head, FIGURES) == 3
    assert "0.500 m" in fall_rule(FIGURES) and "0.160 m" in fall_rule(FIGURES)


def test_the_rule_is_the_configurations():
    """Another share and margin are another rule, in numbers and in words."""
    from dataclasses import replace

    strict = replace(DEFAULT.falls, fraction=0.8, margin=0.05)
    pelvis, head = np.array([0.75]), np.array([1.5])
    assert not fallen(pelvis, head, np.array([1.0]), head, FIGURES)[0]
    assert fallen(pelvis, head, np.array([1.0]), head, FIGURES, strict)[0]
    assert "0.800 m" in fall_rule(FIGURES, strict) and "0.080 m" in fall_rule(FIGURES, strict)
