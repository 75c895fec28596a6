"""A motion: a skeleton plus per-frame arrays (no per-frame objects)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from upm.motion.skeleton import POSTURE_SIZE, Skeleton


@dataclass(frozen=True, eq=False)
class Motion:
    """Frames of one skeleton, as arrays.

    Attributes
    ----------
    skeleton : Skeleton
    posture_deg : ndarray, shape (T, 63)
        The 21-joint posture of every frame, degrees (see :mod:`upm.motion.skeleton`).
    root : ndarray, shape (T, 6)
        Root ``tx, ty, tz`` in metres and ``rx, ry, rz`` in degrees, ASF world frame
        (y up).
    fps : float
        Frames per second (AMC files carry none: the caller supplies it).
    extra_deg : ndarray, shape (T, E), optional
        Values of the non-articulated channels (``skeleton.extra_channels``: upperneck,
        wrists, fingers, thumbs), kept so that a file read and written again is unchanged.
        ``None`` means all zero.
    name : str
        A label (e.g. the clip name).
    """

    skeleton: Skeleton
    posture_deg: np.ndarray
    root: np.ndarray
    fps: float = 120.0
    extra_deg: np.ndarray | None = None
    name: str = ""

    def __post_init__(self):
        posture = np.asarray(self.posture_deg, dtype=float)
        root = np.asarray(self.root, dtype=float)
        if posture.ndim != 2 or posture.shape[1] != POSTURE_SIZE:
            raise ValueError(f"posture_deg must have shape (T, {POSTURE_SIZE}), "
                             f"not {posture.shape}")
        if root.shape != (posture.shape[0], 6):
            raise ValueError(f"root must have shape ({posture.shape[0]}, 6), not {root.shape}")
        if not self.fps > 0:
            raise ValueError(f"fps must be positive, not {self.fps}")
        object.__setattr__(self, "posture_deg", posture)
        object.__setattr__(self, "root", root)
        if self.extra_deg is not None:
            extra = np.asarray(self.extra_deg, dtype=float)
            n_extra = len(self.skeleton.extra_channels)
            if extra.shape != (posture.shape[0], n_extra):
                raise ValueError(f"extra_deg must have shape ({posture.shape[0]}, {n_extra}), "
                                 f"not {extra.shape}")
            object.__setattr__(self, "extra_deg", extra)

    @property
    def n_frames(self) -> int:
        return self.posture_deg.shape[0]

    def __len__(self) -> int:
        return self.n_frames

    @property
    def duration_s(self) -> float:
        """Duration in seconds: ``n_frames / fps``."""
        return self.n_frames / self.fps

    def frames(self, start: int | None = None, stop: int | None = None) -> Motion:
        """Frames ``start:stop`` (0-based, half-open, Python slice semantics)."""
        s = slice(start, stop)
        extra = None if self.extra_deg is None else self.extra_deg[s]
        return replace(self, posture_deg=self.posture_deg[s], root=self.root[s], extra_deg=extra)

    def replace(self, **changes) -> Motion:
        """A copy with some fields changed (``dataclasses.replace``)."""
        return replace(self, **changes)
