"""The key source of ``feasible``: a posture map's neurons inside the allowed range, and
the humanoid's kinematic checker (registered from the controller side)."""

from __future__ import annotations

import functools
from collections.abc import Callable

import numpy as np

from upm.core.errors import UsageError
from upm.maps.angular_search import diff_of_wrapped
from upm.motion.limits import limit_excess_deg
from upm.motion.skeleton import CLASS_NAMES, CLASS_SLICES
from upm.ops.angles import wrap_deg

#: Nearest in-range neurons per class considered for the key.
CLASS_CANDIDATES = 3
#: Whole-body key candidates checked for self-collision (nearest first).
KEY_TRIES = 12

class FeasibleKeys:
    """The key source of ``feasible``: a posture map and (optionally) the humanoid's
    kinematic checks.

    Parameters
    ----------
    posture_map : upm.maps.class_maps.ClassMaps
        A trained map (the UPM; a SOM works too): its neurons are the key candidates.
    checker_for : callable, optional
        ``checker_for(skeleton)`` -> an object with ``self_collision_pairs(postures_deg)``
        (``(N, 63)`` -> list of N frozensets of body-pair names). Called once per
        skeleton (cached).
    """

    kind = "feasible"

    def __init__(self, posture_map, checker_for: Callable | None = None):
        if not all(c in getattr(posture_map, "neurons", {}) for c in CLASS_NAMES):
            raise UsageError("feasible needs a trained posture map (its neurons are the key "
                             "candidates)")
        self.posture_map = posture_map
        self.checker_for = checker_for
        self._checkers: dict[int, tuple[object, object]] = {}
        self._excess: dict[bytes, dict[str, np.ndarray]] = {}
        self._outside: dict[tuple, np.ndarray] = {}

    def key_posture(self, a_deg, b_deg, alpha=0.5) -> np.ndarray:
        """The map's own key posture (the key-posture protocol); the method itself picks
        among :meth:`candidates`."""
        return self.posture_map.key_posture(a_deg, b_deg, alpha)

    def checker(self, skeleton):
        """The kinematic checker of a skeleton, or None without a factory."""
        if self.checker_for is None:
            return None
        entry = self._checkers.get(id(skeleton))
        if entry is None or entry[0] is not skeleton:
            entry = (skeleton, self.checker_for(skeleton))
            self._checkers[id(skeleton)] = entry
        return entry[1]

    def neuron_excess(self, limits_deg: np.ndarray) -> dict[str, np.ndarray]:
        """Per class, each neuron's excess beyond per-DOF boxes, ``(K_c, D_c)`` degrees
        (cached per set of limits)."""
        key = np.ascontiguousarray(limits_deg).tobytes()
        if key not in self._excess:
            self._excess[key] = {
                c: limit_excess_deg(self.posture_map.neurons[c], limits_deg[CLASS_SLICES[c]])
                for c in CLASS_NAMES}
        return self._excess[key]

    def _inside(self, class_name: str, limits_deg, widen_deg) -> np.ndarray:
        """Which of the class's neurons lie inside the allowed range, bool (K_c,)."""
        key = (np.ascontiguousarray(limits_deg).tobytes(), class_name)
        if key not in self._outside:
            excess = self.neuron_excess(limits_deg)[class_name]
            outside = np.flatnonzero(excess.max(axis=1) > 0)
            self._outside[key] = (excess.shape[0], outside, excess[outside])
        count, outside, excess = self._outside[key]
        widen = widen_deg[CLASS_SLICES[class_name]]
        allowed = np.all(excess <= widen + 1e-9, axis=1)
        inside = np.ones(count, dtype=bool)
        inside[outside[~allowed]] = False
        return inside

    def candidates(self, point_deg, limits_deg, widen_deg, count: int = KEY_TRIES):
        """Whole-body key candidates inside the allowed range, nearest the point first.

        Parameters
        ----------
        point_deg : ndarray, shape (63,)
            The alpha-point C of A->B.
        limits_deg : ndarray, shape (63, 2)
            The range's boxes (:func:`upm.transitions.feasible_range.range_boxes_deg`).
        widen_deg : ndarray, shape (63,)
            The allowed excess per DOF (the ends' larger excess).
        count : int

        Returns
        -------
        list of ndarray, shape (63,)
            Wrapped postures; per class one in-range neuron (or C clamped into the range
            when no neuron of the class is in range).
        """
        point = wrap_deg(point_deg)
        distances, values = [], []
        for c in CLASS_NAMES:
            s = CLASS_SLICES[c]
            neurons = self.posture_map.neurons[c]
            inside = self._inside(c, limits_deg, widen_deg)
            n_inside = np.count_nonzero(inside)
            if not n_inside:
                distances.append(np.zeros(1))
                values.append(clamp_into_range(point[s], limits_deg[s], widen_deg[s])[None])
                continue
            d = diff_of_wrapped(neurons, point[s])
            dist = np.where(inside, np.einsum("kd,kd->k", d, d), np.inf)
            k = min(CLASS_CANDIDATES, n_inside)
            best = np.argpartition(dist, k - 1)[:k]
            distances.append(dist[best])
            values.append(neurons[best])
        # Every combination of one candidate per class, by summed squared distance.
        total = functools.reduce(np.add.outer, distances).ravel()
        order = np.argsort(total, kind="stable")[:count]
        choice = np.unravel_index(order, [d.size for d in distances])
        out = np.empty((order.size, point.size))
        for c, v, k in zip(CLASS_NAMES, values, choice, strict=True):
            out[:, CLASS_SLICES[c]] = v[k]
        return list(wrap_deg(out))


def clamp_into_range(angle_deg, limits_deg, widen_deg) -> np.ndarray:
    """Angles moved to the nearest end of their allowed arc when outside it, wrapped."""
    lo = limits_deg[:, 0] - widen_deg
    hi = limits_deg[:, 1] + widen_deg
    above = np.mod(np.asarray(angle_deg, dtype=float) - lo, 360.0)
    span = hi - lo
    outside = above > span
    to_hi = above - span
    to_lo = 360.0 - above
    moved = np.where(to_hi < to_lo, hi, lo)
    return wrap_deg(np.where(outside, moved, angle_deg))



#: Builds the kinematic checker of a skeleton for :class:`FeasibleKeys`; registered by the
#: humanoid's side (the controller package registers its checker when it is imported), so
#: nothing here imports MuJoCo or names a module above this one.
_CHECKER_FACTORY: list[Callable] = []


def register_kinematic_checker(factory: Callable) -> None:
    """Make ``factory(skeleton)`` the kinematic checker of the ``feasible`` key source
    (an object with ``self_collision_pairs`` and ``frame_checks``; see the module docstring
    of :mod:`upm.transitions.feasible`). A later registration replaces an earlier one."""
    _CHECKER_FACTORY[:] = [factory]


def registered_checker() -> Callable | None:
    """The registered checker factory, or None (then ``feasible`` checks only ranges)."""
    return _CHECKER_FACTORY[0] if _CHECKER_FACTORY else None


def feasible_key_source(context) -> FeasibleKeys:
    """The key source of ``feasible``: the context's UPM with the registered checker.

    Parameters
    ----------
    context : upm.transitions.registry.KeySourceContext
    """
    return FeasibleKeys(context.posture_map("upm"), checker_for=registered_checker())
