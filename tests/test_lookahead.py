"""The balance controller's lookahead rollouts: on two processes the same run as on one,
with the same frames taken from the rollouts; the frames the run takes from a recorded
rollout the same as simulating them again; the
helper process gone afterwards, and an error in the helper raised in the caller."""

import multiprocessing
import os

import mujoco
import numpy as np
import pytest

from controller import to_qpos
from controller.balance import gain_selection
from controller.balance.control import torque_model
from controller.balance.follow import follow
from controller.balance.lookahead import Lookahead
from controller.config import DEFAULT

MODES = DEFAULT.modes

pytestmark = pytest.mark.physics  # free-root runs


@pytest.fixture(scope="module")
def short_walk(model02, walk):
    # 130 frames at 120 fps: the gain is chosen at frames 0, 60 and 120
    return to_qpos(model02, walk)[:130], walk.fps


def test_two_processes_give_the_same_run(model02, short_walk):
    qpos, fps = short_walk
    one = follow(model02, qpos, fps)
    two = follow(model02, qpos, fps, processes=2)
    np.testing.assert_array_equal(one.ctrl, two.ctrl)
    np.testing.assert_array_equal(one.qpos, two.qpos)
    # the helper's rollouts come back recorded: the run takes the chosen gain's frames
    # whichever process rolled it out
    assert two.reused_steps == one.reused_steps > 0
    # on one process the chosen rollout goes on from its second half at the next choice
    # (frames 60-120 of the choice at 0 are those 0-60 of the choice at 60): a quarter
    # less lookahead work, the same run
    assert one.lookahead_steps < 0.85 * two.lookahead_steps
    assert not multiprocessing.active_children()


def test_a_whole_walk_is_the_same_however_its_frames_are_computed(model02, walk,
                                                                   monkeypatch):
    """02_01 start to end: on one process, on two, and with every frame simulated by the
    run itself, the same run bit for bit. A restored frame must leave the whole state as
    the controller did, its QP's warm start in the user data included (a short walk does
    not show a stale one: the warm start usually reaches the same active set anyway)."""
    qpos = to_qpos(model02, walk)
    one = follow(model02, qpos, walk.fps)
    two = follow(model02, qpos, walk.fps, processes=2)
    monkeypatch.setattr(gain_selection.GainSelector, "recorded", lambda self, t, gain: None)
    simulated = follow(model02, qpos, walk.fps)
    assert not one.fell and one.reused_steps > 0
    for run in (two, simulated):
        np.testing.assert_array_equal(run.ctrl, one.ctrl)
        np.testing.assert_array_equal(run.qpos, one.qpos)


def test_a_walk_the_search_works_on_is_the_same_on_two_processes(catalog):
    """35_01, where the search runs 17 segments again: the restarts drop what the helper's
    rollouts recorded, and the run and the search's counts are the same on two processes
    as on one, bit for bit."""
    from humanoid_xml import build_mjcf

    motion = catalog.load("35_01")
    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("35")))
    qpos = to_qpos(model, motion)
    one = follow(model, qpos, motion.fps, processes=1)
    two = follow(model, qpos, motion.fps, processes=2)
    assert one.retries == two.retries > 10
    np.testing.assert_array_equal(one.ctrl, two.ctrl)
    np.testing.assert_array_equal(one.qpos, two.qpos)
    np.testing.assert_array_equal(one.segment_modes, two.segment_modes)
    # the search's budget counts the same steps either way
    assert one.simulated_steps == two.simulated_steps
    assert not multiprocessing.active_children()


