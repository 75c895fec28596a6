"""Synthetic motion data for the unit tier: no CMU file needed.

- :func:`asf_text` writes a :class:`~upm.motion.skeleton.Skeleton` as ASF text (e.g. the
  project's own :func:`humanoid_xml.description.generic_skeleton`: the CMU bone topology
  with generic proportions), optionally scaled to another stature;
- :func:`walk_motion` makes a smooth walk-like motion on a skeleton: every declared DOF a
  periodic curve inside its limits (legs in antiphase, arms against the legs), the root
  moving forward along its heading;
- :func:`amc_text` writes a motion as AMC text, independently of :func:`upm.write_amc`;
- :func:`write_data_folder` writes a small data folder shaped like the CMU one:
  ``NN/NN.asf``, ``NN/NN_MM.amc`` and a ``clips.csv`` with frame rates and the train/test
  split (:data:`SUBJECTS`, :data:`CLIPS`).

The conftest's ``synthetic_dir`` / ``synthetic_catalog`` fixtures write the folder once per
session.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np

from upm.motion.motion import Motion
from upm.motion.skeleton import JOINTS, Skeleton, joint_dof_index

#: CMU's ``:units length`` (one ASF unit is 0.0254 / 0.45 m).
CMU_LENGTH_UNIT = 0.45


@dataclasses.dataclass(frozen=True)
class SubjectSpec:
    """One synthetic subject: the generic skeleton scaled to a stature."""

    subject: str
    scale: float  #: bone lengths times this (the generic adult is 1.75 m tall)
    crlf: bool  #: its files end lines with CRLF (as some CMU subjects' do)


@dataclasses.dataclass(frozen=True)
class ClipSpec:
    """One synthetic clip."""

    name: str
    fps: float
    seconds: float
    split: str
    description: str
    cadence_hz: float  #: gait cycles per second
    amplitude: float  #: share (0..1] of each DOF's allowed swing
    speed_m_s: float
    heading_deg: float  #: heading at the first frame (root ry)
    turn_deg_s: float = 0.0
    seed: int = 0


#: Two subjects of different statures (1.75 m and 0.88 x 1.75 = 1.54 m).
SUBJECTS = (SubjectSpec("81", 1.0, crlf=False), SubjectSpec("82", 0.88, crlf=True))

#: Five clips: walks, runs and a turning walk; one at 60 fps; three train, two test.
CLIPS = (
    ClipSpec("81_01", 120.0, 1.5, "train", "synthetic walk", 0.9, 0.6, 1.3, 0.0, seed=1),
    ClipSpec("81_02", 120.0, 1.2, "train", "synthetic run", 1.4, 1.0, 3.0, 20.0, seed=2),
    ClipSpec("81_03", 120.0, 1.5, "test", "synthetic walk, turning left", 0.9, 0.7, 1.1,
             -30.0, turn_deg_s=40.0, seed=3),
    ClipSpec("82_01", 60.0, 2.0, "train", "synthetic walk", 1.0, 0.5, 1.1, 90.0, seed=4),
    ClipSpec("82_02", 120.0, 1.2, "test", "synthetic run", 1.5, 0.9, 2.6, 0.0, seed=5),
)

#: The order of the bones in a CMU AMC frame (after the root).
AMC_BONE_ORDER = ("lowerback", "upperback", "thorax", "lowerneck", "upperneck", "head",
                  "rclavicle", "rhumerus", "rradius", "rwrist", "rhand", "rfingers", "rthumb",
                  "lclavicle", "lhumerus", "lradius", "lwrist", "lhand", "lfingers", "lthumb",
                  "rfemur", "rtibia", "rfoot", "rtoes", "lfemur", "ltibia", "lfoot", "ltoes")

#: clips.csv's columns, as in the CMU folder.
CSV_COLUMNS = ("clip", "subject", "fps", "frames", "split", "description")


def _number(value: float) -> str:
    return repr(float(value)) if value != 0 else "0"


def asf_text(skeleton: Skeleton, *, name: str | None = None, scale: float = 1.0,
             length_unit: float = CMU_LENGTH_UNIT, newline: str = "\n") -> str:
    """An ASF file describing ``skeleton`` (its lengths times ``scale``).

    Parameters
    ----------
    skeleton : Skeleton
        Angles in degrees; its root order, axis orders, DOFs and limits are written as
        they are.
    name : str, optional
        The ``:name`` (default: the skeleton's).
    scale : float
        Factor on every bone length (a taller or shorter subject of the same build).
    length_unit : float
        ``:units length``: one ASF length unit is ``0.0254 / length_unit`` metres.
    newline : str
        ``"\\n"`` or ``"\\r\\n"``.

    Returns
    -------
    str
        Reading it with :func:`upm.read_asf` gives ``skeleton`` back (lengths to float
        precision).
    """
    unit_m = 0.0254 / length_unit
    root = skeleton.root_order
    out = [":version 1.10", f":name {name or skeleton.name}", ":units", "  mass 1.0",
           f"  length {length_unit!r}", "  angle deg", ":documentation",
           "  synthetic skeleton written by tests/synthetic.py", ":root",
           "  order " + " ".join(c.upper() for c in root),
           f"  axis {skeleton.root_axis_order}", "  position 0 0 0", "  orientation 0 0 0",
           ":bonedata"]
    for b in range(1, skeleton.n_bones):
        out += ["  begin", f"     id {b}", f"     name {skeleton.bone_names[b]}",
                "     direction " + " ".join(_number(v) for v in skeleton.directions[b]),
                f"     length {_number(skeleton.lengths_m[b] * scale / unit_m)}",
                "     axis " + " ".join(_number(v) for v in skeleton.axis_deg[b])
                + f" {skeleton.axis_order[b]}"]
        if skeleton.dofs[b]:
            out.append("    dof " + " ".join(skeleton.dofs[b]))
            pairs = [f"({_number(lo)} {_number(hi)})" for lo, hi in skeleton.dof_limits_deg[b]]
            out.append("    limits " + pairs[0])
            out += ["           " + p for p in pairs[1:]]
        out.append("  end")
    out += [":hierarchy", "  begin"]
    for b in range(skeleton.n_bones):
        kids = [skeleton.bone_names[k] for k in np.flatnonzero(skeleton.parents == b)]
        if kids:
            out.append(f"    {skeleton.bone_names[b]} " + " ".join(kids))
    out += ["  end", ""]
    return newline.join(out)


def _allowed_swing(limits_deg: np.ndarray, amplitude: float) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half-swing (degrees) of a curve kept inside each DOF's limits: the
    centre is 0 moved at least 30 % of the range inside it, the swing at most a quarter
    of the range (and 30 degrees), so centre +- swing stays 5 % of the range inside."""
    lo, hi = limits_deg[:, 0], limits_deg[:, 1]
    span = hi - lo
    centre = np.clip(0.0, lo + 0.3 * span, hi - 0.3 * span)
    return centre, amplitude * np.minimum(0.25 * span, 30.0)


def _phases(skeleton: Skeleton, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Gait phase (radians) of every posture DOF: left leg 0, right leg pi, arms against
    their leg, the trunk at twice the cadence; and a random phase for each DOF's second
    harmonic."""
    phase = np.zeros(63)
    for joint in JOINTS:
        side = {"l": 0.0, "r": math.pi}.get(joint[0], 0.0)
        if joint in ("lowerback", "upperback", "thorax", "lowerneck", "head"):
            side = 0.5 * math.pi
        arm = joint[1:] in ("clavicle", "humerus", "radius", "hand")
        for axis in ("rx", "ry", "rz"):
            phase[joint_dof_index(joint, axis)] = side + (math.pi if arm else 0.0)
    return phase, rng.uniform(0.0, 2.0 * math.pi, 63)


def rest_root_height_m(skeleton: Skeleton) -> float:
    """The root height that puts the lowest bone end of the rest pose on the floor, m."""
    from upm.motion.kinematics import rest_positions

    return float(-rest_positions(skeleton)[:, 1].min())


def walk_motion(skeleton: Skeleton, clip: ClipSpec) -> Motion:
    """A smooth walk-like motion of ``skeleton``.

    Every declared posture DOF follows ``c + a (0.8 sin(w t + p) + 0.2 sin(2 w t + q))``
    with ``w = 2 pi cadence``, inside its limits (:func:`_allowed_swing`); undeclared
    DOFs stay 0. The root moves forward along its heading (root ry, turning at
    ``turn_deg_s``) at ``speed_m_s``, swaying and bobbing a little; its height keeps the
    rest pose's feet on the floor. The non-articulated channels (fingers, thumbs, ...)
    move too, inside their limits.

    Returns
    -------
    Motion
        ``round(seconds * fps)`` frames at ``clip.fps``, named ``clip.name``.
    """
    rng = np.random.default_rng(clip.seed)
    n = int(round(clip.seconds * clip.fps))
    t = np.arange(n) / clip.fps
    w = 2.0 * math.pi * clip.cadence_hz
    centre, swing = _allowed_swing(skeleton.limits_deg, clip.amplitude)
    phase, harmonic = _phases(skeleton, rng)
    wave = 0.8 * np.sin(w * t[:, None] + phase) + 0.2 * np.sin(2 * w * t[:, None] + harmonic)
    posture = np.where(skeleton.declared, centre + swing * wave, 0.0)

    heading = clip.heading_deg + clip.turn_deg_s * t
    step = clip.speed_m_s / clip.fps
    forward = np.stack([np.sin(np.radians(heading)), np.cos(np.radians(heading))], axis=1)
    ground = np.vstack([np.zeros(2), np.cumsum(step * forward[:-1], axis=0)])
    root = np.zeros((n, 6))
    root[:, 0] = ground[:, 0] + 0.02 * np.sin(w * t)
    root[:, 2] = ground[:, 1]
    root[:, 1] = rest_root_height_m(skeleton) - 0.015 * (1.0 - np.cos(2 * w * t))
    root[:, 3] = 4.0 * np.sin(2 * w * t)
    root[:, 4] = heading
    root[:, 5] = 3.0 * np.sin(w * t)

    extra_limits = skeleton.extra_limits_deg
    extra = None
    if len(extra_limits):
        c, a = _allowed_swing(extra_limits, clip.amplitude)
        extra = c + a * np.sin(w * t[:, None] + rng.uniform(0, 2 * math.pi, len(c)))
    return Motion(skeleton, posture, root, fps=clip.fps, extra_deg=extra, name=clip.name)


def amc_text(motion: Motion, *, newline: str = "\n", precision: int = 10) -> str:
    """``motion`` as AMC text (degrees; the root first, then the bones in CMU's order,
    :data:`AMC_BONE_ORDER`, then any other bone with DOFs in ASF order).

    Written here, not by :func:`upm.write_amc`, so that reading it tests the reader
    against an independent writer.
    """
    skeleton = motion.skeleton
    to_units = 1.0 / skeleton.length_to_m
    extra_index = {channel: k for k, channel in enumerate(skeleton.extra_channels)}
    joints = set(JOINTS)
    fmt = f"%.{precision}g"
    root_columns = {"tx": 0, "ty": 1, "tz": 2, "rx": 3, "ry": 4, "rz": 5}
    names = skeleton.bone_names[1:]
    order = [b for b in AMC_BONE_ORDER if b in names] + [
        b for b in names if b not in AMC_BONE_ORDER]
    out = ["#!OML:ASF " + Path(skeleton.source).name, ":FULLY-SPECIFIED", ":DEGREES"]
    for frame in range(motion.n_frames):
        out.append(str(frame + 1))
        root = [motion.root[frame, root_columns[c]] * (to_units if c[0] == "t" else 1.0)
                for c in skeleton.root_order]
        out.append("root " + " ".join(fmt % v for v in root))
        for bone in order:
            dofs = skeleton.dofs[skeleton.bone_index(bone)]
            if not dofs:
                continue
            if bone in joints:
                values = [motion.posture_deg[frame, joint_dof_index(bone, d)] for d in dofs]
            elif motion.extra_deg is None:
                values = [0.0] * len(dofs)
            else:
                values = [motion.extra_deg[frame, extra_index[bone, d]] for d in dofs]
            out.append(bone + " " + " ".join(fmt % v for v in values))
    return newline.join(out) + newline


def subject_skeleton(spec: SubjectSpec, folder: Path) -> Skeleton:
    """The skeleton of a synthetic subject as read back from its ASF in ``folder``."""
    from upm.motion.asf import read_asf

    return read_asf(folder / spec.subject / f"{spec.subject}.asf")


def write_data_folder(root: str | Path, subjects=SUBJECTS, clips=CLIPS) -> Path:
    """Write a synthetic data folder: ``NN/NN.asf``, ``NN/NN_MM.amc`` and ``clips.csv``.

    Each subject's ASF is the generic skeleton scaled to its stature; each clip is
    :func:`walk_motion` on the skeleton read back from that ASF (so the AMC's root
    translation is in the subject's own length unit).

    Returns
    -------
    Path
        ``root``.
    """
    import csv
    import io

    from humanoid_xml.description import generic_skeleton

    root = Path(root)
    generic = generic_skeleton()
    by_subject = {}
    for spec in subjects:
        folder = root / spec.subject
        folder.mkdir(parents=True, exist_ok=True)
        newline = "\r\n" if spec.crlf else "\n"
        text = asf_text(generic, name=f"synthetic{spec.subject}", scale=spec.scale,
                        newline=newline)
        (folder / f"{spec.subject}.asf").write_bytes(text.encode("ascii"))
        by_subject[spec.subject] = (spec, subject_skeleton(spec, root))
    rows = io.StringIO()
    writer = csv.writer(rows, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for clip in clips:
        subject = clip.name.split("_")[0]
        spec, skeleton = by_subject[subject]
        motion = walk_motion(skeleton, dataclasses.replace(
            clip, speed_m_s=clip.speed_m_s * spec.scale))
        newline = "\r\n" if spec.crlf else "\n"
        (root / subject / f"{clip.name}.amc").write_bytes(
            amc_text(motion, newline=newline).encode("ascii"))
        writer.writerow([clip.name, subject, f"{clip.fps:g}", motion.n_frames, clip.split,
                         clip.description])
    (root / "clips.csv").write_text(rows.getvalue(), encoding="utf-8")
    return root


def clip_spec(name: str) -> ClipSpec:
    """The :data:`CLIPS` entry called ``name``."""
    return next(c for c in CLIPS if c.name == name)
