"""Join clips with transitions, drive the MuJoCo humanoid with the sequence, and report
how physically valid it is, frame by frame and window by window.

The sequence (--sequence CLIP@A:B CLIP@A:B ...) is built as by 'upm sequence': a
transition of --frames new frames by --method joins each consecutive pair (upm and som
need --map). The humanoid of the first piece's subject then

  - is checked per frame: joint limits (and, in windows, the excess beyond what the
    window's two end postures already have), self-collision, floor penetration;
  - needs an external force beyond what floor contact can supply (inverse dynamics, in
    body weights): the "hand of god" the motion asks for;
  - follows it with its position servos, root driven along the sequence ("driven") and
    root free on the floor ("free"): joint tracking error, joint-limit activity,
    self-contacts, and whether and when it falls; plus, per window, a free-root run from
    0.5 s before the window to 0.5 s after it.

--report writes the JSON report (per frame, per window, per piece, totals) and a CSV
summary beside it. --video renders offscreen (no GPU needed: OSMesa) an .mp4, a .gif, or
a .png filmstrip of the whole sequence; --filmstrip a PNG of the frames around each
window; --viewer plays it in MuJoCo's viewer where there is a display.

Example:
  upm simulate --map upm.npz --sequence 02_01@0:200 02_03@20:150 --report r.json --video r.mp4
"""

from __future__ import annotations

HELP = "drive the humanoid with clips joined by transitions; report physical validity"

RENDER_CHOICES = ("driven", "free", "reference")


