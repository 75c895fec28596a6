"""The studio's state and its recomputation: clip 1 -> window -> clip 2 as capsule poses.

No web code here, so tests (and any other front end) drive it directly.
"""

from __future__ import annotations

import copy
import time
import warnings
from dataclasses import dataclass

import numpy as np


def method_names() -> list[str]:
    """Every registered transition method (the one adapter to the method registry)."""
    from upm.transitions import METHODS

    return list(METHODS)


def key_source(method: str, map_path, catalog, follow: str | None = None,
               performer_config=None):
    """The key-posture source a method needs (None for those that need none); for
    ``performed``, that of the followed method ``follow`` with the performer's
    configuration (a :class:`controller.config.ControllerConfig`; None: the defaults)."""
    from upm.transitions.load import key_source_for

    if method != "performed":
        return key_source_for(method, map_path, catalog)
    with warnings.catch_warnings():  # a map the followed method does not use is fine here
        warnings.simplefilter("ignore")
        return key_source_for(method, map_path, catalog, follow=follow,
                              performer_config=performer_config)


@dataclass
class Scene:
    """One recomputed transition, ready to draw.

    Attributes
    ----------
    result : upm.transitions.Transition
    model : mujoco.MjModel, the humanoid the poses are of (clip 1's subject).
    geom_pos_m : (T, G, 3) array, world positions of the G capsules per frame.
    geom_wxyz : (T, G, 4) array, their orientations as unit quaternions.
    valid : (T,) bool array, frame passes the kinematic checks (limits, self-collision,
        floor).
    offending : (T, G) bool array, the capsules whose body breaks a check on that frame
        by the calibrated verdict (a rule of its joint's human range broken, a
        self-contact deeper than its body pair's soft-tissue allowance, deeper below the
        floor than its class allows): what the studio tints.
    seconds : float, wall time of the whole recomputation (transition + kinematics + checks).
    """

    result: object
    model: object
    geom_pos_m: np.ndarray
    geom_wxyz: np.ndarray
    valid: np.ndarray
    offending: np.ndarray
    seconds: float


class Session:
    """Clip 1 up to ``a_frame``, a ``method`` window of ``frames``, clip 2 from ``b_frame``.

    ``key_sources`` (method name -> key-posture source) are used as given; the others are
    built on first use from ``map_path`` and the catalogue. ``performed`` follows
    :attr:`follow` (``feasible`` with a map, else ``linear``), searched with
    ``performer_config`` (a :class:`controller.config.ControllerConfig`; None: the
    defaults); :attr:`performed_ghost` asks for the performed window beside the asked one
    (:mod:`studio.ghost`).
    """

    def __init__(self, catalog, clip1: str, clip2: str, map_path=None, context: int = 60,
                 key_sources: dict | None = None, performer_config=None):
        self.catalog = catalog
        self.map_path = map_path
        self.context = context
        self.clip1, self.clip2 = clip1, clip2
        self._clips: dict[str, object] = {}
        self.a_frame = self.clip(clip1).n_frames - 1
        self.b_frame = 0
        # a map given: start on the method it serves (the README's `upm studio --map M`)
        self.method = _map_method(map_path) if map_path else "linear"
        self.compare_method: str | None = None
        self.alpha = 0.5
        self.frames = 20
        self.subject: str | None = None
        self.model = self.humanoid()
        self._sources: dict[str, object] = dict(key_sources or {})
        self.follow = "feasible" if map_path else "linear"
        self.performer_config = performer_config
        self.performed_ghost = False
        self._performed: dict[tuple, Scene] = {}

    def clip(self, name: str):
        """A clip of the catalogue (``upm.Motion``), read once: a slider move must not read
        an AMC file again (tens of milliseconds)."""
        if name not in self._clips:
            self._clips[name] = self.catalog.load(name)
        return self._clips[name]

    def humanoid(self):
        """The humanoid (``mujoco.MjModel``) of clip 1's subject, built again when clip 1
        changes to a clip of another subject (the transition is on clip 1's skeleton)."""
        from humanoid_xml import catalog_model_path, load_model

        subject = self.catalog.info(self.clip1).subject
        if subject != self.subject:
            self.model = load_model(catalog_model_path(self.catalog, self.clip1))
            self.subject = subject
        return self.model

    def _source(self, method: str):
        name = (method, self.asked_method()) if method == "performed" else method
        if name not in self._sources:
            self._sources[name] = key_source(method, self.map_path, self.catalog,
                                             self.asked_method(), self.performer_config)
        return self._sources[name]

    def asked_method(self) -> str:
        """The method whose window ``performed`` follows: :attr:`follow` when the method
        is ``performed``, else the method itself (its window is the asked one)."""
        return self.follow if self.method == "performed" else self.method

    def performed_key(self) -> tuple:
        """The settings a performed window depends on (its cache key)."""
        return (self.clip1, self.a_frame, self.clip2, self.b_frame, self.frames,
                round(float(self.alpha), 6), self.asked_method(), self.context)

    def performed_scene(self) -> Scene | None:
        """The performed scene of the current settings if made already, else None."""
        return self._performed.get(self.performed_key())

    def perform(self) -> Scene:
        """The performed scene of the current settings: the humanoid performs the asked
        window (slow: the offline effort's search), once per settings."""
        key = self.performed_key()
        if key not in self._performed:
            frozen = copy.copy(self)  # the settings of the call, whatever changes meanwhile
            self._performed[key] = frozen.recompute("performed")
        return self._performed[key]

    def _pieces(self):
        from upm.core.errors import UsageError

        m1, m2 = self.clip(self.clip1), self.clip(self.clip2)
        if not 0 <= self.a_frame < m1.n_frames or not 0 <= self.b_frame < m2.n_frames:
            raise UsageError(f"frame out of range: {self.clip1}@{self.a_frame} "
                             f"({m1.n_frames} frames), {self.clip2}@{self.b_frame} "
                             f"({m2.n_frames} frames)")
        before = m1.frames(max(0, self.a_frame + 1 - self.context), self.a_frame + 1)
        after = m2.frames(self.b_frame, min(m2.n_frames, self.b_frame + self.context))
        return before, after

    def transition(self, method: str | None = None):
        """The current transition (``method`` defaults to the session's)."""
        from upm.transitions import transition

        method = method or self.method
        if method == "performed":
            from studio.ghost import ensure_performer

            ensure_performer()
        before, after = self._pieces()
        return transition(method, before, after, self.frames, self.alpha, self._source(method))

    def recompute(self, method: str | None = None) -> Scene:
        """Transition, capsule poses and per-frame validity of the current settings."""
        from controller.checks.validity import check_motion
        from controller.qpos import to_qpos

        start = time.perf_counter()
        model = self.humanoid()
        result = self.transition(method)
        pos, wxyz = capsule_poses(model, to_qpos(model, result.motion))
        validity = check_motion(model, result.motion, [result.window])
        bodies = offending_bodies(model, validity)
        offending = bodies[:, model.geom_bodyid[capsule_geoms(model)]]
        return Scene(result, model, pos, wxyz, np.asarray(validity.valid, bool), offending,
                     time.perf_counter() - start)


