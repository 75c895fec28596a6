"""Join two clips with a transition (paper section 3.2) and write a playable AMC.

Clip 1 ends at --from CLIP@F (frame F, 0-based; default its last frame) and clip 2 starts
at --to CLIP@F (default its first frame); the window of --frames new frames lies between
them. The AMC holds --context frames of each clip around the window (default one second)
and uses clip 1's skeleton (its ASF). Clip 2 is resampled to clip 1's frame rate if they
differ, turned about the vertical so its heading continues clip 1's, and moved to
continue where the window ends.

Methods (--method): upm (default; the paper: UPM key posture + cubic B-spline; needs
--map), feasible (the recommended one: UPM key the humanoid can take, window fitted to
stay in the joint ranges with minimum jerk; needs a UPM --map), som (needs a SOM --map),
classnn and snap (key posture from the nearest training postures of --data's train
split: no map needed), linear, slerp, inertialize, spacetime, and performed: the window
as the free-root humanoid performed it while following --follow's (default feasible),
found by the offline effort's search (--config FILE.toml: its [offline] section); its
figures (joint and body error against the asked window, fall, torque saturation) go into
--json's diagnostics, prefixed performed_.

Examples:
  upm transition --map upm.npz --from 02_01@200 --to 02_03@20 --out walk-run.amc
  upm transition --method feasible --map upm.npz --from 02_01@200 --to 02_03@20 --out f.amc
  upm transition --method linear --from 05_01 --to 05_11 --out lin.amc --json lin.json
  upm transition --method performed --follow linear --from 02_01@200 --to 02_03@20 \
      --out p.amc --json p.json
"""

from __future__ import annotations

HELP = "join two clips with a transition and write an AMC (and JSON)"


def add_method_arguments(parser, default_method: str = "upm") -> None:
    """--method, --map, --alpha, --frames, --no-align: shared with ``upm sequence``."""
    parser.add_argument("--method", default=default_method, metavar="M",
                        help="upm, feasible, som, classnn, snap, linear, slerp, inertialize, "
                             "spacetime, performed (the window as the free-root humanoid "
                             "performed it, following --follow's; about a minute a window) "
                             f"(default: {default_method}; the registry: "
                             "upm.transitions.METHODS)")
    parser.add_argument("--map", metavar="MAP.npz", default=None,
                        help="trained posture map (upm train), needed by --method "
                             "upm/feasible/som")
    parser.add_argument("--alpha", type=float, default=0.5,
                        help="key-posture ratio in [0, 1]: 0 is A, 1 is B (default 0.5)")
    parser.add_argument("--frames", type=int, default=20, metavar="L",
                        help="window length in new frames (default 20, the paper's at 120 fps)")
    parser.add_argument("--no-align", dest="align_heading", action="store_false",
                        help="do not turn the next clip about the vertical to continue the "
                             "previous clip's heading")
    parser.add_argument("--follow", metavar="M", default=None,
                        help="with --method performed: the method whose window the humanoid "
                             "follows (default: feasible)")


def add_cut_argument(parser) -> None:
    """--cut: shared by ``upm sequence`` and ``upm simulate``."""
    from upm.transitions.cuts import MATCH_SEARCH_S

    parser.add_argument("--cut", choices=("whole", "matched"), default="whole",
                        help="where each piece but the last ends: 'whole' (default) at its "
                             "last frame; 'matched' at the frame, within its last "
                             f"{MATCH_SEARCH_S:g} s and its second half, whose feet (ankles "
                             "relative to the pelvis, and their velocities) are nearest the "
                             "next piece's first frame's, so the window joins the same gait "
                             "phase (the pieces used are reported as CLIP@A:B)")


def sequence_from_args(args, pieces_text: list[str]):
    """The clips named on the command line joined by ``--method`` transitions.

    Returns
    -------
    catalog : upm.motion.catalog.Catalog
    refs : list of upm.motion.catalog.ClipRef
    sequence : upm.transitions.Sequence
    """
    import warnings

    from upm.core.progress import progress
    from upm.motion.catalog import Catalog, parse_clip_ref
    from upm.transitions import build_sequence
    from upm.transitions.load import key_source_for
    from upm.transitions.registry import get_method

    catalog = Catalog(args.data)
    refs = [parse_clip_ref(text) for text in pieces_text]
    spans = [catalog.load_span(ref) for ref in progress(refs, desc="reading", unit="clip")]
    pieces = [piece for piece, _ in spans]
    if getattr(args, "cut", "whole") == "matched" and len(pieces) > 1:
        pieces, refs = _matched(pieces, refs, [start for _, start in spans])
    if len(refs) > 1:
        key_source = key_source_for(args.method, args.map, catalog, args.follow,
                                    getattr(args, "performer_config", None))
    else:
        # one piece has no transition: --method is only checked, --map is not read
        key_source = None
        get_method(args.method)
        if args.map is not None:
            warnings.warn("--map is not used: one piece has no transition", stacklevel=2)
    sequence = build_sequence(pieces, args.method, args.frames, args.alpha, key_source,
                              fps=args.fps, align_heading=args.align_heading)
    return catalog, refs, sequence


