"""The unit of the balance controller's cost: a plain ``mj_step``, timed beside the run.

A ratio against raw ``mj_step`` only cancels the machine's speed if both are timed under
the same conditions, and on a shared 2-vCPU machine moments apart are not: timed after
each run (the fastest of five runs of 300 steps from the run's start state), the
unit read up to 1.7x apart between two runs of the same row, while the runs' own wall
times moved by at most 1.2x (2026-11-28, fifteen rows timed twice). :class:`RawStepClock`
therefore times a short burst of plain steps every :data:`EVERY_S` of wall time *while
the run goes on*, and the unit is their mean, as the run's wall time is a mean over the
same stretch; the bursts' own time is taken off the run's.
"""

from __future__ import annotations

import math
import time

#: A burst of this many timed steps (after one untimed, to bring the data into cache) ...
BURST_STEPS = 16
#: ... every this many wall seconds of the run (about 1 % of its wall time).
EVERY_S = 0.1


class RawStepClock:
    """Time bursts of plain ``mj_step`` of a model from one state while a run goes on.

    Call :meth:`tick` often (every frame of the run); it times a burst when
    :data:`EVERY_S` have passed since the last one. :attr:`spent_s` is the wall time the
    bursts took (to take off the run's), :meth:`step_s` the mean time of a timed step.

    Parameters
    ----------
    model : mujoco.MjModel
        The model whose step is the unit (its servos hold the state's pose).
    qpos : ndarray, shape (nq,)
    qvel : ndarray, shape (nv,)
        The state every burst starts from.
    every_s, burst_steps :
        :data:`EVERY_S`, :data:`BURST_STEPS` by default.
    clock : callable
        Returns seconds (``time.perf_counter``).
    """

    def __init__(self, model, qpos, qvel, *, every_s: float = EVERY_S,
                 burst_steps: int = BURST_STEPS, clock=time.perf_counter):
        import mujoco

        self._mujoco = mujoco
        self.model = model
        self.data = mujoco.MjData(model)
        self.qpos = qpos.copy()
        self.qvel = qvel.copy()
        self.ctrl = qpos[model.jnt_qposadr[model.actuator_trnid[:, 0]]].copy()
        self.every_s = float(every_s)
        self.burst_steps = int(burst_steps)
        self.clock = clock
        self.spent_s = 0.0
        self.timed_s = 0.0
        self.timed_steps = 0
        self._next_s = clock() + self.every_s

    @property
    def bursts(self) -> int:
        """How many bursts were timed."""
        return self.timed_steps // self.burst_steps

    def tick(self) -> None:
        """Time a burst if :data:`EVERY_S` have passed since the last one."""
        if self.clock() >= self._next_s:
            self.burst()

    def burst(self) -> None:
        """Time one burst now."""
        mujoco, model, data = self._mujoco, self.model, self.data
        begin = self.clock()
        mujoco.mj_resetData(model, data)
        data.qpos[:] = self.qpos
        data.qvel[:] = self.qvel
        data.ctrl[:] = self.ctrl
        mujoco.mj_step(model, data)
        start = self.clock()
        for _ in range(self.burst_steps):
            mujoco.mj_step(model, data)
        end = self.clock()
        self.timed_s += end - start
        self.timed_steps += self.burst_steps
        self.spent_s += end - begin
        self._next_s = end + self.every_s

    def step_s(self) -> float:
        """Mean wall seconds of one timed step (a burst is timed first if none was)."""
        if self.timed_steps == 0:
            self.burst()
        return self.timed_s / self.timed_steps if self.timed_s > 0 else math.nan
