"""The fixed rotation from the ASF world frame (y up) to the MuJoCo world frame (z up).

``(x, y, z)_asf -> (x, -z, y)_mj``: a rotation of +90 degrees about x. The subject's
left (ASF +x) stays +x, ASF up (+y) becomes MuJoCo up (+z) and ASF forward (+z) becomes
MuJoCo -y. Every vector of the model (body offsets, hinge axes, root position) is this
rotation applied to the ASF vector; a rotation matrix ``R_asf`` becomes
``ASF_TO_MJ @ R_asf @ ASF_TO_MJ.T``.
"""

from __future__ import annotations

import numpy as np

#: ``v_mj = ASF_TO_MJ @ v_asf`` (+90 degrees about x), shape (3, 3).
ASF_TO_MJ = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
ASF_TO_MJ.setflags(write=False)


def vectors_to_mj(v_asf) -> np.ndarray:
    """ASF-frame vectors in the MuJoCo frame.

    Parameters
    ----------
    v_asf : array_like, shape (..., 3)

    Returns
    -------
    ndarray, shape (..., 3)
    """
    return np.asarray(v_asf, dtype=float) @ ASF_TO_MJ.T


def vectors_to_asf(v_mj) -> np.ndarray:
    """The inverse of :func:`vectors_to_mj`, shape (..., 3) -> (..., 3)."""
    return np.asarray(v_mj, dtype=float) @ ASF_TO_MJ


def rotations_to_mj(r_asf) -> np.ndarray:
    """ASF-frame rotation matrices in the MuJoCo frame, shape (..., 3, 3)."""
    return ASF_TO_MJ @ np.asarray(r_asf, dtype=float) @ ASF_TO_MJ.T


def rotations_to_asf(r_mj) -> np.ndarray:
    """The inverse of :func:`rotations_to_mj`, shape (..., 3, 3)."""
    return ASF_TO_MJ.T @ np.asarray(r_mj, dtype=float) @ ASF_TO_MJ
