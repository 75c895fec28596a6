"""The balance controller's cost unit: raw mj_step bursts timed while a run goes on."""

import mujoco
import numpy as np
import pytest

from controller.raw_clock import RawStepClock

pytestmark = pytest.mark.physics  # free-root runs


class FakeClock:
    """A clock that moves only when told to, and by a fixed tick on every reading."""

    def __init__(self, tick_s: float = 0.0):
        self.now_s = 0.0
        self.tick_s = tick_s

    def __call__(self) -> float:
        self.now_s += self.tick_s
        return self.now_s


def _standing(model):
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    return data.qpos.copy(), data.qvel.copy()


def test_bursts_come_every_interval_and_their_time_is_kept_apart(model02):
    clock = FakeClock()
    qpos, qvel = _standing(model02)
    raw = RawStepClock(model02, qpos, qvel, every_s=0.1, burst_steps=4, clock=clock)
    for _ in range(5):
        raw.tick()  # not yet due: no burst
    assert raw.bursts == 0 and raw.spent_s == 0.0
    clock.now_s = 0.25
    clock.tick_s = 0.001  # each reading 1 ms on: begin, start, end of a burst
    raw.tick()  # due: one burst
    assert raw.bursts == 1
    assert raw.timed_steps == 4
    assert np.isclose(raw.timed_s, 0.001)  # start to end
    assert np.isclose(raw.spent_s, 0.002)  # begin to end, the warm-up step included
    raw.tick()  # the next one is due 0.1 s after the last burst's end
    assert raw.bursts == 1
    clock.now_s += 0.1
    raw.tick()
    assert raw.bursts == 2
    assert np.isclose(raw.step_s(), 0.002 / 8)


def test_a_run_too_short_for_a_burst_still_gets_its_unit(model02):
    qpos, qvel = _standing(model02)
    raw = RawStepClock(model02, qpos, qvel, every_s=1e9)
    raw.tick()
    assert raw.bursts == 0
    step_s = raw.step_s()
    assert raw.bursts == 1 and np.isfinite(step_s) and step_s > 0


def test_every_burst_steps_the_same_state(model02):
    """The bursts time the same work each time: the model's state from the given one."""
    qpos, qvel = _standing(model02)
    raw = RawStepClock(model02, qpos, qvel, burst_steps=3)
    raw.burst()
    first = raw.data.qpos.copy()
    raw.burst()
    np.testing.assert_array_equal(raw.data.qpos, first)
    assert not np.array_equal(first, qpos)  # it did step
