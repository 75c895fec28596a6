"""``feasible``: the UPM transition made to respect the body — a key posture the humanoid
can take, and a window fitted as a small convex problem that stays in range.

1. **Key posture.** The allowed range of each DOF is its ASF range widened by what the two
   end postures A and B already exceed (per DOF, the larger excess of the two: the study's
   "added excess" rule, :func:`controller.validity.added_excess`), so the method is
   judged only on what it adds. Per joint class, the map's neurons nearest the alpha-point
   C of A->B that lie inside the allowed range are the candidates (a class with none
   takes C clamped into the range); whole-body candidates (one neuron per class) are
   tried nearest first, and the first whose posture the humanoid takes without a
   self-collision that A and B do not already have is the key. The UPM curve is then the
   paper's: the cubic B-spline through the clips' frames and that key
   (:func:`upm.transitions.spline.keyframe_spline`).
2. **Window.** Per DOF, the window is a cubic B-spline ``p(t)`` on ``t = 0 .. L+1``
   (uniform knots :data:`KNOT_SPACING` frames apart) whose coefficients solve

   ``min |p(1..L) - u|^2 + JERK_WEIGHT * |D3 [clip 1, p(1..L), clip 2]|^2``

   with ``u`` the UPM curve at the window frames and ``D3`` the third differences of
   every stencil touching the window (the study's jerk, joins included), subject to
   **C1 joins** as equalities — ``p(0) = A``, ``p'(0)`` = clip 1's velocity at A,
   ``p(L+1) = B``, ``p'(L+1)`` = clip 2's velocity at B (second-order one-sided
   differences) — and **every window frame inside the allowed range**. The problem is
   the same matrix for every DOF and pair of the same layout: the equality-constrained
   solution of all DOFs is one cached linear map; only DOFs whose frames leave the range
   go to the QP solver (``quadprog``, Goldfarb-Idnani, the project's QP dependency).
3. **Self-collision and the floor across the window.** The fitted window is checked
   frame by frame on the humanoid (about 8 microseconds a frame), with the window's
   shared root (``WindowProblem.root_window``) so that the floor is checked too: a frame
   counts when it has any self-collision or a geom more than 1 cm below the floor — what
   the study counts, beyond the range the fit already keeps. If a frame counts, the next
   candidate window is fitted and checked (up to :data:`WINDOW_TRIES` windows), and the
   window with the fewest such frames is kept (the first on a tie). The second candidate
   is the alpha-point C itself, clamped into the allowed range (when the humanoid takes
   it without a new self-collision): a key off the map, whose curve stays near the
   straight path from A to B, which often clears the floor or the other leg where the
   map's posture does not.

**A clip entering the window moving outward past a limit.** The range constraint is on
the window's frames, never on A or on the join's velocity, so it stays feasible: A lies
inside the allowed range by construction (the range is widened by A's own excess), and
with a knot at every frame the first spline segment can turn back before frame 1 (its
value and slope at A leave the segment's other coefficients free). The turn costs
jerk, not validity. Should the QP still report inconsistent constraints (very short
windows, where both joins and the range fight over a few coefficients), the range
becomes a soft constraint with a heavy penalty on the excess (``soft_range_dofs`` in the
diagnostics counts those DOFs). A DOF whose allowed arc holds neither way from A to B
(only a range of a full turn) is left unconstrained and counted in
``unconstrained_dofs``.

**At a limit, the range wins over the frames' C1.** When an end posture sits on its
bound and its clip moves outward across it (clip 1 arriving at A on the bound; clip 2
leaving B inward, which seen from the window is arriving from beyond), a window whose
frames continue the clip's velocity would have a frame beyond the bound. The spline
keeps the join's slope (the equality) and turns back between the join and the next
frame, so the *frames* show a velocity change there (:func:`limit_turns` names those
DOFs; ``limit_turn_dofs`` counts them).

**The long way round.** Widened by the ends' excess, the allowed arc can hold A and B
but not the short way between them (e.g. a shoulder rz at -53 at A and 144 at B, range
[-90, 90] widened to [-144, 144]: the short way passes 180). A joint cannot turn through
its limit, so for such DOFs clip 2 is taken a whole turn further (:func:`long_way_turns`)
and the window goes the long way, inside the arc (``long_way_dofs``).

**Where the kinematic checks come from.** ``upm`` never imports MuJoCo (the layering
``upm`` <- ``humanoid_xml`` <- ``controller``). The key source, :class:`FeasibleKeys`,
takes a *checker factory*: ``checker_for(skeleton)`` returns an object with
``self_collision_pairs(postures_deg) -> list of frozenset`` (the body pairs in
self-collision deeper than 1 mm, per posture). The humanoid's checker is
:class:`controller.kinematic_check.HumanoidChecker`, and the registry names the builder
that wires it lazily (``"controller.kinematic_check:feasible_key_source"``), so the
registry entry is one line, importing ``upm.transitions`` stays MuJoCo-free, and the
command line, the studio, the bench and the study all get the checked source. Without a
checker (``FeasibleKeys(map)`` in a script) the method still keeps every frame in range;
it just cannot avoid self-collisions.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from collections.abc import Callable

import numpy as np
from scipy.interpolate import BSpline

from upm.angles import angle_diff_deg, wrap_deg
from upm.angular_search import diff_of_wrapped
from upm.errors import UsageError
from upm.limits import limit_excess_deg
from upm.skeleton import CLASS_NAMES, CLASS_SLICES
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult
from upm.transitions.spline import keyframe_spline

#: Weight of the squared third differences (deg/frame^3) against the squared distance to
#: the UPM curve (deg^2). Measured on 40 test pairs (eval.pairs.draw_pairs, seed 1,
#: L = 20; the study draws with seed 0): weights 10 / 100 / 1000 give a mean window jerk
#: of 526 / 489 / 436 10^3 deg/s^3 (upm 540, linear 1344) and move the window a median
#: 0.08 / 0.30 / 1.17 degrees from the UPM curve; 100 keeps the window on the map's curve
#: (nearest-real distance) while cutting jerk.
JERK_WEIGHT = 100.0
#: Frames between the window spline's knots: knots every frame gave a mean jerk of 489
#: against 537 with knots every 2 frames (same pairs, weight 100): the turn-backs near
#: a limit are smoother with more freedom.
KNOT_SPACING = 1.0
#: Nearest in-range neurons per class considered for the key.
CLASS_CANDIDATES = 3
#: Whole-body key candidates checked for self-collision (nearest first).
KEY_TRIES = 12
#: Candidate windows fitted and checked at most (when the first has invalid frames).
#: Measured on 60 pairs drawn with seed 1 (the study draws with seed 0), L = 20, valid
#: frames: one window 66.2 %; the map's two nearest collision-free keys 67.1 %; the
#: nearest key then the alpha-point 73.1 % (alpha-point window kept on 16 pairs); four
#: windows (two more map keys) 73.3 %.
WINDOW_TRIES = 2
#: Whether the alpha-point (clamped into range: no map) is the second key candidate.
STRAIGHT_KEY = True
#: Frames are kept this far inside the allowed range (degrees): the study counts excess
#: beyond 1e-6 degrees.
RANGE_MARGIN_DEG = 1e-4
#: Penalty on the range excess (per deg^2) when the range must be soft.
SOFT_RANGE_WEIGHT = 1e6


# --- the key source -----------------------------------------------------------------------


class FeasibleKeys:
    """The key source of ``feasible``: a posture map and (optionally) the humanoid's
    kinematic checks.

    Parameters
    ----------
    posture_map : upm.class_maps.ClassMaps
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
        """Per class, each neuron's excess beyond the ASF limits, ``(K_c, D_c)`` degrees
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
            ASF limits.
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


# --- the allowed range --------------------------------------------------------------------


def long_way_turns(problem: WindowProblem) -> np.ndarray:
    """Per DOF, the whole turns (-1, 0 or +1) to add to clip 2 so that A -> B stays inside
    the allowed arc: nonzero where the short way from A to B leaves it but the long way
    does not (a joint cannot turn through its limit; with the arc widened by the ends'
    excess, this happens on real pairs, e.g. a shoulder rz beyond its limit at B).

    Returns
    -------
    ndarray of float, shape (63,)
    """
    lo, hi, _ = _widened(problem)
    a, b = problem.a_deg, problem.b_deg
    shift = 360.0 * np.floor((a - lo + 1e-6) / 360.0)
    lo_t, hi_t = lo + shift, hi + shift
    tolerance = 1e-5
    turns = np.zeros_like(a)
    for k in (-1.0, 1.0):
        moved = b + 360.0 * k
        fits = ((b < lo_t - tolerance) | (b > hi_t + tolerance)) & (
            moved >= lo_t - tolerance) & (moved <= hi_t + tolerance)
        turns[fits & problem.skeleton.declared] = k
    return turns


def _widened(problem: WindowProblem):
    limits = problem.skeleton.limits_deg
    ends = limit_excess_deg(np.stack([problem.a_deg, problem.b_deg]), limits)
    widen = ends.max(axis=0)
    return limits[:, 0] - widen, limits[:, 1] + widen, widen


def allowed_range(problem: WindowProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                   np.ndarray]:
    """The allowed range of each DOF on the turn of the window's (unwrapped) angles.

    Returns
    -------
    lower_deg, upper_deg : ndarray, shape (63,)
        Bounds for the window's frames, on A's turn, ``RANGE_MARGIN_DEG`` inside.
    constrained : ndarray of bool, shape (63,)
        DOFs with a bound: declared, range below a full turn, and B (as the problem has
        it: see :func:`long_way_turns`) inside the arc on A's turn.
    widen_deg : ndarray, shape (63,)
        The larger of A's and B's excess beyond the ASF limits, per DOF.
    """
    lo, hi, widen = _widened(problem)
    a, b = problem.a_deg, problem.b_deg
    shift = 360.0 * np.floor((a - lo + 1e-6) / 360.0)
    lo_t, hi_t = lo + shift, hi + shift
    tolerance = 1e-5
    constrained = (problem.skeleton.declared & (hi - lo < 360.0 - 1e-6)
                   & (a >= lo_t - tolerance) & (a <= hi_t + tolerance)
                   & (b >= lo_t - tolerance) & (b <= hi_t + tolerance))
    lower = np.minimum(lo_t, np.minimum(a, b))
    upper = np.maximum(hi_t, np.maximum(a, b))
    # Inside even when an end sits on the widened bound (a window frame there equal to the
    # end up to rounding would count as added excess).
    margin = np.minimum(RANGE_MARGIN_DEG, 0.25 * (upper - lower))
    lower, upper = lower + margin, upper - margin
    return lower, upper, constrained, widen


def limit_turns(problem: WindowProblem, lower_deg, upper_deg, constrained,
                tolerance_deg: float = 1e-3) -> np.ndarray:
    """DOFs whose C1 join would need a window frame beyond the range: the end posture
    sits on its bound and the clip moves outward across it (at A: clip 1 arriving at the
    bound; at B: clip 2 leaving it inward, which seen from the window is arriving from
    beyond). There the range wins: the spline keeps the clip's slope at the join but
    turns back between the join and the next frame, so the frames show the turn.

    Returns
    -------
    ndarray of bool, shape (2, 63)
        At A, at B.
    """
    v_a = _end_velocity(problem.before_deg, True)
    v_b = _end_velocity(problem.after_deg, False)
    a, b = problem.a_deg, problem.b_deg
    at_a = constrained & (((a >= upper_deg - tolerance_deg) & (v_a > 0))
                          | ((a <= lower_deg + tolerance_deg) & (v_a < 0)))
    at_b = constrained & (((b >= upper_deg - tolerance_deg) & (v_b < 0))
                          | ((b <= lower_deg + tolerance_deg) & (v_b > 0)))
    return np.stack([at_a, at_b])


# --- the window fit -----------------------------------------------------------------------


@functools.lru_cache(maxsize=64)
def _layout(frames: int, k_before: int, k_after: int):
    """Matrices of the window fit for one layout (read-only, cached).

    Returns
    -------
    dict
        ``window`` (L, n): the spline's values at t = 1 .. L from its coefficients;
        ``equality`` (4, n): p(0), p'(0), p(L+1), p'(L+1); ``hessian`` (n, n);
        ``jerk_context`` (n, K1 + K2): the linear term's matrix for the clip frames;
        ``solve`` (n, L + K1 + K2 + 4): coefficients of the equality-constrained optimum
        from ``[u, clip 1 frames, clip 2 frames, equality values]``.
    """
    end = frames + 1
    segments = max(2, int(np.ceil(end / KNOT_SPACING)))
    h = end / segments
    knots = np.concatenate([[0.0] * 3, np.arange(segments + 1) * h, [end] * 3])
    knots[segments + 3] = end
    n = segments + 3
    basis = BSpline(knots, np.eye(n), 3, extrapolate=False)
    window = basis(np.arange(1, frames + 1, dtype=float))
    slope = basis.derivative()
    equality = np.stack([basis(0.0), slope(0.0), basis(float(end) - 1e-12),
                         slope(float(end) - 1e-12)])
    # The sequence [clip 1 (K1), window (L), clip 2 (K2)] and its third differences.
    length = k_before + frames + k_after
    d3 = np.diff(np.eye(length), 3, axis=0)
    touching = [r for r in range(d3.shape[0]) if r + 3 >= k_before and r < k_before + frames]
    d3 = d3[touching]
    d_window = d3[:, k_before:k_before + frames] @ window  # (S, n)
    d_context = np.concatenate([d3[:, :k_before], d3[:, k_before + frames:]], axis=1)
    hessian = window.T @ window + JERK_WEIGHT * d_window.T @ d_window + 1e-9 * np.eye(n)
    jerk_context = -JERK_WEIGHT * d_window.T @ d_context  # (n, K1 + K2)
    kkt = np.block([[hessian, equality.T], [equality, np.zeros((4, 4))]])
    inverse = np.linalg.inv(kkt)[:n]
    rhs = np.zeros((n + 4, frames + k_before + k_after + 4))
    rhs[:n, :frames] = window.T
    rhs[:n, frames:frames + k_before + k_after] = jerk_context
    rhs[n:, frames + k_before + k_after:] = np.eye(4)
    out = {"window": window, "equality": equality, "hessian": hessian,
           "jerk_context": jerk_context, "solve": inverse @ rhs}
    for value in out.values():
        value.setflags(write=False)
    return out


def _end_velocity(frames_deg: np.ndarray, at_end: bool) -> np.ndarray:
    """Velocity (deg/frame) at the last (``at_end``) or first frame of a clip piece:
    second-order one-sided difference with 3 frames, first-order with 2, 0 with 1."""
    f = frames_deg if at_end else frames_deg[::-1]
    sign = 1.0 if at_end else -1.0
    if f.shape[0] >= 3:
        return sign * (1.5 * f[-1] - 2.0 * f[-2] + 0.5 * f[-3])
    if f.shape[0] == 2:
        return sign * (f[-1] - f[-2])
    return np.zeros(f.shape[1])


def fit_window(problem: WindowProblem, reference_deg, lower_deg, upper_deg,
               constrained) -> tuple[np.ndarray, dict[str, float]]:
    """The window as the convex problem of the module docstring.

    Parameters
    ----------
    problem : WindowProblem
    reference_deg : ndarray, shape (L, 63)
        The curve to stay near (the UPM curve), continuous with the problem's context.
    lower_deg, upper_deg : ndarray, shape (63,)
    constrained : ndarray of bool, shape (63,)

    Returns
    -------
    window : ndarray, shape (L, 63)
    diagnostics : dict
        ``qp_dofs`` (DOFs whose range was active), ``soft_range_dofs``.
    """
    import quadprog

    before, after = problem.before_deg, problem.after_deg
    k1, k2 = before.shape[0], after.shape[0]
    layout = _layout(problem.frames, k1, k2)
    ends = np.stack([problem.a_deg, _end_velocity(before, True),
                     problem.b_deg, _end_velocity(after, False)])
    data = np.concatenate([reference_deg, before, after, ends])  # (L + K1 + K2 + 4, 63)
    coefficients = layout["solve"] @ data
    window = layout["window"] @ coefficients
    out_of_range = constrained & ((window < lower_deg).any(axis=0)
                                  | (window > upper_deg).any(axis=0))
    soft = 0
    basis = layout["window"]
    for dof in np.flatnonzero(out_of_range):
        linear = basis.T @ reference_deg[:, dof] + layout["jerk_context"] @ np.concatenate(
            [before[:, dof], after[:, dof]])
        lo, hi = lower_deg[dof], upper_deg[dof]
        constraints = np.concatenate([layout["equality"], basis, -basis]).T
        bounds = np.concatenate([ends[:, dof], np.full(basis.shape[0], lo),
                                 np.full(basis.shape[0], -hi)])
        try:
            # quadprog writes into its arguments: the cached Hessian goes in as a copy.
            solution = quadprog.solve_qp(np.array(layout["hessian"]), linear, constraints,
                                         bounds, 4)[0]
        except ValueError:
            solution = _soft_range(layout, linear, ends[:, dof], lo, hi)
            soft += 1
        window[:, dof] = basis @ solution
    return window, {"qp_dofs": float(out_of_range.sum()), "soft_range_dofs": float(soft)}


def _soft_range(layout, linear, ends, lo, hi) -> np.ndarray:
    """The fit with the range as a heavy penalty on the excess (slack variables)."""
    import quadprog

    basis, hessian = layout["window"], layout["hessian"]
    n, m = hessian.shape[0], basis.shape[0]
    g = np.zeros((n + m, n + m))
    g[:n, :n] = hessian
    g[n:, n:] = SOFT_RANGE_WEIGHT * np.eye(m) + 1e-9 * np.eye(m)
    a = np.concatenate([linear, np.zeros(m)])
    eq = np.concatenate([layout["equality"], np.zeros((4, m))], axis=1)
    upper = np.concatenate([-basis, np.eye(m)], axis=1)  # hi + s - p >= 0
    lower = np.concatenate([basis, np.eye(m)], axis=1)  # p + s - lo >= 0
    slack = np.concatenate([np.zeros((m, n)), np.eye(m)], axis=1)
    c = np.concatenate([eq, upper, lower, slack]).T
    b = np.concatenate([ends, np.full(m, -hi), np.full(m, lo), np.zeros(m)])
    return quadprog.solve_qp(g, a, c, b, 4)[0][:n]


# --- the method ---------------------------------------------------------------------------


def _continuous_key(problem: WindowProblem, key_wrapped: np.ndarray) -> np.ndarray:
    point = problem.a_deg + problem.alpha * (problem.b_deg - problem.a_deg)
    return point + angle_diff_deg(key_wrapped, point)


def _upm_curve(problem: WindowProblem, key: np.ndarray) -> np.ndarray:
    times = np.concatenate([problem.before_times, [problem.key_time], problem.after_times])
    values = np.concatenate([problem.before_deg, key[None], problem.after_deg])
    return keyframe_spline(times, values, problem.window_times)


def _invalid_frames(checker, window_deg, root) -> int:
    """Window frames the study counts invalid for a reason the range cannot prevent: a
    self-collision (any pair, as the study counts it) or, with the root, a foot or body
    below the floor."""
    colliding, floor = checker.frame_checks(window_deg, root, names=False)
    return int(np.count_nonzero(colliding | floor))


def _keys_in_order(candidates, straight, checker, at_ends):
    """The key candidates in the order their windows are tried, each with whether the
    humanoid takes it without a self-collision that A and B do not have: the map's
    nearest collision-free key, the alpha-point (``straight``, if collision-free), the
    map's other collision-free keys, then its colliding ones. Checked lazily: only the
    keys whose window is fitted cost a check."""
    def free(key) -> bool:
        return not checker.self_collision_pairs(key)[0] - at_ends

    rest = iter(candidates)
    colliding = []
    for key in rest:
        if free(key):
            yield key, True
            break
        colliding.append(key)
    if straight is not None and free(straight):
        yield straight, True
    for key in rest:
        if free(key):
            yield key, True
        else:
            colliding.append(key)
    for key in colliding:
        yield key, False


def solve(problem: WindowProblem) -> WindowResult:
    source = problem.key_source
    if not isinstance(source, FeasibleKeys):
        raise UsageError(f"method 'feasible' needs a FeasibleKeys source, not "
                         f"{type(source).__name__}")
    skeleton = problem.skeleton
    turns = long_way_turns(problem)
    if turns.any():
        problem = dataclasses.replace(problem, after_deg=problem.after_deg + 360.0 * turns)
    lower, upper, constrained, widen = allowed_range(problem)
    point = wrap_deg(problem.a_deg + problem.alpha * (problem.b_deg - problem.a_deg))
    candidates = source.candidates(point, skeleton.limits_deg, widen)
    checker = source.checker(skeleton)

    if checker is None:
        keys = iter([(candidates[0], None)])
    else:
        end_pairs = checker.self_collision_pairs(np.stack([problem.a_deg, problem.b_deg]))
        straight = (clamp_into_range(point, skeleton.limits_deg, widen) if STRAIGHT_KEY
                    else None)
        keys = _keys_in_order(candidates, straight, checker, frozenset().union(*end_pairs))

    best = None
    for attempt, (key_wrapped, collision_free) in enumerate(itertools.islice(keys, WINDOW_TRIES)):
        key = _continuous_key(problem, key_wrapped)
        window, fit = fit_window(problem, _upm_curve(problem, key), lower, upper, constrained)
        invalid = 0
        if checker is not None:
            invalid = _invalid_frames(checker, window, problem.root_window)
        if best is None or invalid < best[0]:
            best = (invalid, window, key_wrapped, fit, attempt, collision_free)
        if invalid == 0 or checker is None:
            break
    invalid, window, key_wrapped, fit, attempt, collision_free = best
    diagnostics = {
        "key_candidate": float(attempt),
        "window_invalid_frames": float(invalid),
        "unconstrained_dofs": float((skeleton.declared & ~constrained).sum()),
        "long_way_dofs": float(np.count_nonzero(turns)),
        "limit_turn_dofs": float(limit_turns(problem, lower, upper, constrained).any(
            axis=0).sum()),
        "kinematic_checks": float(checker is not None),
        "floor_checked": float(checker is not None and problem.root_window is not None),
        **fit,
    }
    if checker is not None:
        diagnostics["key_collision_free"] = float(collision_free)
    return WindowResult(window, key_posture_deg=wrap_deg(key_wrapped), diagnostics=diagnostics)


METHOD = TransitionMethod(
    name="feasible", solve=solve, continuity="C1", key_kind="feasible",
    summary="UPM key among the neurons the humanoid can take, window fitted as a small QP: "
            "near the UPM curve, minimum jerk, C1 joins, every frame in range (needs a map)",
    key_source="controller.kinematic_check:feasible_key_source",
    key_help="a trained Uniform Posture Map (upm train --kind upm) with the humanoid's "
             "checks: controller.kinematic_check.feasible_key_source, or "
             "upm.transitions.feasible.FeasibleKeys(map)",
)
