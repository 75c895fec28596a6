"""The offline effort's warm start and lookahead (controller.offline.warm, samcon): the
real-time controller's run turned into servo targets is replayed by the servos step for
step, a real-time run that falls leaves the plan as it was, a walk the search alone falls
on stands from the warm start, and the lookahead charges a state that is tipping over."""

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.balance.follow import follow
from controller.config import DEFAULT
from controller.offline import perform
from controller.offline.rollouts import Roller
from controller.offline.samcon import _lookahead, _score, rank
from controller.offline.warm import warm_plan
from controller.tracking.plan import plan_tracking
from controller.tracking.servo import track_plan
from tests.test_balance import _feet_lifted

pytestmark = pytest.mark.physics  # free-root runs

#: A small search: a test's run takes seconds, not minutes.
SMALL = DEFAULT.updated({"offline": {"samples": 32, "keep": 4, "warm_start": True}})


def test_the_warm_plan_is_the_real_time_run_step_for_step(model02, walk):
    qpos = to_qpos(model02, walk)[:60]
    plan = plan_tracking(model02, qpos, walk.fps, "free", True, DEFAULT)
    warm = warm_plan(model02, plan, DEFAULT)
    assert not warm.realtime_fell and warm.used_frames == 60
    sim = warm.plan.model
    np.testing.assert_array_equal(sim.actuator_biasprm[:, 2], 0.0)  # no servo damping
    assert not sim.actuator_ctrllimited.any()
    np.testing.assert_array_equal(sim.actuator_forcerange, model02.actuator_forcerange)
    assert plan.model.actuator_ctrllimited.all()  # the plan given is not changed
    run = follow(model02, plan.reference_qpos, walk.fps, config=DEFAULT)
    replayed = track_plan(model02, warm.plan, DEFAULT)
    np.testing.assert_allclose(replayed.qpos, run.qpos, atol=1e-9)
    # and the targets matter: the reference's targets on the undamped servos differ
    assert np.abs(track_plan(model02, plan, DEFAULT).qpos - run.qpos).max() > 1e-3


def test_where_the_real_time_run_falls_the_plan_is_kept(model02):
    qpos, fps = _feet_lifted(model02)
    config = DEFAULT.with_search_budget(0)
    plan = plan_tracking(model02, qpos[:240], fps, "free", True, config)
    warm = warm_plan(model02, plan, config)
    assert warm.realtime_fell and warm.used_frames == 0
    assert warm.plan is plan


def test_a_walk_the_search_alone_falls_on_stands_from_the_warm_start(catalog):
    """05_01's first 2.5 s: the search from the reference's targets fell at 1.11 s (the
    default search, every clip's table); from the real-time run, with 32 samples, it
    stands."""
    from humanoid_xml import build_mjcf

    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("05")))
    motion = catalog.load("05_01")
    qpos = to_qpos(model, motion)[:301]
    result = perform(model, qpos, motion.fps, SMALL)
    assert not result.fell
    assert result.summary()["error_deg_rms"] < 8.0


def test_the_lookahead_charges_a_state_that_is_tipping_over(model02, walk):
    from controller.body import body_figures
    from controller.offline.cost import FeatureMaker

    config = DEFAULT.updated({"offline": {"lookahead_s": 0.6, "lookahead_top": 2}})
    off = config.offline
    plan = plan_tracking(model02, to_qpos(model02, walk)[:30], walk.fps, "free", True,
                         config)
    features = FeatureMaker(plan.model)
    ref = features.reference(plan.reference_qpos, plan.fps)
    figures = body_figures(model02)
    tipped = plan.start_qpos.copy()
    tipped[3:7] = [np.cos(np.radians(40)), np.sin(np.radians(40)), 0.0, 0.0]  # 80 deg
    with Roller(plan.model, 1) as roller:
        states = np.stack([roller.state_of(plan.start_qpos, plan.start_qvel),
                           roller.state_of(tipped, plan.start_qvel),
                           roller.state_of(plan.start_qpos, plan.start_qvel)])
        ahead, fell, down, steps = _lookahead(
            roller, plan, states, np.zeros((3, plan.model.nu)), np.array([0.0, 0.1, 0.2]),
            0, lambda q, v, f: _score(q, v, f, ref, features, figures, config), off)
    assert list(fell) == [False, True, True]  # the third is not looked ahead: not judged
    assert list(down) == [False, True, True]
    assert 0.0 <= ahead[0] < off.trouble_cost
    assert ahead[1] >= off.fall_cost and ahead[2] == np.inf
    assert steps == 2 * round(0.6 * walk.fps) * plan.substeps


def test_the_segment_score_says_which_states_end_in_trouble(model02, walk):
    """A state at the reference is out of trouble; one with the pelvis 20 cm under the
    reference's (the search's trouble test: 12 cm), or tilted 60 deg, is in it."""
    from controller.body import body_figures
    from controller.offline.cost import FeatureMaker

    plan = plan_tracking(model02, to_qpos(model02, walk)[:30], walk.fps, "free", True,
                         DEFAULT)
    features = FeatureMaker(plan.model)
    ref = features.reference(plan.reference_qpos, plan.fps)
    qpos = np.repeat(plan.reference_qpos[None, :3], 3, axis=0)  # (3 states, 3 frames, nq)
    qpos[1, :, 2] -= 0.20
    qpos[2, :, 3:7] = [np.cos(np.radians(30)), np.sin(np.radians(30)), 0.0, 0.0]
    qvel = np.zeros((3, 3, plan.model.nv))
    _, fell, down = _score(qpos, qvel, np.arange(3), ref, features, body_figures(model02),
                           DEFAULT)
    assert list(down) == [False, True, True]
    assert not fell[0]


def test_the_ranking_keeps_upright_states_before_cheaper_ones_going_down():
    cost = np.array([0.5, 0.1, 0.3, 0.2])
    ahead = np.array([0.0, 0.0, 0.0, np.inf])
    down = np.array([False, True, False, False])
    assert list(rank(cost, ahead, down)) == [2, 0, 3, 1]
    assert list(rank(cost, ahead, down, upright_first=False)) == [1, 2, 0, 3]
