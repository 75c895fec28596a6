"""``performed``: the window as the free-root humanoid performed it.

Another method's window (``feasible``'s by default: :attr:`PerformedKeys.follow`, ``--follow
METHOD``) is made first, as that method makes it; then the humanoid, its root free on the
floor and no force on it but the floor's, follows the transition from the clip's own
state a little before the window to a little after it (the configuration's
``window_runs``: 0.5 s each side, as the controller's other window runs), in the offline
effort (a sampling search over its servos' targets, :mod:`controller.offline`); what it
did — joints and root, contacts included — converted back to the subject's joint angles,
replaces the window *and the context around it*: the run starts from the clip's own state,
so it joins clip 1 where it starts, and the one join left is where it ends, 0.5 s into
clip 2, which is turned about the vertical and moved along the floor (as physical on a
flat floor) to continue where and as the body ended. (The window's frames alone would
join the clips with a step: after 0.5 s of following, the body's pelvis is tilted a few
degrees from the clip's, and on 02_01@200 -> 02_03@20 that step made the study's jerk,
foot skating and residual force of the window those of a jump.) The figures report both
joins' steps.

Where the body cannot perform the asked window (it falls, or the search was in trouble
in the window), that is a finding, reported in the transition's diagnostics
(``performed_fell``, ``performed_left_window``), not an error.

This layer does not import the humanoid: the performer is installed by the layer that
has it (:func:`install_performer`; the command line and the study install
:func:`controller.offline.performer.perform_transition`). Without one, the method is a
:class:`upm.core.errors.UsageError`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from upm.core.errors import UsageError
from upm.transitions.base import Transition, TransitionMethod, WindowProblem, WindowResult

#: The method followed when none is named.
DEFAULT_FOLLOW = "feasible"

#: The installed performer (None until the application layer installs one).
_PERFORMER: list[Callable | None] = [None]


@dataclass(frozen=True)
class PerformedWindow:
    """What the performer returns.

    Attributes
    ----------
    posture_deg : ndarray, shape (M, 63)
        The performed frames' joint angles, degrees: the window and the context the body
        performed around it.
    root : ndarray, shape (M, 6)
        Their root: tx, ty, tz metres, rx, ry, rz degrees (the skeleton's root order).
    figures : dict of str to float
        How it went (joint and body error against the asked window, fall, trouble,
        torque saturation, cost): the transition's diagnostics, prefixed ``performed_``.
    first : int
        The transition motion's frame of the first performed frame (the run starts there
        from the clip's own state).
    """

    posture_deg: np.ndarray
    root: np.ndarray
    figures: dict
    first: int


def install_performer(performer: Callable | None) -> None:
    """Make ``performer(transition, context_s, config) -> PerformedWindow`` the one the
    method calls (None: none). ``context_s`` None: the configuration's own."""
    _PERFORMER[0] = performer


def installed_performer() -> Callable | None:
    return _PERFORMER[0]


@dataclass(frozen=True, eq=False)
class PerformedKeys:
    """The key source of ``performed``: the followed method, its own key source, and the
    performer's configuration (a :class:`controller.config.ControllerConfig`, opaque here;
    None: the defaults).

    Attributes
    ----------
    follow : TransitionMethod
        The followed method (``upm.transitions.get_method("feasible")``).
    source : KeyPostureSource or None
        Its key source.
    config : object or None
    context_s : float or None
        Context before and after the window, s (None: the configuration's).
    """

    follow: TransitionMethod
    source: object | None = None
    config: object | None = None
    context_s: float | None = None
    kind = "performed"

    def key_posture(self, a_deg, b_deg, alpha=0.5):
        """The followed method's key posture (a linear blend for a method without one)."""
        if self.source is not None:
            return self.source.key_posture(a_deg, b_deg, alpha)
        a, b = np.asarray(a_deg, dtype=float), np.asarray(b_deg, dtype=float)
        return a + alpha * (b - a)


def key_source_of(context, get_method: Callable, build_key_source: Callable) -> PerformedKeys:
    """The key source of ``performed`` from a :class:`upm.transitions.registry.KeySourceContext`
    (its ``follow`` and ``performer_config``), with the registry's ``get_method`` and
    ``build_key_source`` (the registry passes them: this module does not import it)."""
    follow = context.follow or DEFAULT_FOLLOW
    if follow == "performed":
        raise UsageError("--follow performed: follow another method (e.g. feasible, linear)")
    spec = get_method(follow)
    source = build_key_source(spec, context)
    context.method = "performed"
    return PerformedKeys(follow=spec, source=source, config=context.performer_config)


def _keys(key_source) -> PerformedKeys:
    if not isinstance(key_source, PerformedKeys):
        raise UsageError("method 'performed' needs its key source "
                         "(upm.transitions.build_key_source('performed', context), or "
                         "upm.transitions.performed.PerformedKeys)")
    return key_source


def solve(problem: WindowProblem) -> WindowResult:
    """The followed method's window (what the humanoid is asked to perform)."""
    keys = _keys(problem.key_source)
    return keys.follow.solve(dataclasses.replace(problem, key_source=keys.source))


def finish(result: Transition, key_source) -> Transition:
    """The transition with its window and the context around it replaced by what the
    humanoid performed (:class:`PerformedWindow`)."""
    import time

    keys = _keys(key_source)
    performer = installed_performer()
    if performer is None:
        raise UsageError("method 'performed' needs the humanoid's performer: run it from the "
                         "command line (upm transition/sequence/simulate/eval), or install "
                         "one (upm.transitions.performed.install_performer)")
    start = time.perf_counter()
    done = performer(result, keys.context_s, keys.config)
    seconds = time.perf_counter() - start
    window = result.window
    order = result.motion.skeleton.root_axis_order
    posture = np.array(result.motion.posture_deg, dtype=float)
    root = np.array(result.motion.root, dtype=float)
    first = int(done.first)
    stop = first + done.posture_deg.shape[0]
    if not (0 <= first <= window.start and window.stop <= stop <= root.shape[0]):
        raise ValueError(f"the performer returned frames {first}:{stop}, which do not cover "
                         f"the window {window.start}:{window.stop}")
    asked_end = root[stop - 1].copy()
    posture[first:stop] = done.posture_deg
    root[first:stop] = done.root
    if stop < root.shape[0]:  # the clip continues where and as the body ended
        end = root[stop - 1]
        root[stop:] = turned(root[stop:], order, _heading_turn(asked_end, end, order),
                             asked_end, end)
    motion = result.motion.replace(posture_deg=posture, root=root)
    diagnostics = dict(result.diagnostics)
    diagnostics.update({f"performed_{k}": float(v) for k, v in done.figures.items()})
    return dataclasses.replace(result, motion=motion, method="performed",
                               seconds=result.seconds + seconds, diagnostics=diagnostics)


def _heading_turn(source, target, order: str) -> float:
    """The turn about the vertical, degrees, from root ``source``'s heading to
    ``target``'s (roots (6,): tx, ty, tz m, rx, ry, rz deg)."""
    from upm.ops.angles import angle_diff_deg
    from upm.ops.rotations import euler_to_matrix
    from upm.transitions.root import heading_deg

    return float(angle_diff_deg(heading_deg(euler_to_matrix(target[3:], order)),
                                heading_deg(euler_to_matrix(source[3:], order))))


def turned(root, order: str, turn_deg: float, pivot, to) -> np.ndarray:
    """Roots (T, 6) turned by ``turn_deg`` about the vertical (ASF y) through ``pivot``'s
    position and moved so that ``pivot``'s lands on ``to``'s, horizontally (heights kept);
    angles continuous from the first frame's."""
    from upm.ops.rotations import axis_rotation, continuous_euler_deg, euler_to_matrix

    root = np.asarray(root, dtype=float)
    turn = axis_rotation(turn_deg, "Y")
    out = root.copy()
    offset = root[:, :3] - np.array([pivot[0], 0.0, pivot[2]])
    out[:, :3] = offset @ turn.T + np.array([to[0], 0.0, to[2]])
    matrices = turn @ euler_to_matrix(root[:, 3:], order)
    out[:, 3:] = continuous_euler_deg(matrices, order, root[0, 3:])
    return out


#: The method; the registry registers it with its key-source builder
#: (``upm.transitions.registry``: :func:`key_source_of` with the registry's functions).
METHOD = TransitionMethod(
    name="performed", solve=solve, finish=finish, continuity="C0", key_kind="performed",
    summary="the window as the free-root humanoid performed it while following another "
            "method's (feasible by default, --follow), found by the offline effort's search "
            "(about a minute per window)",
    key_help="the followed method's key source and the humanoid's performer "
             "(upm.transitions.build_key_source('performed', context))",
    role="performed", needs_map=False,
)
