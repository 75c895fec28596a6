"""The humanoid's performer of the ``performed`` transition method
(:mod:`upm.transitions.performed`): the transition followed in the offline effort from the
clip's own state a little before the window to a little after it, and the window's frames
as the body did them, back on the subject's joint angles. :func:`install` puts it into
the method's slot (the command line and the study call it)."""

from __future__ import annotations

import numpy as np

from controller.config import DEFAULT

#: The humanoid of each skeleton seen (by identity; the skeleton is kept with it).
_MODELS: dict[int, tuple[object, object]] = {}


def install() -> None:
    """Install :func:`perform_transition` as ``performed``'s performer."""
    from upm.transitions.performed import install_performer

    install_performer(perform_transition)


def humanoid_of(skeleton):
    """The humanoid of an ASF skeleton (built once per skeleton)."""
    import mujoco

    from humanoid_xml import build_mjcf

    key = id(skeleton)
    if key not in _MODELS or _MODELS[key][0] is not skeleton:
        _MODELS[key] = (skeleton, mujoco.MjModel.from_xml_string(build_mjcf(skeleton)))
    return _MODELS[key][1]


def perform_transition(transition, context_s: float | None = None, config=None):
    """What the free-root humanoid did in a transition's window.

    Parameters
    ----------
    transition : upm.transitions.Transition
        The asked transition (its motion and window).
    context_s : float or None
        Seconds of the motion simulated before and after the window (None: the
        configuration's ``window_runs.lead_s`` and ``tail_s``).
    config : controller.config.ControllerConfig or None
        The offline effort's configuration (None: the defaults).

    Returns
    -------
    upm.transitions.performed.PerformedWindow
        The window's joint angles and root, and ``figures``: ``joint_error_deg`` (RMS
        over the window's frames and hinges, against the asked window), ``body_error_mm``
        (mean), ``fell`` (1/0: anywhere in the run), ``fell_in_window``, ``left_window``
        (1: fell before the window's end, or the search's chosen path was in trouble in a
        segment that overlaps the window), ``torque_saturation_share`` (the window's
        frames), ``root_drift_m`` (at the window's end), ``join_step_a_deg`` and
        ``join_step_b_deg`` (RMS over the DOFs of the step from A to the first window frame
        and from the last to B), ``rollouts``, ``wall_s``, ``path_shift_m`` (the horizontal
        shift that joins the performed path to A's: the run starts before A and drifts; on
        the flat floor the shifted motion is as physical).
    """
    from controller.offline import perform
    from controller.offline.samcon import segment_bounds
    from controller.qpos import from_qpos, to_qpos
    from upm.ops.angles import angle_diff_deg
    from upm.transitions.performed import PerformedWindow

    config = DEFAULT if config is None else config
    motion = transition.motion
    model = humanoid_of(motion.skeleton)
    fps = motion.fps
    n = motion.n_frames
    w0, w1, _ = transition.window.indices(n)
    lead = config.window_runs.lead_s if context_s is None else context_s
    tail = config.window_runs.tail_s if context_s is None else context_s
    a = max(0, w0 - round(lead * fps))
    b = min(n, w1 + round(tail * fps))
    asked = to_qpos(model, motion)
    result = perform(model, asked[a:b], fps, config)
    inside = slice(w0 - a, w1 - a)
    qpos = result.qpos[inside]
    finite = np.all(np.isfinite(qpos), axis=1)
    qpos = np.where(finite[:, None], qpos, asked[w0:w1])  # a diverged run: the asked frames
    done = from_qpos(model, qpos, motion.skeleton, fps)
    root = done.root.copy()
    # The floor is flat: the same motion moved along it is as physical. Moved so that the
    # body's path joins A's (the run started before A and drifted): the horizontal shift
    # that puts its pelvis at A where A's is.
    at_a = w0 - 1 - a
    shift = np.zeros(2)
    if at_a >= 0 and np.all(np.isfinite(result.qpos[at_a])):
        performed_a = from_qpos(model, result.qpos[at_a][None], motion.skeleton, fps).root[0]
        shift = motion.root[w0 - 1, [0, 2]] - performed_a[[0, 2]]
    root[:, [0, 2]] += shift
    previous = motion.root[w0 - 1, 3:] if w0 > 0 else root[0, 3:]
    for t in range(root.shape[0]):  # the root's angles continue from A's, as join's do
        root[t, 3:] = previous + angle_diff_deg(root[t, 3:], previous)
        previous = root[t, 3:]
    posture = done.posture_deg
    declared = motion.skeleton.declared
    fall = result.tracking.fall_frame
    bounds = np.asarray(segment_bounds(b - a, fps, config.offline.segment_s))
    overlap = (bounds[1:] > w0 - a) & (bounds[:-1] < w1 - a)
    trouble = bool(np.any(result.outcome.segment_cost[overlap] > config.offline.trouble_cost))
    fell_in_window = fall is not None and fall < w1 - a
    share = result.tracking.saturation_share(inside)

    def step(x, y):
        return float(np.sqrt(np.mean(angle_diff_deg(x[declared], y[declared]) ** 2)))

    figures = {
        "joint_error_deg": float(np.sqrt(np.nanmean(result.error_deg[inside] ** 2))),
        "body_error_mm": float(np.nanmean(result.body_error_mm[inside])),
        "fell": float(result.fell),
        "fell_in_window": float(fell_in_window),
        "left_window": float(fell_in_window or trouble),
        "torque_saturation_share": float("nan") if share is None else share,
        "root_drift_m": float(result.root_drift_m[inside][-1]),
        "join_step_a_deg": (step(posture[0], motion.posture_deg[w0 - 1]) if w0 > 0
                            else 0.0),
        "join_step_b_deg": (step(posture[-1], motion.posture_deg[w1]) if w1 < n else 0.0),
        "rollouts": float(result.samples),
        "wall_s": float(result.wall_s),
        "diverged_frames": float(np.count_nonzero(~finite)),
        "path_shift_m": float(np.linalg.norm(shift)),
    }
    return PerformedWindow(posture_deg=posture, root=root, figures=figures)
