"""Real test data for the study: the test clips at 120 fps, the bank of their postures that
the nearest-real-posture distance searches, and which clips stand on a flat floor.

- :func:`load_test_clips`: every clip of the ``test`` split, resampled to 120 fps.
- :class:`RealPostures`: every frame of those clips (wrapped, declared DOFs only), with
  its clip and frame, so that a pair's exclusion zones (:mod:`eval.pairs`) can be left
  out of the search.
- :func:`floor_residuals`: the median root residual force of each clip's own frames. The
  model's floor is flat; where the capture was not (03_01 uneven terrain, 83_26 a step
  up) or the feet hover above it (141_04), the real data alone reads about one body
  weight, and a residual says nothing about a transition there. A clip is *flat-floor*
  when its median is below :data:`FLAT_FLOOR_MAX_BW`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eval.metrics import nearest_rms_deg
from eval.pairs import STUDY_FPS, Segment
from upm.core.errors import UsageError
from upm.ops.angles import wrap_deg

#: A clip is flat-floor when the median residual force of its own frames is below this
#: (body weights). Measured: flat walks and runs 0.01-0.06, the dance 05_11 0.09; the
#: uneven-terrain walk, the step-up and the 60 fps jumps 0.85-1.0.
FLAT_FLOOR_MAX_BW = 0.5


def load_test_clips(catalog, split: str = "test") -> dict:
    """The clips of a split, resampled to the study's 120 fps.

    Returns
    -------
    dict of str to upm.Motion
        By clip name, in catalogue order.
    """
    from upm.motion.resample import resample

    names = catalog.names(split)
    if len(names) < 2:
        raise UsageError(f"the study needs at least two clips in the {split!r} split of "
                         f"{catalog.root / 'clips.csv'}, found {len(names)}")
    return {name: resample(catalog.load(name), STUDY_FPS) for name in names}


def declared_dofs(motions) -> np.ndarray:
    """The posture DOFs every clip's skeleton declares, bool (63,) (45 on CMU)."""
    return np.logical_and.reduce([m.skeleton.declared for m in motions.values()])


@dataclass(frozen=True)
class RealPostures:
    """Every frame of the test clips, for the nearest-real-posture distance.

    Attributes
    ----------
    clips : tuple of str
    postures_deg : ndarray, shape (N, D)
        The declared DOFs of every frame, wrapped to [-180, 180).
    clip_index : ndarray of int, shape (N,)
        Index in ``clips`` of each frame's clip.
    frame : ndarray of int, shape (N,)
        Its frame in that clip (120 fps).
    dofs : ndarray of bool, shape (63,)
        Which posture DOFs the columns are.
    """

    clips: tuple[str, ...]
    postures_deg: np.ndarray
    clip_index: np.ndarray
    frame: np.ndarray
    dofs: np.ndarray

    @classmethod
    def of(cls, motions) -> RealPostures:
        """The bank of ``{name: Motion}`` (e.g. :func:`load_test_clips`)."""
        dofs = declared_dofs(motions)
        names = tuple(motions)
        return cls(
            clips=names,
            postures_deg=wrap_deg(np.concatenate([m.posture_deg[:, dofs]
                                                  for m in motions.values()])),
            clip_index=np.concatenate([np.full(m.n_frames, k)
                                       for k, m in enumerate(motions.values())]),
            frame=np.concatenate([np.arange(m.n_frames) for m in motions.values()]),
            dofs=dofs,
        )

    def allowed(self, zones: list[Segment]) -> np.ndarray:
        """Frames outside every zone, bool (N,)."""
        keep = np.ones(self.frame.shape[0], dtype=bool)
        for zone in zones:
            k = self.clips.index(zone.clip)
            keep &= ~((self.clip_index == k) & (self.frame >= zone.start)
                      & (self.frame < zone.stop))
        return keep

    def nearest_rms_deg(self, postures_deg, zones: list[Segment]) -> np.ndarray:
        """Distance of each posture to the nearest real frame outside ``zones``.

        Parameters
        ----------
        postures_deg : array_like, shape (M, 63)
        zones : list of Segment

        Returns
        -------
        ndarray, shape (M,)
            Degrees, RMS over the declared DOFs (:func:`eval.metrics.nearest_rms_deg`).
        """
        points = np.asarray(postures_deg, dtype=float)[:, self.dofs]
        return nearest_rms_deg(points, self.postures_deg[self.allowed(zones)])


def floor_residuals(catalog, motions) -> dict[str, float]:
    """The median root residual force of each clip's own frames, body weights, on its
    subject's model.

    Parameters
    ----------
    catalog : upm.motion.catalog.Catalog
    motions : dict of str to upm.Motion

    Returns
    -------
    dict of str to float
    """
    from controller.checks.dynamics import root_residual
    from controller.qpos import to_qpos
    from humanoid_xml import catalog_model_path, load_model

    out = {}
    for name, motion in motions.items():
        model = load_model(catalog_model_path(catalog, name))
        force = root_residual(model, to_qpos(model, motion), motion.fps).force_bw
        out[name] = round(float(np.median(force)), 4)
    return out
