"""``feasible``: the UPM transition made to respect the body — a key posture the humanoid
can take, and a window fitted as a small convex problem that stays in range.

1. **Key posture.** The allowed range of each DOF is its box of the human range of motion
   (:func:`upm.motion.human_boxes.human_dof_boxes`: the humanoid's hinge ranges; not the
   ASF's nominal limits) widened by what the two end postures A and B already exceed (per
   DOF, the larger excess of the two: the study's "added excess" rule,
   :func:`controller.checks.validity.added_excess`), so the method is judged only on what
   it adds. Per joint class, the map's neurons nearest the alpha-point C of A->B that lie
   inside the allowed range are the candidates (a class with none takes C clamped into
   the range); whole-body candidates (one neuron per class) are tried nearest first, and
   the first that the human range's coupled rules allow (:mod:`upm.motion.human_rom`:
   no rule broken beyond what A and B break) and that the humanoid takes without a
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
3. **Coupled rules, self-collision and the floor across the window.** The boxes cannot
   state a coupled rule (a shoulder's twist allowed at its elevation), so the fitted
   window is checked frame by frame against the human range's rules and on the humanoid
   (about 8 microseconds a frame), with the window's shared root
   (``WindowProblem.root_window``) so that the floor is checked too: a frame counts when
   it breaks a rule beyond the ends, has any self-collision beyond its soft-tissue
   allowance or a geom deeper below the floor than its class allows — what the study
   counts, beyond the boxes the fit already keeps. If a frame counts, the next
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
:class:`controller.checks.kinematic_check.HumanoidChecker`, and the registry names the builder
that wires it lazily (``"controller.checks.kinematic_check:feasible_key_source"``), so the
registry entry is one line, importing ``upm.transitions`` stays MuJoCo-free, and the
command line, the studio, the bench and the study all get the checked source. Without a
checker (``FeasibleKeys(map)`` in a script) the method still keeps every frame in range
and checks the coupled rules; it just cannot avoid self-collisions.
"""
from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from upm.core.errors import UsageError
from upm.motion.range_models import range_model
from upm.motion.skeleton import JOINTS
from upm.ops.angles import angle_diff_deg, wrap_deg
from upm.transitions import slerp
from upm.transitions.base import TransitionMethod, WindowProblem, WindowResult
from upm.transitions.feasible_fit import fit_window
from upm.transitions.feasible_keys import FeasibleKeys, clamp_into_range, feasible_key_source
from upm.transitions.feasible_range import (
    allowed_range,
    limit_turns,
    long_way_turns,
    range_boxes_deg,
)
from upm.transitions.spline import keyframe_spline

#: Candidate windows fitted and checked at most (when the first has invalid frames).
#: Measured on 60 pairs drawn with seed 1 (the study draws with seed 0), L = 20, valid
#: frames: one window 66.2 %; the map's two nearest collision-free keys 67.1 %; the
#: nearest key then the alpha-point 73.1 % (alpha-point window kept on 16 pairs); four
#: windows (two more map keys) 73.3 %.
WINDOW_TRIES = 2
#: Whether the alpha-point (clamped into range: no map) is the second key candidate.
STRAIGHT_KEY = True

def _continuous_key(problem: WindowProblem, key_wrapped: np.ndarray) -> np.ndarray:
    point = problem.a_deg + problem.alpha * (problem.b_deg - problem.a_deg)
    return point + angle_diff_deg(key_wrapped, point)


def _upm_curve(problem: WindowProblem, key: np.ndarray) -> np.ndarray:
    times = np.concatenate([problem.before_times, [problem.key_time], problem.after_times])
    values = np.concatenate([problem.before_deg, key[None], problem.after_deg])
    return keyframe_spline(times, values, problem.window_times)


def _added_rule_excess(problem: WindowProblem):
    """``added(postures_deg) -> (N, R)``: degrees beyond each rule of the human range
    beyond what the window's ends already break (the study's added excess; a coupled rule,
    such as a shoulder's twist at its elevation, that the per-DOF boxes cannot state). The
    ends' excess is computed once; it does not change when clip 2 is taken a whole turn
    further."""
    model, skeleton = range_model(), problem.skeleton
    ends = model.excess_deg(skeleton, np.stack([problem.a_deg, problem.b_deg])).max(axis=0)

    def added(postures_deg) -> np.ndarray:
        return np.maximum(model.excess_deg(skeleton, postures_deg) - ends, 0.0)

    return added


