"""Join a sequence of clip pieces into one continuous motion and write it as an AMC or a BVH.

Each piece is CLIP (the whole clip), CLIP@A:B (frames A to B-1, 0-based) or CLIP@F (one
frame, a held pose); a transition of --frames new frames joins each consecutive pair.
Pieces of different frame rates are resampled to the first piece's (or --fps); pieces of
different subjects are allowed: postures are joint angles, and the result uses the first
piece's skeleton, with each later piece's root translation scaled by the ratio of leg
lengths. With --cut matched each piece but the last ends where the next one's first frame
finds it at the same phase of the stride (the feet's positions and velocities relative
to the pelvis), so that a walk joins a walk in step (02_01 -> 02_02: the window's fastest
ankle 3.2 m/s instead of 5.2); the pieces used are printed and reported as CLIP@A:B.

Examples:
  upm sequence 02_01@0:200 02_03@20:150 05_01@100:400 --method classnn --out seq.amc
  upm sequence 02_01 02_02 02_01 02_02 --method linear --cut matched --out walks.amc
"""

from __future__ import annotations

HELP = "join clips (CLIP@A:B ...) with transitions into one AMC or BVH"


def configure(parser) -> None:
    from upm.commands.common import add_data_argument, add_performed_config_argument
    from upm.commands.transition import add_cut_argument, add_method_arguments

    add_data_argument(parser)
    parser.add_argument("pieces", nargs="+", metavar="CLIP@A:B",
                        help="the pieces, in order (at least two)")
    add_method_arguments(parser)
    add_cut_argument(parser)
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of the result (default: the first piece's)")
    parser.add_argument("--out", required=True, metavar="OUT.amc|OUT.bvh",
                        help="the motion to write: AMC, or BVH (centimetres, y up) by the "
                             "extension")
    parser.add_argument("--json", metavar="FILE.json", default=None,
                        help="also write where each piece and window lies, and the timing "
                             "(with --method performed, how the humanoid performed each)")
    add_performed_config_argument(parser)


def run(args) -> int:
    import json

    from upm.bvh.formats import check_motion_path, write_motion
    from upm.commands.common import performed_setup
    from upm.commands.transition import sequence_from_args
    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_write_text

    check_motion_path(args.out)
    performed_setup(args)

    if len(args.pieces) < 2:
        raise UsageError("a sequence needs at least two pieces (CLIP@A:B CLIP@A:B ...)")
    catalog, refs, sequence = sequence_from_args(args, args.pieces)
    write_motion(args.out, sequence.motion)
    motion = sequence.motion
    report = {
        "method": sequence.method, "frames": sequence.frames, "alpha": args.alpha,
        "fps": motion.fps, "out": str(args.out), "out_frames": motion.n_frames,
        "asf": str(catalog.info(refs[0].name).asf_path),
        "pieces": [{"clip": str(ref), "first_frame": s.start, "stop_frame": s.stop}
                   for ref, s in zip(refs, sequence.pieces, strict=True)],
        "windows": [{"first_frame": w.start, "stop_frame": w.stop, "seconds": sec}
                    for w, sec in zip(sequence.windows, sequence.seconds, strict=True)],
    }
    if sequence.method == "performed":
        for window, figures in zip(report["windows"], sequence.diagnostics, strict=True):
            window["performed"] = {k.removeprefix("performed_"): v for k, v in figures.items()
                                   if k.startswith("performed_")}
    if args.json:
        atomic_write_text(args.json, json.dumps(report, indent=2) + "\n")
    print(f"wrote {args.out}: {motion.n_frames} frames at {motion.fps:g} fps "
          f"(ASF {report['asf']}), method {sequence.method}, {sequence.frames}-frame windows")
    for piece in report["pieces"]:
        print(f"  {piece['clip']:<18} frames {piece['first_frame']}-{piece['stop_frame'] - 1}")
    for i, window in enumerate(report["windows"], start=1):
        print(f"  window {i:<11} frames {window['first_frame']}-{window['stop_frame'] - 1}"
              f"  ({1e3 * window['seconds']:.2f} ms)")
        if sequence.method == "performed":
            from upm.commands.transition import performed_line

            print("    " + performed_line(sequence.diagnostics[i - 1], args.follow or "feasible"))
    print("(frame numbers 0-based; AMC frame numbers are one more)")
    return 0
