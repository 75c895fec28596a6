"""Self-contact and floor-contact queries on the humanoid, for one state or over frames.

A contact is MuJoCo's (``mj_kinematics`` then ``mj_collision``, no dynamics): a pair of
geoms that overlap, with its penetration depth (``-dist``, metres, > 0 when they
overlap). Contacts are reported per body pair: a **self-contact** is between two bodies
of the humanoid (pairs MuJoCo filters, parent-child and weld groups, and the model's
``<exclude>`` pairs never appear), a **floor contact** is between a body and the world
(the floor plane). A frame is *in self-collision* when a self-contact is deeper than
:data:`SELF_COLLISION_DEPTH_M` (1 mm, SPEC section 6).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Depth beyond which a self-contact counts as a self-collision, metres.
SELF_COLLISION_DEPTH_M = 0.001


@dataclass(frozen=True)
class ContactTable:
    """Contacts of a sequence of states: one row per geom-pair contact.

    Attributes
    ----------
    n_frames : int
    body_names : tuple of str
        The model's body names by id (0 is the world, which owns the floor).
    frame : ndarray of int, shape (K,)
        Frame of each contact.
    body1, body2 : ndarray of int, shape (K,)
        Body ids of each contact, ``body1 < body2`` (a floor contact has ``body1 == 0``).
    geom1, geom2 : ndarray of int, shape (K,)
        Geom ids, in the same order as the bodies.
    depth_m : ndarray, shape (K,)
        Penetration depth, metres (>= 0 for every row kept).
    """

    n_frames: int
    body_names: tuple[str, ...]
    frame: np.ndarray
    body1: np.ndarray
    body2: np.ndarray
    geom1: np.ndarray
    geom2: np.ndarray
    depth_m: np.ndarray

    @property
    def is_floor(self) -> np.ndarray:
        """Which rows are floor (world) contacts, shape (K,)."""
        return self.body1 == 0

    def max_self_depth_m(self) -> np.ndarray:
        """Deepest self-contact of each frame (0 if none), shape (T,) metres."""
        return self._frame_max(~self.is_floor)

    def floor_depth_m(self) -> np.ndarray:
        """Deepest penetration of any geom into the floor per frame (0 if none), (T,) m."""
        return self._frame_max(self.is_floor)

    def in_self_collision(self, depth_m: float = SELF_COLLISION_DEPTH_M) -> np.ndarray:
        """Frames with a self-contact deeper than ``depth_m``, bool shape (T,)."""
        return self.max_self_depth_m() > depth_m

    def pair_frames(self, depth_m: float = SELF_COLLISION_DEPTH_M) -> dict[tuple[str, str], int]:
        """For each self-contact body pair, the number of frames where it is deeper than
        ``depth_m``, most frequent first."""
        keep = ~self.is_floor & (self.depth_m > depth_m)
        if not keep.any():
            return {}
        rows = np.unique(np.stack([self.frame[keep], self.body1[keep], self.body2[keep]], 1),
                         axis=0)
        pairs, counts = np.unique(rows[:, 1:], axis=0, return_counts=True)
        order = np.argsort(-counts, kind="stable")
        return {(self.body_names[pairs[i, 0]], self.body_names[pairs[i, 1]]): int(counts[i])
                for i in order}

    def _frame_max(self, mask: np.ndarray) -> np.ndarray:
        out = np.zeros(self.n_frames)
        np.maximum.at(out, self.frame[mask], self.depth_m[mask])
        return out


def floor_contacts(model, data) -> tuple[np.ndarray, np.ndarray]:
    """The state's floor contacts (as computed: after ``mj_step1`` or ``mj_forward``).

    Returns
    -------
    index : ndarray of int, shape (m,)
        Which of ``data.contact`` touch the floor, in contact order.
    body : ndarray of int, shape (m,)
        The body each of them touches the floor with.
    """
    from controller.checks.contact_kernels import floor_contact_index

    if not data.ncon:
        return _NO_CONTACT
    return floor_contact_index(data.contact.geom, model.geom_bodyid)


_NO_CONTACT = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))


def collide(model, data, qpos) -> None:
    """Set ``data.qpos`` and compute positions and contacts (``mj_kinematics`` +
    ``mj_collision``; no velocities, no dynamics)."""
    import mujoco

    data.qpos[:] = qpos
    mujoco.mj_kinematics(model, data)
    mujoco.mj_collision(model, data)


def state_contacts(model, data) -> list[tuple[str, str, float]]:
    """The contacts of the current state (after :func:`collide` or ``mj_forward``).

    Returns
    -------
    list of (body1, body2, depth_m)
        Body names (``"world"`` for the floor, always first), deepest first.
    """
    import mujoco

    n = data.ncon
    if n == 0:
        return []
    geoms = np.asarray(data.contact.geom[:n])
    bodies = np.sort(model.geom_bodyid[geoms], axis=1)
    depth = -np.asarray(data.contact.dist[:n])
    out = [(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(a)),
            mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, int(b)), float(d))
           for (a, b), d in zip(bodies, depth, strict=True)]
    return sorted(out, key=lambda row: -row[2])


def contacts_over_frames(model, qpos, min_depth_m: float = 0.0) -> ContactTable:
    """Contacts of every state of a sequence.

    Parameters
    ----------
    model : mujoco.MjModel
    qpos : array_like, shape (T, model.nq)
        E.g. :func:`controller.to_qpos` of a motion.
    min_depth_m : float
        Keep only contacts at least this deep (0 keeps every overlap).

    Returns
    -------
    ContactTable
    """
    import mujoco

    qpos = np.atleast_2d(np.asarray(qpos, dtype=float))
    data = mujoco.MjData(model)
    frames, geom_pairs, depths = [], [], []
    for t in range(qpos.shape[0]):
        collide(model, data, qpos[t])
        n = data.ncon
        if n:
            depth = -np.asarray(data.contact.dist[:n])
            keep = depth >= min_depth_m
            if keep.any():
                frames.append(np.full(int(keep.sum()), t))
                geom_pairs.append(np.asarray(data.contact.geom[:n])[keep])
                depths.append(depth[keep])
    if frames:
        frame = np.concatenate(frames)
        geom = np.concatenate(geom_pairs)
        depth = np.concatenate(depths)
    else:
        frame, geom, depth = np.zeros(0, int), np.zeros((0, 2), int), np.zeros(0)
    bodies = model.geom_bodyid[geom]
    swap = bodies[:, 0] > bodies[:, 1]
    bodies[swap] = bodies[swap][:, ::-1]
    geom[swap] = geom[swap][:, ::-1]
    names = tuple(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b)
                  for b in range(model.nbody))
    return ContactTable(n_frames=qpos.shape[0], body_names=names, frame=frame,
                        body1=bodies[:, 0], body2=bodies[:, 1], geom1=geom[:, 0],
                        geom2=geom[:, 1], depth_m=depth)


@dataclass(frozen=True)
class ContactSurvey:
    """Self-collision over real clips, each played on its own subject's model.

    Attributes
    ----------
    depth_m : float
        The depth beyond which a contact counts.
    clip_frames : dict of str to (int, int)
        Per clip: (frames, frames in self-collision).
    pair_frames : dict of (str, str) to int
        Per body pair: frames in which that pair is deeper than ``depth_m``, summed over
        clips, most frequent first.
    floor_frames : dict of str to int
        Per clip: frames with a geom more than 1 cm below the floor.
    """

    depth_m: float
    clip_frames: dict[str, tuple[int, int]]
    pair_frames: dict[tuple[str, str], int]
    floor_frames: dict[str, int]

    @property
    def frames(self) -> int:
        return sum(f for f, _ in self.clip_frames.values())

    @property
    def frames_in_self_collision(self) -> int:
        return sum(c for _, c in self.clip_frames.values())

    @property
    def share(self) -> float:
        """Share of all frames in self-collision."""
        return self.frames_in_self_collision / max(self.frames, 1)

    def as_dict(self) -> dict:
        """JSON-ready figures (shares in percent)."""
        total = max(self.frames, 1)
        return {
            "depth_mm": 1000 * self.depth_m,
            "frames": self.frames,
            "frames_in_self_collision": self.frames_in_self_collision,
            "self_collision_pct": round(100 * self.share, 2),
            "clips": {name: {"frames": f, "self_collision_pct": round(100 * c / max(f, 1), 2),
                             "floor_over_1cm_pct": round(100 * self.floor_frames[name]
                                                         / max(f, 1), 2)}
                      for name, (f, c) in self.clip_frames.items()},
            "pairs": {f"{a}-{b}": {"frames": n, "pct_of_all_frames": round(100 * n / total, 2)}
                      for (a, b), n in self.pair_frames.items()},
        }


def survey_clips(catalog, names=None, depth_m: float = SELF_COLLISION_DEPTH_M) -> ContactSurvey:
    """Self-collision of real clips, each on the model built from its own subject's ASF.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    names : iterable of str, optional
        Clip names (default: every clip).
    depth_m : float

    Returns
    -------
    ContactSurvey
    """
    from controller.qpos import to_qpos
    from humanoid_xml import catalog_model_path, load_model
    from upm.core.progress import progress

    names = list(catalog.names() if names is None else names)
    models: dict[str, object] = {}
    clip_frames, floor_frames, pairs = {}, {}, {}
    for name in progress(names, desc="contacts", unit="clip"):
        subject = catalog.info(name).subject
        if subject not in models:
            models[subject] = load_model(catalog_model_path(catalog, subject))
        model = models[subject]
        table = contacts_over_frames(model, to_qpos(model, catalog.load(name)))
        clip_frames[name] = (table.n_frames, int(table.in_self_collision(depth_m).sum()))
        floor_frames[name] = int((table.floor_depth_m() > 0.01).sum())
        for pair, n in table.pair_frames(depth_m).items():
            pairs[pair] = pairs.get(pair, 0) + n
    ordered = dict(sorted(pairs.items(), key=lambda kv: (-kv[1], kv[0])))
    return ContactSurvey(depth_m=depth_m, clip_frames=clip_frames, pair_frames=ordered,
                         floor_frames=floor_frames)