@pytest.mark.parametrize("processes", [1, 2])
def test_frames_taken_from_the_lookahead_are_the_frames_simulated(model02, short_walk,
                                                                   monkeypatch, processes):
    qpos, fps = short_walk
    taken = []
    recorded = gain_selection.GainSelector.recorded

    def counting(self, t, gain):
        out = recorded(self, t, gain)
        taken.append(out is not None)
        return out

    monkeypatch.setattr(gain_selection.GainSelector, "recorded", counting)
    reused = follow(model02, qpos, fps, processes=processes)
    assert sum(taken) > 60  # most of the run's frames came from its lookahead
    monkeypatch.setattr(gain_selection.GainSelector, "recorded", lambda self, t, gain: None)
    simulated = follow(model02, qpos, fps, processes=processes)
    np.testing.assert_array_equal(reused.ctrl, simulated.ctrl)
    np.testing.assert_array_equal(reused.qpos, simulated.qpos)
    np.testing.assert_array_equal(reused.torque_nm, simulated.torque_nm)
    np.testing.assert_array_equal(reused.contact_force_n, simulated.contact_force_n)
    assert reused.simulated_steps == simulated.simulated_steps
    # the work saved is counted: the frames taken, in physics steps, less the last step
    # of each (taken again to restore the frame), and nothing else
    assert reused.reused_steps == sum(taken) * (reused.substeps - 1)
    assert simulated.reused_steps == 0
    assert simulated.lookahead_steps > reused.steps
    if processes == 2:
        assert reused.lookahead_steps == simulated.lookahead_steps
    else:
        # and on one process the chosen rollout, whose frames the run took, goes on from
        # its second half at the next choice instead of being simulated again: the same
        # run (above) for less lookahead work
        assert reused.lookahead_steps < simulated.lookahead_steps


def test_processes_other_than_1_or_2_are_refused(model02, short_walk):
    qpos, fps = short_walk
    with pytest.raises(ValueError, match="1 or 2 processes"):
        follow(model02, qpos[:10], fps, processes=3)


class _FailsInHelper:
    """A controller whose step fails in any process but the one that made it."""

    def __init__(self, sim):
        self.sim, self.substeps, self.parent = sim, 1, os.getpid()
        self.ref_qvel = np.zeros((5, sim.nv))  # the reference at rest

    def step(self, data, k, mode, gain):
        if os.getpid() != self.parent:
            raise RuntimeError(f"step {k} failed in the helper")
        mujoco.mj_step(self.sim, data)
        return data.ctrl.copy(), data.ctrl.copy()


def test_an_error_in_the_helper_is_raised_in_the_caller(model02):
    sim = torque_model(model02)
    data = mujoco.MjData(sim)
    mujoco.mj_forward(sim, data)
    heights = np.full(5, 1.0)
    with Lookahead(_FailsInHelper(sim), heights, 1, processes=2) as lookahead:
        with pytest.raises(RuntimeError, match="failed in the helper"):
            lookahead.costs(data, 0, 3, (0.3, 0.6), MODES[0])
        # one process: both rollouts here, no error
        lookahead.processes = 1
        costs = lookahead.costs(data, 0, 3, (0.3, 0.6), MODES[0])
        assert costs[0] == costs[1]
    assert not multiprocessing.active_children()


class _Coasting:
    """A controller that applies no torque, with a reference at rest."""

    def __init__(self, sim, frames):
        self.sim, self.substeps = sim, 1
        self.ref_qvel = np.zeros((frames, sim.nv))

    def step(self, data, k, mode, gain):
        mujoco.mj_step(self.sim, data)
        return data.ctrl.copy(), data.ctrl.copy()


def test_a_rollout_that_strays_from_the_reference_pace_costs_more(model02):
    from controller.balance import lookahead

    sim = torque_model(model02)
    sim.opt.gravity[:] = 0.0  # nothing but the root's own velocity moves it
    data = mujoco.MjData(sim)
    mujoco.mj_forward(sim, data)
    data.qpos[2] += 1.0  # clear of the floor
    data.qvel[:2] = (0.3, -0.4)  # 0.5 m/s across the floor; the reference stands still
    control = _Coasting(sim, 6)
    heights = np.full(6, -1.0)  # never below the reference's pelvis
    costs = {}
    for weight in (0.0, 0.03):
        scratch = mujoco.MjData(sim)
        mujoco.mj_copyData(scratch, sim, data)
        costs[weight], steps = lookahead.rollout_cost(control, scratch, 0, 5, 0.3, MODES[0],
                                                      heights, 1, velocity_weight_s=weight)
        assert steps == 5
    # five frames at 0.5 m/s off the reference's pace, 0.03 s per m/s each
    assert costs[0.03] - costs[0.0] == pytest.approx(5 * 0.03 * 0.5, rel=1e-3)
