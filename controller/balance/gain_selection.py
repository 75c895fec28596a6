"""The foot-placement gain of the balance controller's default mode, chosen by lookahead.

Every ``lookahead.every_s`` (0.5 s) the gain is chosen among the configuration's
:attr:`controller.config.ControllerConfig.gains` (``placement.gain`` and
``lookahead.other_gains``) by rolling the same controller out ``lookahead.horizon_s``
(1 s) ahead from a copy of the state and keeping the gain whose pelvis stays nearest the
reference's height and upright (:mod:`controller.balance.lookahead`). Where even the chosen
gain's rollout strays (its cost over ``lookahead.refine_cost``) the gain is chosen again
half-way to the next choice: the body is heading for trouble, and a choice from a state
0.25 s on sees it sooner.
"""

from __future__ import annotations

import math

from controller.config import DEFAULT, ControllerConfig


class GainSelector:
    """Every ``lookahead.every_s`` (and half-way on where the choice's rollout cost more
    than ``lookahead.refine_cost``), the foot-placement gain of ``config.gains`` whose
    ``lookahead.horizon_s`` rollout (the same controller, from a copy of the state) keeps
    the pelvis nearest the reference's height and upright, and the pace nearest the
    reference's (:func:`controller.balance.lookahead.rollout_cost`); the first on ties. The
    rollouts run on ``processes`` processes (:class:`controller.balance.lookahead.Lookahead`),
    in the configuration's default mode (its first)."""

    def __init__(self, control, ref_pelvis, pelvis_body: int, fps: float, n_frames: int,
                 processes: int = 1, config: ControllerConfig = DEFAULT):
        from controller.balance.lookahead import Lookahead, Recording

        settings = config.lookahead
        self.gains = config.gains
        self.default_mode = config.modes[0]
        self.refine_cost = settings.refine_cost
        self.n_frames = n_frames
        self.every_frames = max(1, int(round(settings.every_s * fps)))
        self.lookahead_frames = max(1, int(round(settings.horizon_s * fps)))
        self.lookahead = Lookahead(control, ref_pelvis, pelvis_body, processes, config)
        # on one process the chosen rollout is recorded whole: the next choice goes on
        # from its second half instead of simulating it again
        self.resumes = processes == 1
        capacity = (self.lookahead_frames if self.resumes
                    else min(self.every_frames, self.lookahead_frames))
        self.recordings = [Recording(control.sim, capacity, control.substeps)
                           for _ in self.gains]
        self.chain = None
        self.last_choice = 0
        self.last_cost = math.inf
        # per choice's start frame, the gain from it on and whether it is chosen again
        # half-way to the next
        self._gains = {}
        self._refined = {}

    def gain_at(self, data, t: int, fallback: float) -> float:
        """The default mode's gain for frame ``t`` (``data``: the state after frame
        ``t - 1``). It is chosen (:meth:`choose`) at the frame its choice starts from when
        the run passes that frame in the default mode; a run that comes to a choice's
        span later (after the search's other modes, or having gone back into it) takes
        ``fallback`` for it."""
        first = (t - 1) - (t - 1) % self.every_frames
        half = first + self.every_frames // 2
        if t - 1 >= half and self._refined.get(first, False):
            first = half
        if first not in self._gains:
            if first == t - 1:
                self._gains[first] = self.choose(data, first)
                self._refined[first] = self.last_cost > self.refine_cost
            else:
                self._gains[first] = fallback
        return self._gains[first]

    def went_back(self, frame: int) -> None:
        """The run goes back to frame ``frame``: the choices from ``frame - 1`` on, and
        everything recorded, are forgotten."""
        for first in [f for f in self._gains if f >= frame - 1]:
            del self._gains[first]
            self._refined.pop(first, None)
        self.forget()

    def choose(self, data, frame: int) -> float:
        """The gain from frame ``frame`` on (``data``: the state after it). Every gain's
        rollout is recorded for :meth:`recorded` (on two processes, the one expected to
        win, the gain chosen last time, runs in this process)."""
        last = min(self.n_frames - 1, frame + self.lookahead_frames)
        resume = self._resumable(frame)
        self.forget(keep=resume)
        costs = self.lookahead.costs(data, frame, last, self.gains, self.default_mode,
                                     self.recordings, here=self.last_choice, resume=resume)
        self.chain = frame
        best, best_cost = 0, math.inf
        for i, cost in enumerate(costs):
            if cost < best_cost:
                best, best_cost = i, cost
        self.last_choice, self.last_cost = best, best_cost
        return self.gains[best]

    def _resumable(self, frame: int) -> int | None:
        """The last choice's gain, if its rollout can go on from ``frame`` (one process,
        the run took every frame up to ``frame`` from it, and it recorded every frame it
        simulated, finite): its recording is moved on to start after ``frame``."""
        if not self.resumes or self.chain != frame:
            return None
        recording = self.recordings[self.last_choice]
        start = recording.start_frame
        ended = min(self.n_frames - 1, start + self.lookahead_frames)
        if (start < 0 or recording.gain != self.gains[self.last_choice] or ended <= frame
                or recording.frames != ended - start or not math.isfinite(self.last_cost)):
            return None
        recording.advance(frame - start)
        return self.last_choice

    def recorded(self, t: int, gain: float):
        """Frame ``t`` as the last choice's rollout simulated it, if the run is still on
        that rollout (every frame since the choice taken from it, with its gain in the
        default mode): :meth:`controller.balance.lookahead.Recording.frame`'s tuple, for
        :func:`controller.balance.lookahead.restore_frame`, else None."""
        if self.chain != t - 1:
            self.chain = None
            return None
        out = None
        for recording in self.recordings:
            out = out or recording.frame(t, gain)
        self.chain = t if out is not None else None
        return out

    def forget(self, keep: int | None = None) -> None:
        """The run went back: nothing recorded is its future any more (but gain
        ``keep``'s recording, which goes on)."""
        for i, recording in enumerate(self.recordings):
            if i != keep:
                recording.clear()
        self.chain = None

    def close(self) -> None:
        self.lookahead.close()

