"""Small, seeded changes of a motion's joint angles: how much one simulated run says.

A free-root run is one trajectory of a chaotic system; whether it falls can turn on
differences far under mocap's precision. :func:`offset_joint_angles` moves every joint
channel of a motion by its own constant, drawn from a normal distribution, so the same
command run with a few seeds shows how often the outcome holds (``upm simulate
--offset-deg``).
"""

from __future__ import annotations

import numpy as np

from upm.motion.dropouts import dropout_mask


def offset_joint_angles(motion, sigma_deg: float, seed: int):
    """The motion with each joint channel moved by one constant over all its frames.

    Parameters
    ----------
    motion : upm.motion.Motion
        ``posture_deg`` (T, 63).
    sigma_deg : float
        Standard deviation of the per-channel constants, degrees (0: the motion itself).
    seed : int
        Seed of the draws (``numpy.random.default_rng``): the same seed, the same offsets.

    Returns
    -------
    upm.motion.Motion
        A copy. A channel that reads zero throughout (one the skeleton does not declare)
        and a bone's marker dropouts (:func:`upm.motion.dropouts.dropout_mask`, which the
        controller fills) stay as they are; every other value moves, a zero among them.
        The root is unchanged.
    """
    if not (np.isfinite(sigma_deg) and sigma_deg >= 0):
        raise ValueError(f"the offsets' standard deviation must be finite and >= 0, got "
                         f"{sigma_deg!r} deg")
    posture = np.asarray(motion.posture_deg, dtype=float)
    offset_deg = sigma_deg * np.random.default_rng(seed).standard_normal(posture.shape[1])
    kept = dropout_mask(posture) | np.all(posture == 0.0, axis=0)
    return motion.replace(posture_deg=np.where(kept, posture, posture + offset_deg))
