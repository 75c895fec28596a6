"""Convert a motion between AMC and BVH.

IN is a clip of the data directory (02_01, 02_01@0:200), an .amc file with its
--skeleton ASF, or a .bvh file; OUT ends in .amc or .bvh.

  - clip / AMC -> BVH: the motion on its ASF skeleton as BVH: one joint per ASF bone (its
    ASF name), the ASF rest pose, y up, centimetres, Z Y X rotation channels; the root
    adds X Y Z positions (y up, as Blender's BVH import assumes by default).
  - BVH -> AMC (or BVH on the ASF), with --skeleton: a BVH written by upm on that ASF,
    or a take in the CMU 31-joint naming (Hips, LHipJoint, LeftUpLeg, ...: the cgspeed
    conversions), whose added T-pose first frame is detected and dropped (--keep-first
    keeps it); when the file is named after a clip of the data directory, its frame rate
    comes from clips.csv (subject 141's conversions say 120 fps for 60 fps takes).
    Other skeletons (DAZ-style, Mixamo) need a world-direction retarget that upm does not
    do yet: they are refused with a message.
  - BVH -> BVH: re-written as read (any hierarchy; --fps changes the frame time).
  - AMC -> AMC: re-written (e.g. a clip range as its own file).

Examples:
  upm convert 02_01 walk.bvh
  upm convert 02_01@100:300 part.amc
  upm convert walk.bvh walk.amc --skeleton 02.asf
  upm convert take.amc take.bvh --skeleton 05.asf --fps 120
"""

from __future__ import annotations

HELP = "convert a motion between AMC and BVH (a clip, an .amc with its ASF, or a .bvh)"


def configure(parser) -> None:
    from upm.commands.common import add_data_argument

    add_data_argument(parser)
    parser.add_argument("source", metavar="IN", help="a clip (CLIP, CLIP@A:B), an .amc "
                        "file (with --skeleton) or a .bvh file")
    parser.add_argument("out", metavar="OUT", help="the file to write: .amc or .bvh")
    parser.add_argument("--skeleton", metavar="ASF", default=None,
                        help="the ASF of an .amc input, or the ASF a .bvh was written on "
                             "(for BVH -> AMC)")
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of an .amc input (default 120) or of the output")
    parser.add_argument("--keep-first", action="store_true",
                        help="keep a CMU BVH's first frame even when it looks like an "
                             "added T-pose")


def run(args) -> int:
    from pathlib import Path

    from upm.errors import UsageError
    from upm.motion_io import check_motion_path, write_motion

    check_motion_path(args.out, "OUT")
    if args.fps is not None and not 0 < args.fps <= 10000:
        raise UsageError(f"--fps must be in (0, 10000], not {args.fps:g}")
    source = Path(args.source)
    suffix = source.suffix.lower()
    out_bvh = Path(args.out).suffix.lower() == ".bvh"
    if suffix in (".amc", ".bvh") and not source.is_file():
        raise UsageError(f"{source}: no such file")
    if suffix == ".bvh":
        from dataclasses import replace

        from upm.bvh import motion_from_bvh, read_bvh, write_bvh

        bvh = read_bvh(source)
        if args.fps:
            bvh = replace(bvh, frame_time_s=1.0 / args.fps)
        if out_bvh:
            if args.skeleton:
                raise UsageError("--skeleton goes with BVH -> AMC, not BVH -> BVH")
            write_bvh(args.out, bvh)
            print(f"wrote {args.out}: {bvh.n_frames} frames, {bvh.skeleton.n_joints} joints")
            return 0
        if not args.skeleton:
            raise UsageError(f"{source} -> AMC needs the ASF to put it on: --skeleton")
        from upm.asf import read_asf

        skeleton = read_asf(args.skeleton)
        if tuple(bvh.skeleton.names) == tuple(skeleton.bone_names):
            motion = motion_from_bvh(bvh, skeleton, name=source.stem)
        else:
            import sys

            from upm.bvh.retarget import CMU_31, retarget_cmu

            if not set(CMU_31) <= set(bvh.skeleton.names):
                motion_from_bvh(bvh, skeleton)  # the one-line refusal naming the file
            fps = args.fps or _catalog_fps(args.data, source.stem)
            if fps and abs(fps - bvh.fps) > 1e-3 * fps:
                print(f"upm convert: {source.name}: {fps:g} fps from clips.csv (the file "
                      f"says {bvh.fps:g})", file=sys.stderr)
            motion = retarget_cmu(bvh, skeleton, fps=fps,
                                  drop_tpose=False if args.keep_first else None,
                                  name=source.stem)
    elif suffix == ".amc":
        if not args.skeleton:
            raise UsageError(f"{source}: an AMC file needs its skeleton: --skeleton ASF")
        from upm.amc import read_amc
        from upm.asf import read_asf

        motion = read_amc(source, read_asf(args.skeleton), fps=args.fps or 120.0,
                          name=source.stem)
    elif suffix:
        raise UsageError(f"{source}: give a clip, an .amc or a .bvh file")
    else:
        if args.skeleton:
            raise UsageError("--skeleton goes with an .amc or .bvh input, not a clip")
        from upm.catalog import Catalog, parse_clip_ref

        catalog = Catalog(args.data)
        motion = catalog.load_ref(parse_clip_ref(args.source))
        if args.fps:
            from upm.resample import resample

            motion = resample(motion, args.fps)
    write_motion(args.out, motion)
    print(f"wrote {args.out}: {motion.n_frames} frames at {motion.fps:g} fps "
          f"(ASF {Path(motion.skeleton.source).name})")
    return 0


def _catalog_fps(data, stem: str) -> float | None:
    """The frame rate clips.csv gives a clip named ``stem`` (None if there is none)."""
    from upm.catalog import Catalog
    from upm.errors import UpmError

    try:
        catalog = Catalog(data)
        return float(catalog.info(stem).fps)
    except (UpmError, KeyError, OSError):
        return None