def _matched(pieces, refs, starts):
    """The pieces cut where the next one's gait phase matches, and their references."""
    from upm.core.errors import UsageError
    from upm.motion.catalog import ClipRef
    from upm.transitions.cuts import matched_pieces

    short = [str(ref) for ref, piece in zip(refs, pieces, strict=True) if piece.n_frames < 2]
    if short:
        raise UsageError(f"--cut matched needs pieces of at least 2 frames: {short[0]} is one "
                         "(a held pose has no gait phase)")
    cut, cuts = matched_pieces(pieces)
    out = [ClipRef(ref.name, start, start + piece.n_frames, has_range=True)
           for ref, piece, start in zip(refs[:-1], cut[:-1], starts[:-1], strict=True)]
    for ref, after, c in zip(out, refs[1:], cuts, strict=True):
        print(f"cut {ref}: its feet {c.distance_m:.2f} m from {after}'s first frame's "
              f"(at its last frame {c.whole_distance_m:.2f} m)")
    return cut, out + refs[-1:]


def configure(parser) -> None:
    from upm.commands.common import add_data_argument, add_performed_config_argument

    add_data_argument(parser)
    parser.add_argument("--from", dest="source", required=True, metavar="CLIP[@FRAME]",
                        help="clip 1, ending at FRAME (0-based; default its last frame)")
    parser.add_argument("--to", dest="target", required=True, metavar="CLIP[@FRAME]",
                        help="clip 2, starting at FRAME (default 0)")
    add_method_arguments(parser)
    parser.add_argument("--context", type=int, default=None, metavar="N",
                        help="frames of each clip kept in the AMC around the window "
                             "(default: one second)")
    parser.add_argument("--out", required=True, metavar="OUT.amc|OUT.bvh",
                        help="the motion to write: AMC, or BVH (centimetres, y up) by the "
                             "extension")
    parser.add_argument("--json", metavar="FILE.json", default=None,
                        help="also write the window's postures, root and timing as JSON")
    parser.add_argument("--plot", metavar="FIG.png", default=None,
                        help="also plot one DOF across the window, this method vs linear "
                             "(the paper's Fig. 13)")
    add_performed_config_argument(parser)
    parser.add_argument("--plot-dof", metavar="JOINT.AXIS", default=None,
                        help="the DOF to plot, e.g. rhumerus.rz (default: the right shoulder "
                             "DOF where the method and linear differ most)")


def _single_frame(text: str, option: str):
    from upm.core.errors import UsageError
    from upm.motion.catalog import parse_clip_ref

    ref = parse_clip_ref(text)
    if ref.has_range:
        raise UsageError(f"{option} {text}: give CLIP or CLIP@FRAME (one frame), not a range")
    return ref


def _clip_window(catalog, ref, role: str, context: int | None):
    """Clip 1 up to its frame (role "from") or clip 2 from its frame (role "to")."""
    from upm.core.errors import UsageError

    motion = catalog.load(ref.name)
    n = motion.n_frames
    keep = context if context is not None else max(1, round(motion.fps))
    if role == "from":
        end = n - 1 if ref.start is None else (ref.start + n if ref.start < 0 else ref.start)
        if not 0 <= end < n:
            raise UsageError(f"--from {ref}: frame out of range (clip {ref.name} has {n} "
                             f"frames, numbered 0 to {n - 1})")
        return motion.frames(max(0, end + 1 - keep), end + 1), end
    start = 0 if ref.start is None else (ref.start + n if ref.start < 0 else ref.start)
    if not 0 <= start < n:
        raise UsageError(f"--to {ref}: frame out of range (clip {ref.name} has {n} frames, "
                         f"numbered 0 to {n - 1})")
    return motion.frames(start, min(n, start + keep)), start


