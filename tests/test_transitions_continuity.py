"""Every method joins clips without a jump at both window edges — positions (C0) for
all, velocities too (C1) where the method promises it — including across the +-180 wrap:
on real pairs (data tier) and on the synthetic ones (unit tier, tests/synthetic.py).

The checks are in tests/transition_data.py (with their tolerances and why).
"""

import dataclasses

import numpy as np
import pytest

from controller.checks.kinematic_check import HumanoidChecker
from tests.transition_data import (
    PAIRS,
    SYNTHETIC_PAIRS,
    feasible_limit_turns,
    pair,
    sources,
    synthetic_pair,
    window_edges,
)
from upm.maps.posture_map import UniformPostureMap
from upm.maps.som import KohonenSOM
from upm.motion.limits import limit_excess_deg
from upm.motion.skeleton import POSTURE_DOF_NAMES
from upm.ops.angles import angle_diff_deg
from upm.transitions import (
    KINEMATIC_METHODS,
    METHODS,
    ClassNearest,
    NearestPosture,
    transition,
)
from upm.transitions.feasible import FeasibleKeys
from upm.transitions.feasible_range import range_boxes_deg

PROMISES = {"upm": "C1", "som": "C1", "classnn": "C1", "snap": "C1", "linear": "C0",
            "slerp": "C0", "inertialize": "C1", "spacetime": "C1", "feasible": "C1",
            "performed": "C0"}


def test_every_method_states_its_continuity():
    assert {name: m.continuity for name, m in METHODS.items()} == PROMISES


def _run(data_dir, method, before, after, frames=20):
    source = sources(data_dir).get(method) if METHODS[method].needs_key_source else None
    return transition(method, before, after, frames, 0.5, source)


FAST = [m for m in KINEMATIC_METHODS if m != "spacetime"]


@pytest.mark.parametrize("index", range(len(PAIRS)))
def test_joins_on_real_pairs(data_dir, index):
    before, after = pair(data_dir, index)
    for method in FAST + (["spacetime"] if index < 2 else []):
        result = _run(data_dir, method, before, after)
        (c0_a, c1_a), (c0_b, c1_b) = window_edges(result)
        assert c0_a <= 0 and c0_b <= 0, (method, PAIRS[index], c0_a, c0_b)
        if method == "feasible":  # C1 except where a join turns at a limit (the range wins)
            skip = feasible_limit_turns(before, after)
            (_, c1_a), (_, c1_b) = window_edges(result, skip)
        if METHODS[method].continuity == "C1":
            assert c1_a <= 0 and c1_b <= 0, (method, PAIRS[index], c1_a, c1_b)


@pytest.mark.parametrize("index", range(len(SYNTHETIC_PAIRS)))
def test_joins_on_synthetic_pairs(synthetic_catalog, synthetic_sources, index):
    before, after = synthetic_pair(synthetic_catalog, index)
    for method in FAST + (["spacetime"] if index == 0 else []):  # spacetime: about 1 s
        result = transition(method, before, after, 20, 0.5, synthetic_sources.get(method))
        (c0_a, c1_a), (c0_b, c1_b) = window_edges(result)
        assert c0_a <= 0 and c0_b <= 0, (method, SYNTHETIC_PAIRS[index], c0_a, c0_b)
        if method == "feasible":
            skip = feasible_limit_turns(before, after)
            (_, c1_a), (_, c1_b) = window_edges(result, skip)
        if METHODS[method].continuity == "C1":
            assert c1_a <= 0 and c1_b <= 0, (method, SYNTHETIC_PAIRS[index], c1_a, c1_b)


def test_the_velocity_check_catches_a_linear_blend_on_synthetic_pairs(synthetic_catalog):
    """The C1 check is not vacuous on the smooth synthetic curves either."""
    for index in range(len(SYNTHETIC_PAIRS)):
        before, after = synthetic_pair(synthetic_catalog, index)
        (_, c1_a), (_, c1_b) = window_edges(transition("linear", before, after, 20))
        assert c1_a > 0 and c1_b > 0, SYNTHETIC_PAIRS[index]