def configure(parser) -> None:
    from upm.commands.common import add_data_argument
    from upm.commands.transition import add_method_arguments

    add_data_argument(parser)
    parser.add_argument("--sequence", nargs="+", required=True, metavar="CLIP@A:B",
                        help="the pieces, in order (CLIP, CLIP@A:B frames A to B-1, CLIP@F)")
    add_method_arguments(parser)
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of the sequence (default: the first piece's)")
    parser.add_argument("--report", required=True, metavar="R.json",
                        help="the JSON report to write (and a CSV summary, R.csv)")
    parser.add_argument("--modes", nargs="+", choices=["driven", "free"],
                        default=["driven", "free"],
                        help="tracking simulations to run (default: both)")
    parser.add_argument("--no-window-runs", dest="window_runs", action="store_false",
                        help="skip the free-root run around each window")
    parser.add_argument("--video", metavar="V.mp4", default=None,
                        help="render offscreen: .mp4, .gif, or .png (a filmstrip)")
    parser.add_argument("--render", choices=RENDER_CHOICES, default=None,
                        help="what --video and --viewer show (default: the first of "
                             "--modes; 'reference' is the sequence itself, unsimulated)")
    parser.add_argument("--filmstrip", metavar="F.png", default=None,
                        help="a PNG of every 5th frame around each window: the sequence "
                             "itself above, the simulation below (the paper's Fig. 11/12)")
    parser.add_argument("--viewer", action="store_true",
                        help="play it in MuJoCo's interactive viewer (needs a display)")


def run(args) -> int:
    import warnings

    from controller.analysis import analyse
    from controller.qpos import to_qpos
    from controller.render import (
        VIDEO_SUFFIXES,
        filmstrip,
        filmstrip_frames,
        has_display,
        play_in_viewer,
        write_video,
    )
    from controller.report import write_report
    from humanoid_xml import catalog_model_path, load_model
    from upm.commands.transition import sequence_from_args
    from upm.errors import UsageError

    render = args.render or args.modes[0]
    if render != "reference" and render not in args.modes:
        raise UsageError(f"--render {render} needs that simulation: add it to --modes")
    if args.video and not args.video.lower().endswith(VIDEO_SUFFIXES):
        raise UsageError(f"--video {args.video}: use a name ending in "
                         f"{', '.join(VIDEO_SUFFIXES)}")
    if args.filmstrip and not args.filmstrip.lower().endswith(".png"):
        raise UsageError(f"--filmstrip {args.filmstrip}: use a name ending in .png")
    if args.viewer and not has_display():
        raise UsageError("--viewer needs a display (DISPLAY is not set); use --video V.mp4 "
                         "to render offscreen instead")
    catalog, refs, sequence = sequence_from_args(args, args.sequence)
    motion = sequence.motion
    if motion.n_frames < 2:
        raise UsageError("the sequence has fewer than 2 frames: nothing to simulate")
    model_path = catalog_model_path(catalog, refs[0].name)
    model = load_model(model_path)
    window_meta = [{"method": sequence.method, "from": str(refs[k]), "to": str(refs[k + 1]),
                    "compute_s": sequence.seconds[k]} for k in range(len(sequence.windows))]
    report, results = analyse(
        model, motion, kind="simulate", windows=sequence.windows, window_meta=window_meta,
        pieces=[(str(ref), part) for ref, part in zip(refs, sequence.pieces, strict=True)],
        tracking_modes=tuple(args.modes), window_free=args.window_runs,
        model_path=model_path)
    report["sequence"] = {"pieces": [str(r) for r in refs], "method": sequence.method,
                          "frames": sequence.frames, "alpha": args.alpha,
                          "map": args.map, "align_heading": args.align_heading}
    json_path, csv_path = write_report(report, args.report)

    for mode, run_ in results["tracking"].items():
        if run_.diverged_frame is not None or run_.warnings:
            warnings.warn(f"{mode} simulation: MuJoCo warnings {run_.warnings}"
                          + (f", stopped at frame {run_.diverged_frame}"
                             if run_.diverged_frame is not None else ""), stacklevel=1)
    _print_summary(report, json_path, csv_path)

    trajectory = (to_qpos(model, motion) if render == "reference"
                  else results["tracking"][render].qpos)
    if args.video:
        path = write_video(model, trajectory, motion.fps, args.video,
                           windows=sequence.windows)
        print(f"video ({render}): {path}")
    if args.filmstrip:
        rows = [("sequence", to_qpos(model, motion))]
        if render != "reference":
            rows.append((f"simulated ({render})", trajectory))
        path = filmstrip(model, rows, filmstrip_frames(sequence.windows, motion.n_frames),
                         args.filmstrip, fps=motion.fps, windows=sequence.windows,
                         title=f"{motion.name}: {sequence.method}, "
                               f"{sequence.frames}-frame windows")
        print(f"filmstrip: {path}")
    if args.viewer:
        play_in_viewer(model, trajectory, motion.fps)
    return 0


def _print_summary(report: dict, json_path, csv_path) -> None:
    m = report["motion"]
    seq = report["sequence"]
    print(f"{m['name']}: {m['frames']} frames at {m['fps']:g} fps, method {seq['method']}, "
          f"{seq['frames']}-frame windows, on a {m['mass_kg']:.1f} kg humanoid")
    rows = [("all", report["totals"])]
    rows += [(f"window {w['index']} ({w['start']}-{w['stop'] - 1})", w)
             for w in report["windows"]]
    for label, part in rows:
        k = part["kinematic"]
        line = (f"  {label:<24} valid {k['valid_pct']:5.1f} %  limit "
                f"{k['limit_violation_pct']:5.1f} %  self {k['self_collision_pct']:5.1f} %  "
                f"floor {k['floor_penetration_pct']:5.1f} %")
        if "added_excess_peak_deg" in k and label != "all":
            line += f"  added excess peak {k['added_excess_peak_deg']:.2f} deg"
        if "dynamics" in part:
            line += f"  residual {part['dynamics']['residual_force_bw_mean']:.3f} bw"
        tracking = part.get("tracking", {})
        if "driven" in tracking and tracking["driven"].get("error_deg_rms") is not None:
            line += f"  driven error {tracking['driven']['error_deg_rms']:.2f} deg"
        if "free_window" in tracking:
            line += "  free run: " + ("falls" if tracking["free_window"]["fell"] else "stands")
        print(line)
    free = report["totals"].get("tracking", {}).get("free")
    if free is not None:
        print("  free root: " + (f"falls at {free['fall_time_s']:.2f} s" if free["fell"]
                                 else "does not fall"))
    print(f"report: {json_path} (summary {csv_path})")
