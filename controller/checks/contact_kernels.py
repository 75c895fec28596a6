"""Compiled kernel of the floor-contact query (:mod:`controller.checks.contacts`; numba,
cached on disk)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def floor_contact_index(geom, geom_bodyid):
    """The contacts between the floor (body 0) and a body of the humanoid.

    Parameters
    ----------
    geom : ndarray of int, shape (n, 2)
        The geoms of each of the state's contacts.
    geom_bodyid : ndarray of int, shape (ngeom,)

    Returns
    -------
    index : ndarray of int, shape (m,)
        Which contacts touch the floor, in contact order.
    body : ndarray of int, shape (m,)
        The body each of them touches the floor with.
    """
    n = geom.shape[0]
    index = np.empty(n, dtype=np.int64)
    body = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        b0 = geom_bodyid[geom[i, 0]]
        b1 = geom_bodyid[geom[i, 1]]
        if (b0 == 0) != (b1 == 0):
            index[m] = i
            body[m] = b0 + b1
            m += 1
    return index[:m], body[:m]