def _with_geodesic_joints(problem: WindowProblem, curve_deg, broken_rules, constrained):
    """The curve (L, 63) with each joint of a broken rule (``broken_rules``, bool (R,))
    replaced by that joint's geodesic (``slerp``'s shortest rotation from A to B, which
    keeps a joint inside a rule both ends satisfy far more often than a path in Euler
    angles does), and the problem with clip 2 a whole turn further where the geodesic
    arrives at B on another turn (only on DOFs without a bound); None when no joint can be
    replaced; and the number of joints replaced."""
    joints = {rule.split(".")[0] for rule, b in zip(range_model().rule_names, broken_rules,
                                                     strict=True) if b}
    geodesic = slerp.solve(problem).posture_deg
    curve, turns, replaced = np.array(curve_deg, dtype=float), np.zeros(63), 0
    for joint in sorted(joints):
        dofs = slice(3 * JOINTS.index(joint), 3 * JOINTS.index(joint) + 3)
        turn = np.round((geodesic[-1, dofs] - problem.b_deg[dofs]) / 360.0)
        if np.any((turn != 0) & constrained[dofs]):
            continue
        curve[:, dofs], turns[dofs] = geodesic[:, dofs], turn
        replaced += 1
    if not replaced:
        return None, problem, 0
    moved = dataclasses.replace(problem, after_deg=problem.after_deg + 360.0 * turns)
    return curve, moved, replaced


def _invalid_frames(added_excess, checker, window_deg, root):
    """Window frames the study counts invalid for a reason the range's boxes cannot
    prevent: a coupled rule of the human range broken beyond the ends, a self-collision
    (any pair, as the study counts it) or, with the root, a foot or body below the floor;
    and which rules the window breaks, bool (R,)."""
    beyond = added_excess(window_deg) > 1e-6
    invalid = beyond.any(axis=1)
    if checker is not None:
        colliding, floor = checker.frame_checks(window_deg, root, names=False)
        invalid |= colliding | floor
    return int(np.count_nonzero(invalid)), beyond.any(axis=0)


def _keys_in_order(added_excess, candidates, straight, checker, at_ends):
    """The key candidates in the order their windows are tried, each with whether the
    humanoid takes it (inside the human range's rules beyond what A and B break, and
    without a self-collision that A and B do not have): the map's nearest such key, the
    alpha-point (``straight``, if it is one), the map's other such keys, then the rest.
    Checked lazily: only the keys whose window is fitted cost a check."""
    def free(key) -> bool:
        if added_excess(key[None]).max() > 1e-6:
            return False
        return checker is None or not checker.self_collision_pairs(key)[0] - at_ends

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
    boxes = range_boxes_deg(skeleton)
    point = wrap_deg(problem.a_deg + problem.alpha * (problem.b_deg - problem.a_deg))
    candidates = source.candidates(point, boxes, widen)
    checker = source.checker(skeleton)

    at_ends = frozenset()
    if checker is not None:
        end_pairs = checker.self_collision_pairs(np.stack([problem.a_deg, problem.b_deg]))
        at_ends = frozenset().union(*end_pairs)
    straight = clamp_into_range(point, boxes, widen) if STRAIGHT_KEY else None
    added_excess = _added_rule_excess(problem)
    keys = _keys_in_order(added_excess, candidates, straight, checker, at_ends)

    def fitted(curve, on=problem):
        bounds = (lower, upper, constrained) if on is problem else allowed_range(on)[:3]
        window, fit = fit_window(on, curve, *bounds)
        return (*_invalid_frames(added_excess, checker, window, on.root_window), window,
                fit)

    best = None
    for attempt, (key_wrapped, admissible) in enumerate(itertools.islice(keys, WINDOW_TRIES)):
        curve = _upm_curve(problem, _continuous_key(problem, key_wrapped))
        invalid, broken, window, fit = fitted(curve)
        geodesic = 0
        if invalid and broken.any():
            repaired, moved, joints = _with_geodesic_joints(problem, curve, broken,
                                                            constrained)
            if repaired is not None:
                candidate = fitted(repaired, moved)
                if candidate[0] < invalid:
                    (invalid, _, window, fit), geodesic = candidate, joints
        if best is None or invalid < best[0]:
            best = (invalid, window, key_wrapped, fit, attempt, admissible, geodesic)
        if invalid == 0:
            break
    invalid, window, key_wrapped, fit, attempt, admissible, geodesic = best
    diagnostics = {
        "key_candidate": float(attempt),
        "window_invalid_frames": float(invalid),
        "unconstrained_dofs": float((skeleton.declared & ~constrained).sum()),
        "long_way_dofs": float(np.count_nonzero(turns)),
        "geodesic_joints": float(geodesic),
        "limit_turn_dofs": float(limit_turns(problem, lower, upper, constrained).any(
            axis=0).sum()),
        "kinematic_checks": float(checker is not None),
        "floor_checked": float(checker is not None and problem.root_window is not None),
        **fit,
    }
    diagnostics["key_admissible"] = float(admissible)
    return WindowResult(window, key_posture_deg=wrap_deg(key_wrapped), diagnostics=diagnostics)


METHOD = TransitionMethod(
    name="feasible", solve=solve, continuity="C1", key_kind="feasible",
    summary="UPM key among the neurons the humanoid can take, window fitted as a small QP: "
            "near the UPM curve, minimum jerk, C1 joins, every frame in range (needs a map)",
    key_source=feasible_key_source,
    key_help="a trained Uniform Posture Map (upm train --kind upm); the humanoid's checks "
             "come from the checker the controller package registers "
             "(upm.transitions.feasible_keys.register_kinematic_checker)",
    role="recommended", needs_map=True,
)

