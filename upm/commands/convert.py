"""Convert a motion between AMC and BVH.

IN is a clip of the data directory (02_01, 02_01@0:200), an .amc file with its
--skeleton ASF, or a .bvh file; OUT ends in .amc or .bvh.

  - clip / AMC -> BVH: the motion on its ASF skeleton as BVH: one joint per ASF bone (its
    ASF name), the ASF rest pose, y up, centimetres, Z Y X rotation channels; the root
    adds X Y Z positions (y up, as Blender's BVH import assumes by default).
  - BVH -> AMC: onto --skeleton ASF; without it, onto the subject of the clip the file
    is named after (141_01.bvh, 05_11_daz.bvh -> 05_11: the clip name, alone or followed
    by '_' or '-') when the data directory has it, else onto the generic adult. Then:
      * a BVH written by upm on that ASF converts back exactly;
      * the CMU 31-joint naming (Hips, LHipJoint, LeftUpLeg, ...: cgspeed's conversions)
        keeps the ASF's rest pose: rotations carried exactly;
      * any other figure is retargeted by world direction: each posture bone points where
        its BVH segment points (solved in the ASF's axis frames and declared DOFs; twist
        from the knee/elbow bend plane, else the segment's own rotation), the root on the
        BVH's hip centre scaled by leg length. Built-in joint maps: the DAZ-style 43-joint
        figure (hip, abdomen, lThigh, ...), Mixamo (mixamorig:Hips, ...) and the 19-joint
        Hips/Chest/LeftHip/LeftKnee figure; --map JOINTS.json for anything else.
    An added rest/T-pose first frame (cgspeed's and the DAZ-style conversions) is detected
    and dropped by default; --keep-first keeps frame 0 whatever it is. When the file is
    named after a clip, the frame rate comes from clips.csv (subject 141's conversions say
    120 fps for 60 fps takes); --fps overrides both.
  - BVH -> BVH: re-written as read (any hierarchy; --fps changes the frame time).
  - AMC -> AMC: re-written (e.g. a clip range as its own file).

Examples:
  upm convert 02_01 walk.bvh
  upm convert 02_01@100:300 part.amc
  upm convert walk.bvh walk.amc --skeleton 02.asf
  upm convert take.amc take.bvh --skeleton 05.asf --fps 120
  upm convert 05_11_daz.bvh 05_11.amc --skeleton 05.asf
  upm convert dance.bvh dance.amc --map dance_joints.json

JOINTS.json (a joint map) names, for the ASF root and each of the 21 posture joints, its
counterpart in the BVH:
  {"root": "Hips",
   "bones": {"lfemur": ["LeftUpLeg", "LeftLeg"],   bone points from joint to joint
             "lfoot": ["LeftFoot", "End Site"],    ... or to the joint's end site
             "head": ["Head"],                     turns as this joint turns from rest
             "ltoes": null,                        no counterpart: kept at rest
             ...}}
Keys of "bones" are the posture joints (lclavicle rclavicle thorax upperback lowerback
lowerneck lhumerus rhumerus lfemur rfemur head ltibia rtibia lradius rradius lfoot rfoot
ltoes rtoes lhand rhand); thorax and the four limbs (femur, tibia, humerus, radius, both
sides) are required; a joint left out is kept at rest.
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
                        help="the ASF of an .amc input, or the ASF to put a .bvh on (BVH -> "
                             "AMC; default: the subject of the clip the file is named "
                             "after, else the generic adult)")
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of an .amc input (default 120) or of the output")
    parser.add_argument("--keep-first", action="store_true",
                        help="keep a BVH's first frame even when it looks like an added "
                             "T-pose (default: detected and dropped)")
    parser.add_argument("--map", metavar="JOINTS.json", default=None,
                        help="joint map of a BVH figure upm has no built-in map for (format "
                             "above)")


def run(args) -> int:
    from pathlib import Path

    from upm.bvh.formats import check_motion_path, write_motion
    from upm.core.errors import UsageError

    check_motion_path(args.out, "OUT")
    if args.fps is not None and not 0 < args.fps <= 10000:
        raise UsageError(f"--fps must be in (0, 10000], not {args.fps:g}")
    source = Path(args.source)
    suffix = source.suffix.lower()
    out_bvh = Path(args.out).suffix.lower() == ".bvh"
    if suffix in (".amc", ".bvh") and not source.is_file():
        raise UsageError(f"{source}: no such file")
    if args.map and suffix != ".bvh":
        raise UsageError("--map goes with a .bvh input")
    if suffix == ".bvh":
        from dataclasses import replace

        from upm.bvh import read_bvh, write_bvh

        bvh = read_bvh(source)
        if args.fps:
            bvh = replace(bvh, frame_time_s=1.0 / args.fps)
        if out_bvh:
            if args.skeleton or args.map:
                raise UsageError("--skeleton and --map go with BVH -> AMC, not BVH -> BVH")
            write_bvh(args.out, bvh)
            print(f"wrote {args.out}: {bvh.n_frames} frames, {bvh.skeleton.n_joints} joints")
            return 0
        motion = motion_of_bvh(args, bvh, source)
    elif suffix == ".amc":
        if not args.skeleton:
            raise UsageError(f"{source}: an AMC file needs its skeleton: --skeleton ASF")
        from upm.motion.amc import read_amc
        from upm.motion.asf import read_asf

        motion = read_amc(source, read_asf(args.skeleton), fps=args.fps or 120.0,
                          name=source.stem)
    elif suffix:
        raise UsageError(f"{source}: give a clip, an .amc or a .bvh file")
    else:
        if args.skeleton:
            raise UsageError("--skeleton goes with an .amc or .bvh input, not a clip")
        from upm.motion.catalog import Catalog, parse_clip_ref

        catalog = Catalog(args.data)
        motion = catalog.load_ref(parse_clip_ref(args.source))
        if args.fps:
            from upm.motion.resample import resample

            motion = resample(motion, args.fps)
    write_motion(args.out, motion)
    print(f"wrote {args.out}: {motion.n_frames} frames at {motion.fps:g} fps "
          f"(ASF {Path(motion.skeleton.source).name})")
    return 0


def motion_of_bvh(args, bvh, source):
    """A BVH onto an ASF skeleton as a Motion (see the module docstring for the rules)."""
    import sys

    from upm.bvh import motion_from_bvh
    from upm.bvh.retarget import CMU_31, retarget_cmu

    clip = clip_named(args.data, source.stem)
    if args.skeleton:
        from upm.motion.asf import read_asf

        skeleton = read_asf(args.skeleton)
    elif clip is not None:
        skeleton = clip[0].skeleton(clip[1].subject)
    else:
        from humanoid_xml import generic_skeleton

        skeleton = generic_skeleton()
    fps = args.fps or (float(clip[1].fps) if clip else None)
    if not args.fps and fps and abs(fps - bvh.fps) > 1e-3 * fps:
        print(f"upm convert: {source.name}: {fps:g} fps from clips.csv ({clip[1].name}; "
              f"the file says {bvh.fps:g})", file=sys.stderr)
    names = set(bvh.skeleton.names)
    if not args.map and tuple(bvh.skeleton.names) == tuple(skeleton.bone_names):
        return motion_from_bvh(bvh, skeleton, fps=fps, name=source.stem)
    if not args.map and set(CMU_31) <= names:
        return retarget_cmu(bvh, skeleton, fps=fps,
                            drop_tpose=False if args.keep_first else None, name=source.stem)
    from upm.bvh.joint_maps import find_builtin_map, read_joint_map
    from upm.bvh.world_retarget import retarget_world

    joint_map = read_joint_map(args.map) if args.map else find_builtin_map(bvh)
    return retarget_world(bvh, skeleton, joint_map, fps=fps,
                          drop_first=False if args.keep_first else None, name=source.stem)


def clip_named(data, stem: str):
    """``(catalog, clip info)`` of the clip a BVH file is named after: its stem is the
    clip's name, or starts with it followed by ``_`` or ``-`` (the longest such name);
    None when there is no such clip or no readable data directory."""
    from upm.core.errors import UpmError
    from upm.motion.catalog import Catalog

    try:
        catalog = Catalog(data)
        names = catalog.names()
    except (UpmError, OSError):
        return None
    fits = [n for n in names if stem == n or stem.startswith((n + "_", n + "-"))]
    if not fits:
        return None
    return catalog, catalog.info(max(fits, key=len))
