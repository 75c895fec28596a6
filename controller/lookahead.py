"""Lookahead rollouts of the balance controller, on one core or two.

The balance controller (:mod:`controller.balance`) chooses its foot-placement gain by
rolling itself out ahead from a copy of the state once per gain. The controller has no
state of its own beside MuJoCo's (``mjSTATE_INTEGRATION``: time, positions, velocities,
warm start, controls, ...), so a rollout is a pure function of that state, the start frame
and the gain, and the rollouts of different gains can run in different processes and give
the same numbers as one after the other. :class:`Lookahead` runs the first gain's rollout
in the calling process and, with ``processes=2``, the others in a forked helper process
(which has the controller as it was built: nothing is pickled but the state).
"""

from __future__ import annotations

import math
import multiprocessing
import signal

import numpy as np


def rollout_cost(control, scratch, state, frame: int, last: int, gain: float, mode,
                 ref_pelvis_m, pelvis_body: int) -> float:
    """How far one rollout strays: the sum over frames ``frame + 1 .. last`` of how far
    the pelvis is below the reference's (m, zero when above) plus one minus its up axis's
    vertical component; ``inf`` when the simulation fails.

    Parameters
    ----------
    control : controller.balance._Control
    scratch : mujoco.MjData
        Overwritten.
    state : ndarray, shape (mj_stateSize(mjSTATE_INTEGRATION),)
        The start state.
    frame, last : int
        Start and last reference frame.
    gain : float
        Foot-placement gain.
    mode : controller.balance.Mode
    ref_pelvis_m : ndarray, shape (T,)
        The reference's pelvis height per frame.
    pelvis_body : int
    """
    import mujoco

    sim = control.sim
    mujoco.mj_setState(sim, scratch, state, mujoco.mjtState.mjSTATE_INTEGRATION)
    cost = 0.0
    for t in range(frame + 1, last + 1):
        for k in range((t - 1) * control.substeps, t * control.substeps):
            control.step(scratch, k, mode, gain)
        if not np.all(np.isfinite(scratch.qpos)):
            return math.inf
        low = ref_pelvis_m[t] - scratch.xpos[pelvis_body, 2]
        tilt = 1.0 - scratch.xmat[pelvis_body, 8]
        cost += max(0.0, low) + tilt
    return cost


def integration_state(model, data) -> np.ndarray:
    """The full integration state of ``data`` (``mj_getState``, ``mjSTATE_INTEGRATION``)."""
    import mujoco

    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state, spec)
    return state


class Lookahead:
    """Costs of rollouts of one controller for several gains (see :func:`rollout_cost`).

    Parameters
    ----------
    control : controller.balance._Control
    ref_pelvis_m : ndarray, shape (T,)
    pelvis_body : int
    processes : int
        1: every rollout here, one after the other; 2: the first gain's here and the
        others in a helper process at the same time (same results). The helper is forked
        at the first call that needs it and ends with :meth:`close` (or this process).
    """

    def __init__(self, control, ref_pelvis_m, pelvis_body: int, processes: int = 1):
        import mujoco

        if processes not in (1, 2):
            raise ValueError(f"lookahead runs on 1 or 2 processes, not {processes!r}")
        self.control = control
        self.ref_pelvis_m = ref_pelvis_m
        self.pelvis_body = pelvis_body
        self.processes = processes
        self.scratch = mujoco.MjData(control.sim)
        self._helper = None
        self._pipe = None
        self._busy = False

    def costs(self, data, frame: int, last: int, gains, mode) -> list[float]:
        """The rollout cost of each gain from ``data``'s state (not modified)."""
        state = integration_state(self.control.sim, data)
        args = (frame, last)
        if self.processes == 1 or len(gains) == 1:
            return [self._cost(state, *args, g, mode) for g in gains]
        pipe = self._start()
        pipe.send((state, frame, last, tuple(gains[1:]), mode))
        self._busy = True
        first = self._cost(state, *args, gains[0], mode)
        reply = pipe.recv()
        self._busy = False
        if isinstance(reply, BaseException):
            raise reply
        return [first, *reply]

    def _cost(self, state, frame, last, gain, mode) -> float:
        return rollout_cost(self.control, self.scratch, state, frame, last, gain, mode,
                            self.ref_pelvis_m, self.pelvis_body)

    def _start(self):
        if self._helper is None:
            ours, theirs = multiprocessing.Pipe()
            helper = multiprocessing.get_context("fork").Process(
                target=self._serve, args=(theirs,), daemon=True, name="balance-lookahead")
            helper.start()
            theirs.close()
            self._helper, self._pipe = helper, ours
        return self._pipe

    def _serve(self, pipe) -> None:
        # Ctrl-C goes to the whole process group: the parent handles it and ends this one
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        while True:
            try:
                job = pipe.recv()
            except EOFError:
                return
            if job is None:
                return
            state, frame, last, gains, mode = job
            try:
                pipe.send([self._cost(state, frame, last, g, mode) for g in gains])
            except Exception as error:  # noqa: BLE001 - handed to the parent, raised there
                pipe.send(error)

    def close(self) -> None:
        """End the helper process, if one was started: at once if it is still rolling
        out (the caller was interrupted), else when it has read the request to end."""
        if self._helper is None:
            return
        if not self._busy:
            try:
                self._pipe.send(None)
                self._helper.join(timeout=5)
            except (BrokenPipeError, OSError):
                pass
        if self._helper.is_alive():
            self._helper.kill()
            self._helper.join()
        self._pipe.close()
        self._helper = self._pipe = None
        self._busy = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
