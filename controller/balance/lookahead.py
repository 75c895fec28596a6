"""Lookahead rollouts of the balance controller, on one core or two.

The balance controller (:mod:`controller.balance.follow`) chooses its foot-placement gain by
rolling itself out ahead from a copy of the state once per gain. The controller has no
state of its own beside MuJoCo's (``mjSTATE_INTEGRATION``: time, positions, velocities,
warm start, controls, ...), so a rollout is a pure function of that state, the start frame
and the gain, and the rollouts of different gains can run in different processes and give
the same numbers as one after the other. :class:`Lookahead` runs every rollout in the
calling process or, with ``processes=2``, one of them there and the others in a forked
helper process at the same time (the helper has the controller as it was built: nothing
crosses the pipe but the state, the frames, the gains, the costs and the recordings).

A rollout is also the run's own future when its gain is chosen: it keeps a
:class:`Recording` of its first frames (each frame's state before its last physics step and
the torques applied at every step), and the run takes those frames from it instead of
simulating them again: it restores the state and takes that last step again (one physics
step instead of the frame's controlled ones, five at 120 fps), which leaves exactly the
data simulating the frame gives. A recording is a few arrays (about 0.35 MB for half a
second at 120 fps), so the helper's rollouts are recorded too and cross the pipe with their
costs: the run takes the chosen gain's frames on two processes as on one.

On one process a rollout is recorded whole (1 s), and when the run has taken the first
half of the chosen one, the next choice's rollout of the same gain *is* its second half
for its first half second (the same state, controller and gain): it goes on from the
recording's last frame instead (``resume``), its recorded cost terms summed again in the
same order, so the costs and the run are the same bit for bit, for a quarter less work.
"""

from __future__ import annotations

import math
import multiprocessing
import signal

import numpy as np

from controller.config import DEFAULT, ControllerConfig


class Recording:
    """The first frames of a rollout, to be taken by the run instead of simulated again.

    A frame is kept as the integration state before its last physics step; the run
    restores it with :func:`restore_frame`. MuJoCo's warning counters are not in that
    state, so a recording ends before the first frame in which MuJoCo warned.

    Attributes
    ----------
    start_frame : int
        The rollout started after this frame.
    gain : float
    frames : int
        Frames recorded so far (``start_frame + 1 .. start_frame + frames``).
    states : ndarray, shape (capacity, nstate)
        Each frame's integration state (``mjSTATE_INTEGRATION``) before its last step.
    ctrl : ndarray, shape (capacity, substeps, nu)
        The torques applied at each step of each frame, N m.
    tau : ndarray, shape (capacity, nu)
        The planned torques of each frame's last step, N m.
    userdata : ndarray, shape (capacity, nuserdata)
        ``mjData.userdata`` after each frame: what the controller's last step wrote
        there (the QP's warm start, :mod:`controller.balance.wbc`), which taking that step again
        without the controller does not write.
    cost_terms : ndarray, shape (capacity, 2)
        Each frame's two additions to the rollout's cost (:func:`rollout_cost`), so that
        a rollout continued from a later frame sums them again in the same order.
    """

    def __init__(self, sim, capacity: int, substeps: int):
        import mujoco

        size = mujoco.mj_stateSize(sim, mujoco.mjtState.mjSTATE_INTEGRATION)
        self.states = np.zeros((capacity, size))
        self.ctrl = np.zeros((capacity, substeps, sim.nu))
        self.tau = np.zeros((capacity, sim.nu))
        self.userdata = np.zeros((capacity, sim.nuserdata))
        self.cost_terms = np.zeros((capacity, 2))
        self.start_frame, self.gain, self.frames = -1, math.nan, 0

    @property
    def capacity(self) -> int:
        return self.states.shape[0]

    def begin(self, start_frame: int, gain: float) -> None:
        self.start_frame, self.gain, self.frames = start_frame, gain, 0

    def frame(self, t: int, gain: float):
        """``(state (nstate,), ctrl (substeps, nu), tau (nu,), userdata (nuserdata,))``
        of frame ``t`` if recorded with ``gain``, else None."""
        i = t - self.start_frame - 1
        if gain != self.gain or not 0 <= i < self.frames:
            return None
        return self.states[i], self.ctrl[i], self.tau[i], self.userdata[i]

    def clear(self) -> None:
        self.frames = 0

    def advance(self, frames: int) -> None:
        """Drop the first ``frames`` frames: the recording then starts after frame
        ``start_frame + frames`` (the run has taken those)."""
        n = self.frames - frames
        for array in (self.states, self.ctrl, self.tau, self.userdata, self.cost_terms):
            array[:n] = array[frames:self.frames]
        self.start_frame += frames
        self.frames = n

    def packed(self) -> tuple:
        """What crosses the pipe: the recorded frames only."""
        n = self.frames
        return (self.start_frame, self.gain, self.states[:n], self.ctrl[:n], self.tau[:n],
                self.userdata[:n])

    def unpack(self, packed: tuple) -> None:
        """Take a recording made elsewhere (:meth:`packed`)."""
        self.start_frame, self.gain, states, ctrl, tau, userdata = packed
        self.frames = n = states.shape[0]
        self.states[:n], self.ctrl[:n], self.tau[:n] = states, ctrl, tau
        self.userdata[:n] = userdata