def test_the_velocity_check_catches_a_linear_blend(data_dir):
    """The C1 check can fail: the linear blend's velocity jump fails it on real pairs."""
    failures = 0
    for index in range(len(PAIRS)):
        before, after = pair(data_dir, index)
        (_, c1_a), (_, c1_b) = window_edges(_run(data_dir, "linear", before, after))
        failures += (c1_a > 0) + (c1_b > 0)
    assert failures >= len(PAIRS)


def test_the_position_check_catches_a_jump(synthetic_catalog):
    before, after = synthetic_pair(synthetic_catalog, 0)
    result = transition("inertialize", before, after, 20)
    assert all(e <= 0 for edge in window_edges(result) for e in edge)  # joined, until:
    window = result.window
    shifted = result.motion.posture_deg.copy()
    shifted[window, POSTURE_DOF_NAMES.index("lfemur.rx")] += 3.0  # a 3-degree jump
    broken = result.motion.replace(posture_deg=shifted)
    (c0_a, _), (c0_b, _) = window_edges(dataclasses.replace(result, motion=broken))
    assert c0_a > 0 and c0_b > 0


def _wrap_pair(catalog):
    """A synthetic pair with one slowly moving DOF moved to sit at +175 at A and -175 at
    B."""
    before, after = synthetic_pair(catalog, 0)
    declared = np.flatnonzero(before.skeleton.declared)
    speed = (np.abs(np.diff(before.posture_deg[-3:, declared], axis=0)).max(axis=0)
             + np.abs(np.diff(after.posture_deg[:3, declared], axis=0)).max(axis=0))
    dof = declared[np.argmin(speed)]
    p1, p2 = before.posture_deg.copy(), after.posture_deg.copy()
    p1[:, dof] += 175.0 - p1[-1, dof]
    p2[:, dof] += -175.0 - p2[0, dof]
    return before.replace(posture_deg=p1), after.replace(posture_deg=p2), dof


@pytest.mark.parametrize("method", KINEMATIC_METHODS)
def test_joins_across_the_wrap(synthetic_catalog, method):
    before, after, dof = _wrap_pair(synthetic_catalog)
    # Key sources that know postures near +-180 in that DOF: fitted on the two clips.
    own = np.concatenate([before.posture_deg, after.posture_deg])
    kind = METHODS[method].key_kind
    makers = {"classnn": ClassNearest, "snap": NearestPosture,
              "upm": lambda x: UniformPostureMap().fit(x), "som": lambda x: KohonenSOM().fit(x),
              "feasible": lambda x: FeasibleKeys(UniformPostureMap().fit(x), HumanoidChecker)}
    source = makers[kind](own) if kind in makers else None
    result = transition(method, before, after, 20, 0.5, source)
    (c0_a, c1_a), (c0_b, c1_b) = window_edges(result)
    assert c0_a <= 0 and c0_b <= 0
    if METHODS[method].continuity == "C1":
        assert c1_a <= 0 and c1_b <= 0
    window = result.window_posture_deg[:, dof]
    assert np.all((window >= -180.0) & (window < 180.0))  # wrapped, as documented
    if method == "feasible" and result.diagnostics["long_way_dofs"]:
        # The short way passes the DOF's human-range box (widened by the ends' excess
        # still stops short of 180): feasible goes the long way, inside the range.
        limits = range_boxes_deg(before.skeleton)[dof:dof + 1]
        ends = limit_excess_deg(np.array([[before.posture_deg[-1, dof]],
                                          [after.posture_deg[0, dof]]]), limits).max()
        assert limit_excess_deg(window[:, None], limits).max() <= ends + 1e-6
        return
    # The short way: 10 degrees through 180, never back through 0.
    assert np.all(np.abs(angle_diff_deg(window, 180.0)) < 45.0), window
