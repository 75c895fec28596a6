"""When the balance controller's placement gain is chosen: every 0.5 s, again half-way
where the choice's rollout strays, and from scratch after the run goes back. The choices'
rollouts are stubbed (the costs given here): what is tested is the schedule."""

import math

from controller.balance.gain_selection import GainSelector
from controller.config import DEFAULT

REFINE_COST = DEFAULT.lookahead.refine_cost

EVERY = 60  # frames between choices (0.5 s at 120 fps)


class _Stub(GainSelector):
    """A selector whose choices return the next of ``costs`` (gain 0.3 when the cost is
    clean, else 0.6) and log the frame they were made at."""

    def __init__(self, costs):  # no model, no rollouts
        self.every_frames = EVERY
        self.refine_cost = REFINE_COST
        self.costs = list(costs)
        self.made = []
        self.last_cost = math.inf
        self._gains, self._refined = {}, {}

    def choose(self, data, frame):
        self.made.append(frame)
        self.last_cost = self.costs.pop(0)
        return 0.3 if self.last_cost <= REFINE_COST else 0.6

    def forget(self, keep=None):
        pass


def _run(selector, frames, fallback=0.3):
    return [selector.gain_at(None, t, fallback) for t in frames]


def test_a_clean_choice_holds_for_the_whole_interval():
    selector = _Stub([1.0, 1.0, 1.0])
    gains = _run(selector, range(1, 3 * EVERY + 1))
    assert selector.made == [0, EVERY, 2 * EVERY]
    assert set(gains) == {0.3}


def test_a_straying_choice_is_made_again_half_way():
    clean, straying = REFINE_COST / 2, REFINE_COST * 4
    selector = _Stub([straying, clean, clean, straying, straying])
    gains = _run(selector, range(1, 2 * EVERY + 1))
    half = EVERY // 2
    # the choice at 0 strays: again at 30, which holds to 60; 60 clean: none at 90
    assert selector.made == [0, half, EVERY]
    assert gains[:half] == [0.6] * half and gains[half:] == [0.3] * (2 * EVERY - half)
    # the choice at 120 strays and so does its half-way one: still one per half interval
    _run(selector, range(2 * EVERY + 1, 3 * EVERY + 1))
    assert selector.made == [0, half, EVERY, 2 * EVERY, 2 * EVERY + half]


def test_going_back_forgets_the_choices_from_there_on():
    straying = REFINE_COST * 4
    selector = _Stub([straying] * 6)
    _run(selector, range(1, EVERY + 1))
    half = EVERY // 2
    assert selector.made == [0, half]
    # back to frame 40: the state the choice at 30 was made from is unchanged, so it holds
    selector.went_back(40)
    assert _run(selector, [40, 41], fallback=0.45) == [0.6, 0.6]
    assert selector.made == [0, half]
    # back to the frame after the choice's own: it is made again from there
    selector.went_back(half + 1)
    _run(selector, [half + 1])
    assert selector.made == [0, half, half]
    # back past the start of the half interval's frame into the first half, then on
    # into the second half without passing its first frame in the default mode: the
    # fallback (the search's mode gave the frames between)
    selector.went_back(10)
    assert _run(selector, [10], fallback=0.45) == [0.6]
    assert _run(selector, [half + 5], fallback=0.45) == [0.45]
    assert selector.made == [0, half, half]