def offending_bodies(model, validity) -> np.ndarray:
    """Which bodies break a kinematic check on each frame.

    Parameters
    ----------
    model : mujoco.MjModel
    validity : controller.checks.validity.Validity

    Returns
    -------
    (T, nbody) bool array
        A body is flagged when a rule of its joint is broken (the range model's: the
        human range by default), when it is in a self-contact deeper than its pair's
        soft-tissue allowance, or when it is deeper below the floor than its class
        allows (:mod:`controller.checks.tissue`): the frame-level flags of
        :attr:`Validity.valid`, per body.
    """
    import mujoco

    n = validity.n_frames
    out = np.zeros((n, model.nbody), dtype=bool)
    dof_body = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY,
                                           name.split(".")[0]) for name in validity.rule_names])
    frames, dofs = np.nonzero(validity.limit_excess_deg > 0)
    known = dof_body[dofs] >= 0
    out[frames[known], dof_body[dofs[known]]] = True
    c = validity.contacts
    beyond = validity.contact_excess_m > 0
    self_deep = ~c.is_floor & beyond
    out[c.frame[self_deep], c.body1[self_deep]] = True
    out[c.frame[self_deep], c.body2[self_deep]] = True
    floor_deep = c.is_floor & beyond
    out[c.frame[floor_deep], c.body2[floor_deep]] = True
    return out


def capsule_geoms(model) -> np.ndarray:
    """Indices of the model's capsule geoms (the body; the floor is left out)."""
    import mujoco

    return np.flatnonzero(model.geom_type == mujoco.mjtGeom.mjGEOM_CAPSULE)


def capsule_poses(model, qpos) -> tuple[np.ndarray, np.ndarray]:
    """World pose of every capsule at every frame.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : (T, nq) array

    Returns
    -------
    pos_m : (T, G, 3) array
    wxyz : (T, G, 4) array
    """
    import mujoco

    geoms = capsule_geoms(model)
    data = mujoco.MjData(model)
    pos = np.empty((len(qpos), len(geoms), 3))
    wxyz = np.empty((len(qpos), len(geoms), 4))
    for t, q in enumerate(qpos):
        data.qpos[:] = q
        mujoco.mj_kinematics(model, data)
        pos[t] = data.geom_xpos[geoms]
        for g, gid in enumerate(geoms):
            mujoco.mju_mat2Quat(wxyz[t, g], data.geom_xmat[gid])
    return pos, wxyz


def export_amc(result, path) -> str:
    """Write the transition (clip 1 context, window, clip 2 context) as AMC or BVH (by the
    extension), atomically."""
    from upm.bvh.formats import write_motion

    write_motion(path, result.motion)
    return str(path)


def dof_curve_png(result, linear, path, dof: str | None = None) -> str:
    """The paper's Fig. 13 for the window: one DOF, the method against linear.

    Returns the DOF drawn (``dof``, or the one where the two differ most).
    """
    from upm.transitions.dof_plot import plot_window_dof

    return plot_window_dof(path, {result.method: result, "linear": linear}, dof=dof)


def physics_check(model, result, tracking_modes=("driven",)) -> list[dict]:
    """The ``upm simulate`` analysis of the transition (its window marked): summary rows.

    Returns
    -------
    list of dict
        :func:`controller.report.summary_rows` (``all``, ``window 0``).
    """
    from controller.analysis import analyse
    from controller.report import summary_rows

    report, _ = analyse(model, result.motion, kind="simulate", windows=[result.window],
                        window_meta=[{"method": result.method}],
                        tracking_modes=tuple(tracking_modes))
    return summary_rows(report)


def _map_method(map_path) -> str:
    """The method a saved map serves: "som" for a SOM map, else "upm" (read without
    unpickling; an unreadable file is left to the first transition to report)."""
    from upm.core.errors import UpmError
    from upm.maps.npz_file import read_map_arrays, text_field

    try:
        kind = text_field(read_map_arrays(map_path), "kind", map_path)
    except (UpmError, OSError, ValueError):
        return "upm"
    return "som" if kind == "som" else "upm"