def restore_frame(sim, data, state, last_ctrl, userdata) -> None:
    """Put ``data`` where a recorded frame left it: its state before the last step, then
    that step again with the torques then applied, and the user data the controller left.

    Parameters
    ----------
    state : ndarray, shape (nstate,)
        :attr:`Recording.states` row.
    last_ctrl : ndarray, shape (nu,)
        The torques of the frame's last step, N m.
    userdata : ndarray, shape (nuserdata,)
        :attr:`Recording.userdata` row.
    """
    import mujoco

    mujoco.mj_setState(sim, data, state, mujoco.mjtState.mjSTATE_INTEGRATION)
    mujoco.mj_step1(sim, data)
    data.ctrl[:] = last_ctrl
    mujoco.mj_step2(sim, data)
    data.userdata[:] = userdata


def _warnings(data) -> int:
    return int(np.sum(data.warning.number))


def rollout_cost(control, scratch, frame: int, last: int, gain: float, mode,
                 ref_pelvis_m, pelvis_body: int,
                 recording: Recording | None = None,
                 resume: bool = False, velocity_weight_s: float = DEFAULT.lookahead
                 .velocity_weight_s) -> tuple[float, int]:
    """How far one rollout strays: the sum over frames ``frame + 1 .. last`` of how far
    the pelvis is below the reference's (m, zero when above), one minus its up axis's
    vertical component, and ``velocity_weight_s`` times the root's horizontal velocity
    error (m/s); ``inf`` when the simulation fails. Returns the cost and the physics steps
    simulated.

    Parameters
    ----------
    control : controller.balance.control.BalanceControl
    scratch : mujoco.MjData
        Holds the start state; overwritten.
    frame, last : int
        Start and last reference frame.
    gain : float
        Foot-placement gain.
    mode : controller.balance.control.Mode
    ref_pelvis_m : ndarray, shape (T,)
        The reference's pelvis height per frame.
    pelvis_body : int
    recording : Recording, optional
        Keeps the rollout's first frames, up to its capacity.
    resume : bool
        ``recording`` already holds this rollout's first frames (from ``frame`` on, with
        this gain): they are not simulated again, the rollout goes on after the last of
        them (restored as the run restores a frame), and their cost terms are summed in
        order (the same cost as simulating them again, bit for bit).
    velocity_weight_s : float
        The velocity error's weight, s (``lookahead.velocity_weight_s``).
    """
    import mujoco

    sim = control.sim
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    last_step = control.substeps - 1
    recording_on = recording is not None
    cost = 0.0
    first = frame + 1
    steps = 0
    if resume:
        done = recording.frames
        for i in range(done):
            cost += recording.cost_terms[i, 0]
            if velocity_weight_s:
                cost += recording.cost_terms[i, 1]
        restore_frame(sim, scratch, recording.states[done - 1],
                      recording.ctrl[done - 1, last_step], recording.userdata[done - 1])
        first, steps = frame + done + 1, 1
        warned = _warnings(scratch)
    elif recording_on:
        recording.begin(frame, gain)
        warned = _warnings(scratch)
    for t in range(first, last + 1):
        i = t - frame - 1
        keep = recording_on and i < recording.capacity
        for j, k in enumerate(range((t - 1) * control.substeps, t * control.substeps)):
            if keep and j == last_step:
                mujoco.mj_getState(sim, scratch, recording.states[i], spec)
            applied, tau = control.step(scratch, k, mode, gain)
            if keep:
                recording.ctrl[i, j] = applied
        if keep:
            if _warnings(scratch) != warned:
                recording_on = False  # the counters differ from the run's from here on
            else:
                recording.tau[i] = tau
                recording.userdata[i] = scratch.userdata
                recording.frames = i + 1
        steps += control.substeps
        if not np.all(np.isfinite(scratch.qpos)):
            return math.inf, steps
        low = ref_pelvis_m[t] - scratch.xpos[pelvis_body, 2]
        tilt = 1.0 - scratch.xmat[pelvis_body, 8]
        upright = max(0.0, low) + tilt
        cost += upright
        pace = 0.0
        if velocity_weight_s:
            dv = scratch.qvel[:2] - control.ref_qvel[t, :2]
            pace = velocity_weight_s * math.hypot(dv[0], dv[1])
            cost += pace
        if keep and recording_on:
            recording.cost_terms[i] = upright, pace
    return cost, steps


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
    control : controller.balance.control.BalanceControl
    ref_pelvis_m : ndarray, shape (T,)
    pelvis_body : int
    processes : int
        1: every rollout here, one after the other; 2: one gain's here (the caller's
        ``here``) and the others in a helper process at the same time (same results).
        The helper is forked at the first call that needs it and ends with :meth:`close`
        (or this process).
    config : controller.config.ControllerConfig
        Its ``lookahead.velocity_weight_s`` (:func:`rollout_cost`).
    """

    def __init__(self, control, ref_pelvis_m, pelvis_body: int, processes: int = 1,
                 config: ControllerConfig = DEFAULT):
        import mujoco

        if processes not in (1, 2):
            raise ValueError(f"lookahead runs on 1 or 2 processes, not {processes!r}")
        if processes == 2 and "fork" not in multiprocessing.get_all_start_methods():
            raise ValueError("lookahead on 2 processes forks a helper, and this system "
                             "cannot fork: use 1 process")
        self.control = control
        self.ref_pelvis_m = ref_pelvis_m
        self.pelvis_body = pelvis_body
        self.processes = processes
        self.velocity_weight_s = config.lookahead.velocity_weight_s
        self.scratch = mujoco.MjData(control.sim)
        self._helper, self._pipe, self._busy = None, None, False
        #: physics steps the rollouts simulated, in this process and in the helper
        self.steps = 0

    def costs(self, data, frame: int, last: int, gains, mode, recordings=None,
              here: int = 0, resume: int | None = None) -> list[float]:
        """The rollout cost of each gain from ``data``'s state (not modified).

        ``recordings``: one :class:`Recording` per gain, or None; every rollout is
        recorded into its gain's (on two processes, gain ``here``'s runs in this process
        and the others in the helper, whose recordings come back with their costs).
        ``resume``: on one process, the gain whose recording already holds its rollout's
        first frames from ``frame`` on (:func:`rollout_cost`).
        """
        import mujoco

        sim = self.control.sim
        helped = self.processes == 2 and len(gains) > 1
        if resume is not None and (helped or recordings is None):
            raise ValueError("a rollout is resumed on one process, from its recording")
        local = [here] if helped else list(range(len(gains)))
        if helped:
            pipe = self._start()
            others = tuple(g for i, g in enumerate(gains) if i != here)
            capacity = None if recordings is None else recordings[here].capacity
            pipe.send((integration_state(sim, data), frame, last, others, mode, capacity))
            self._busy = True
        out = [math.nan] * len(gains)
        for i in local:
            if i != resume:
                mujoco.mj_copyData(self.scratch, sim, data)
            out[i] = self._cost(frame, last, gains[i], mode,
                                None if recordings is None else recordings[i],
                                resume=i == resume)
        if helped:
            reply = pipe.recv()
            self._busy = False
            if isinstance(reply, BaseException):
                raise reply
            costs, steps, packed = reply
            self.steps += steps
            for n, i in enumerate(i for i in range(len(gains)) if i != here):
                out[i] = costs[n]
                if recordings is not None:
                    recordings[i].unpack(packed[n])
        return out

    def _cost(self, frame, last, gain, mode, recording=None, resume: bool = False) -> float:
        cost, steps = rollout_cost(self.control, self.scratch, frame, last, gain, mode,
                                   self.ref_pelvis_m, self.pelvis_body, recording, resume,
                                   self.velocity_weight_s)
        self.steps += steps
        return cost

    def _cost_from(self, state, frame, last, gain, mode, recording=None) -> float:
        import mujoco

        mujoco.mj_setState(self.control.sim, self.scratch, state,
                           mujoco.mjtState.mjSTATE_INTEGRATION)
        return self._cost(frame, last, gain, mode, recording)

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
        recordings_here = None
        while True:
            try:
                job = pipe.recv()
            except EOFError:
                return
            if job is None:
                return
            state, frame, last, gains, mode, capacity = job
            try:
                before = self.steps
                if capacity is None:
                    recordings = [None] * len(gains)
                else:
                    if (recordings_here is None or len(recordings_here) < len(gains)
                            or recordings_here[0].capacity != capacity):
                        recordings_here = [Recording(self.control.sim, capacity,
                                                     self.control.substeps)
                                           for _ in range(len(gains))]
                    recordings = recordings_here[:len(gains)]
                costs = [self._cost_from(state, frame, last, g, mode, r)
                         for g, r in zip(gains, recordings, strict=True)]
                packed = [None if r is None else r.packed() for r in recordings]
                pipe.send((costs, self.steps - before, packed))
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
        self._helper, self._pipe, self._busy = None, None, False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
