"""The balance controller's search one attempt ahead on the second process
(controller.search_ahead): on the real walk 35_01, where the search runs segments again,
two processes give the same run as one, bit for bit, with the same attempts, while frames
of the attempts guessed ahead are taken instead of simulated; a guess made for an attempt
that does not come is dropped."""

import multiprocessing

import mujoco
import numpy as np
import pytest

from controller import search_ahead as ahead_module
from controller import to_qpos
from controller.balance import follow


@pytest.fixture(scope="module")
def run_35_01(catalog):
    from humanoid_xml import build_mjcf

    motion = catalog.load("35_01")
    model = mujoco.MjModel.from_xml_string(build_mjcf(catalog.skeleton("35")))
    return model, to_qpos(model, motion), motion.fps


def test_the_search_ahead_gives_the_same_run_as_one_process(run_35_01, monkeypatch):
    model, qpos, fps = run_35_01
    guesses = {"restarts": 0, "right": 0}
    restarted = ahead_module.SearchAhead.restarted

    def counting(self, search, segment, mode, searching):
        guesses["restarts"] += 1
        guesses["right"] += self.guess == (search.retries, segment, mode)
        return restarted(self, search, segment, mode, searching)

    monkeypatch.setattr(ahead_module.SearchAhead, "restarted", counting)
    one = follow(model, qpos, fps, processes=1)
    two = follow(model, qpos, fps, processes=2)
    assert one.retries == two.retries > 10  # the search runs (17 segments again)
    np.testing.assert_array_equal(one.ctrl, two.ctrl)
    np.testing.assert_array_equal(one.qpos, two.qpos)
    np.testing.assert_array_equal(one.segment_modes, two.segment_modes)
    # the search's budget counts the same steps either way
    assert one.simulated_steps == two.simulated_steps
    # on one process nothing is guessed; on two most restarts were guessed right, and
    # their frames taken from the helper's recording instead of simulated
    assert guesses["restarts"] == two.retries
    assert guesses["right"] > two.retries // 3
    assert two.reused_steps > one.reused_steps
    assert two.lookahead_steps > one.lookahead_steps
    assert not multiprocessing.active_children()


def test_a_wrong_guess_is_dropped(run_35_01, monkeypatch):
    model, qpos, fps = run_35_01
    one = follow(model, qpos, fps, processes=1)
    # every guess is for the wrong mode: the run must not take any of its frames
    entered = ahead_module.SearchAhead.entered

    def wrong(self, search, t):
        entered(self, search, t)
        if self.guess is not None:
            retries, segment, mode = self.guess
            self.guess = (retries, segment, mode + 100)

    monkeypatch.setattr(ahead_module.SearchAhead, "entered", wrong)
    two = follow(model, qpos, fps, processes=2)
    np.testing.assert_array_equal(one.qpos, two.qpos)
    assert two.reused_steps == one.reused_steps