def window_report(result, fps: float) -> dict:
    """The JSON description of a transition's window."""
    from upm.motion.skeleton import POSTURE_DOF_NAMES

    key = result.key_posture_deg
    return {
        "method": result.method,
        "frames": result.frames,
        "alpha": result.alpha,
        "fps": fps,
        "window_first_frame": result.window.start,
        "window_stop_frame": result.window.stop,
        "key_time_frames_after_a": result.key_time,
        "heading_turn_deg": result.heading_turn_deg,
        "seconds": result.seconds,
        "diagnostics": dict(result.diagnostics),
        "dof_names": list(POSTURE_DOF_NAMES),
        "root_channels": ["tx_m", "ty_m", "tz_m", "rx_deg", "ry_deg", "rz_deg"],
        "window_posture_deg": result.window_posture_deg.round(6).tolist(),
        "window_root": result.window_root.round(6).tolist(),
        "key_posture_deg": None if key is None else key.round(6).tolist(),
    }


def run(args) -> int:
    import json

    from upm.bvh.formats import check_motion_path, write_motion
    from upm.commands.common import performed_setup
    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_write_text
    from upm.motion.catalog import Catalog
    from upm.transitions import transition
    from upm.transitions.load import key_source_for

    check_motion_path(args.out)
    performer_config = performed_setup(args)

    if args.context is not None and args.context < 2:
        raise UsageError(f"--context must be at least 2 frames, not {args.context}")
    if args.plot_dof is not None:
        from upm.motion.skeleton import POSTURE_DOF_NAMES

        if args.plot_dof not in POSTURE_DOF_NAMES:
            raise UsageError(f"--plot-dof {args.plot_dof}: not a posture DOF (JOINT.rx/ry/rz, "
                             f"e.g. rhumerus.rz)")
    catalog = Catalog(args.data)
    source_ref = _single_frame(args.source, "--from")
    target_ref = _single_frame(args.target, "--to")
    before, a_frame = _clip_window(catalog, source_ref, "from", args.context)
    after, b_frame = _clip_window(catalog, target_ref, "to", args.context)
    key_source = key_source_for(args.method, args.map, catalog, args.follow, performer_config)
    result = transition(args.method, before, after, args.frames, args.alpha, key_source,
                        align_heading=args.align_heading)
    write_motion(args.out, result.motion)
    report = window_report(result, result.motion.fps)
    report.update({"from": f"{source_ref.name}@{a_frame}", "to": f"{target_ref.name}@{b_frame}",
                   "out": str(args.out), "out_frames": result.motion.n_frames,
                   "asf": str(catalog.info(source_ref.name).asf_path)})
    if args.method == "performed":
        report["follow"] = key_source.follow.name
    if args.json:
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    if args.plot:
        from upm.transitions.dof_plot import plot_window_dof

        linear = result if args.method == "linear" else transition(
            "linear", before, after, args.frames, args.alpha, align_heading=args.align_heading)
        plot_window_dof(args.plot, {args.method: result, "linear": linear}, dof=args.plot_dof,
                        title=f"{report['from']} -> {report['to']}")
    w = result.window
    print(f"{args.method}: {report['from']} -> {report['to']}, {result.frames} frames at "
          f"{result.motion.fps:g} fps, alpha {result.alpha:g}, heading turn "
          f"{result.heading_turn_deg:+.1f} deg")
    print(f"wrote {args.out}: {result.motion.n_frames} frames (ASF {report['asf']}); window = "
          f"frames {w.start}-{w.stop - 1} (0-based; AMC frame numbers {w.start + 1}-{w.stop})")
    print(f"transition computed in {1e3 * result.seconds:.2f} ms")
    if args.method == "performed":
        print(performed_line(result.diagnostics, key_source.follow.name))
    return 0


def performed_line(diagnostics, follow: str) -> str:
    """How the humanoid performed the window, in one line (a fall is a finding)."""
    d = diagnostics
    line = (f"performed (following {follow}): joint error {d['performed_joint_error_deg']:.1f} "
            f"deg RMS, body error {d['performed_body_error_mm']:.0f} mm mean against the "
            f"asked window; torque at its limit {100 * d['performed_torque_saturation_share']:.1f}"
            f" % of the time; joins {d['performed_join_step_start_deg']:.1f} deg into the run "
            f"({d['performed_context_before_s']:.2f} s before the window), "
            f"{d['performed_join_step_end_deg']:.1f} deg out of it "
            f"({d['performed_context_after_s']:.2f} s after)")
    if d["performed_fell"]:
        line += ("; the body FELL" + (" in the window" if d["performed_fell_in_window"]
                                      else " after the window")
                 + ": it cannot perform this window as asked (a finding)")
    elif d["performed_left_window"]:
        line += "; it had to leave the asked window to stay up"
    return line
