"""Batches of open-loop rollouts of the humanoid from given states with given servo
targets (``mujoco.rollout``), and the ``qpos`` in the states they return."""

from __future__ import annotations

import numpy as np


class Roller:
    """Rolls out batches on one model with ``threads`` threads (a context manager: the
    thread pool is closed on exit). The results do not depend on ``threads``."""

    def __init__(self, model, threads: int = 1):
        import mujoco
        from mujoco import rollout

        self.model = model
        self.spec = int(mujoco.mjtState.mjSTATE_FULLPHYSICS)
        self.size = mujoco.mj_stateSize(model, self.spec)
        self.threads = max(1, int(threads))
        self.datas = [mujoco.MjData(model) for _ in range(self.threads)]
        self.pool = rollout.Rollout(nthread=self.threads) if self.threads > 1 else None
        self._rollout = rollout.rollout

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self) -> None:
        if self.pool is not None:
            self.pool.close()
            self.pool = None

    def state_of(self, qpos, qvel) -> np.ndarray:
        """The full physics state (nstate,) of a ``qpos``, ``qvel`` at time 0."""
        import mujoco

        data = self.datas[0]
        mujoco.mj_resetData(self.model, data)
        data.qpos[:] = qpos
        data.qvel[:] = qvel
        out = np.empty(self.size)
        mujoco.mj_getState(self.model, data, out, self.spec)
        return out

    def run(self, initial, ctrl) -> np.ndarray:
        """States after every step, (N, S, nstate), from states ``initial`` (N, nstate)
        with servo targets ``ctrl`` (N, S, nu)."""
        initial = np.ascontiguousarray(initial, dtype=np.float64)
        ctrl = np.ascontiguousarray(ctrl, dtype=np.float64)
        if self.pool is not None:
            state, _ = self.pool.rollout(self.model, self.datas, initial, ctrl)
        else:
            state, _ = self._rollout(self.model, self.datas[0], initial, ctrl)
        return state

    def qpos(self, states) -> np.ndarray:
        """The ``qpos`` in states (..., nstate): after the time, ``nq`` values."""
        return states[..., 1:1 + self.model.nq]

    def qvel(self, states) -> np.ndarray:
        """The ``qvel`` in states (..., nstate): after the time and ``qpos``."""
        nq = self.model.nq
        return states[..., 1 + nq:1 + nq + self.model.nv]
