"""Check a motion for physical validity on the MuJoCo humanoid of its skeleton.

Per frame: beyond the human range of motion (degrees beyond each anatomical rule; the
hips and shoulders coupled; --limits asf judges by the ASF's declared boxes instead, and
the degrees beyond those are always reported as 'asf%'), self-interpenetration (a
contact deeper than the soft tissue of that body pair allows: touching is allowed), and
through the floor (deeper than the body class allows: a heel pad may roll on the floor);
a frame is valid when it has none of the three. 'upm calibrate' measures how often real
frames pass and impossible ones fail. Per motion, unless --no-dynamics: the
external force and torque the motion needs beyond what floor contact can supply (inverse
dynamics, in body weights and body weight x stature).

Give the motion as

  MOTION.amc --asf SKEL.asf [--fps 120]   an AMC file and its skeleton
  MOTION.bvh [--asf SKEL.asf] [--fps F]   a BVH file, read as 'upm convert' reads it: onto
                                          --asf, else onto the subject of the clip it is
                                          named after, else onto the generic adult
  CLIP or CLIP@A:B                        a clip (frames A to B-1) under --data
  --split train|test|all                  every clip of a split: the calibration table

One motion prints its totals and its invalid frames (--json: the full report on stdout;
--report R.json also writes it, with a CSV summary R.csv). Several motions print one row
each and the totals: real motion capture is the calibration for every validity figure.
"""

from __future__ import annotations

from upm.commands.common import add_data_argument, add_limits_argument, format_table, print_json

HELP = "physical validity of a motion: joint limits, self-collision, floor, dynamics"


def configure(parser) -> None:
    parser.add_argument("motions", nargs="*", metavar="MOTION",
                        help="an AMC file (with --asf), a BVH file, or clips such as 02_01 "
                             "or 02_01@0:120")
    parser.add_argument("--asf", metavar="SKEL.asf", default=None,
                        help="the skeleton of an AMC file, or the one to put a BVH on")
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of an AMC file (default 120; clips use clips.csv)")
    parser.add_argument("--split", choices=["train", "test", "all"], default=None,
                        help="check every clip of a split of clips.csv (calibration)")
    add_data_argument(parser)
    add_limits_argument(parser)
    parser.add_argument("--no-dynamics", action="store_true",
                        help="skip the inverse-dynamics residual")
    parser.add_argument("--json", action="store_true",
                        help="print the JSON report (or the calibration) instead of text")
    parser.add_argument("--report", metavar="R.json", default=None,
                        help="write the JSON report and a CSV summary beside it")


def _motions(args):
    """[(motion, model_path, ClipInfo or None)] from the arguments."""
    from pathlib import Path

    from humanoid_xml import catalog_model_path, subject_model_path
    from upm.core.errors import UsageError

    if args.split and args.motions:
        raise UsageError("give motions or --split, not both")
    if not args.split and not args.motions:
        raise UsageError("give a motion (MOTION.amc --asf SKEL.asf, or a CLIP) or --split")
    bvh = [m for m in args.motions if m.lower().endswith(".bvh")]
    if bvh:
        return [_bvh_motion(args, bvh)]
    amc = [m for m in args.motions if m.lower().endswith(".amc")]
    if amc:
        if len(args.motions) != 1:
            raise UsageError("check one AMC file at a time")
        if not args.asf:
            raise UsageError(f"{amc[0]}: an AMC file needs its skeleton: --asf SKEL.asf")
        for path in (amc[0], args.asf):
            if not Path(path).is_file():
                raise UsageError(f"{path}: no such file")
        if args.fps is not None and not args.fps > 0:
            raise UsageError(f"--fps must be positive, not {args.fps:g}")
        from upm.motion.amc import read_amc
        from upm.motion.asf import read_asf

        skeleton = read_asf(args.asf)
        motion = read_amc(amc[0], skeleton, fps=args.fps or 120.0,
                          name=Path(amc[0]).stem)
        return [(motion, subject_model_path(args.asf), None)]
    for ref in args.motions:
        if Path(ref).suffix:
            raise UsageError(f"{ref}: not a motion upm check reads: give an .amc file "
                             "(with --asf SKEL.asf), a .bvh file or a clip such as 02_01")
    if args.asf or args.fps:
        raise UsageError("--asf and --fps go with an AMC file, not with clips")
    from upm.motion.catalog import Catalog, parse_clip_ref

    catalog = Catalog(args.data)
    if args.split:
        refs = catalog.names(None if args.split == "all" else args.split)
    else:
        refs = args.motions
    out = []
    for ref in refs:
        clip = parse_clip_ref(ref)
        motion = catalog.load_ref(clip)
        if clip.has_range or clip.start is not None:
            motion = motion.replace(name=str(clip))
        out.append((motion, catalog_model_path(catalog, clip.name), catalog.info(clip.name)))
    return out


def _bvh_motion(args, files):
    """(motion, model_path, None) of one BVH file, read onto an ASF as upm convert does."""
    from pathlib import Path
    from types import SimpleNamespace

    from humanoid_xml import catalog_model_path, default_model_path, subject_model_path
    from upm.bvh import read_bvh
    from upm.commands.convert import clip_named, motion_of_bvh
    from upm.core.errors import UsageError

    if len(args.motions) != 1:
        raise UsageError("check one BVH file at a time")
    path = Path(files[0])
    if not path.is_file():
        raise UsageError(f"{path}: no such file")
    for given in [args.asf] if args.asf else []:
        if not Path(given).is_file():
            raise UsageError(f"{given}: no such file")
    if args.fps is not None and not 0 < args.fps <= 10000:
        raise UsageError(f"--fps must be in (0, 10000], not {args.fps:g}")
    options = SimpleNamespace(skeleton=args.asf, fps=args.fps, map=None, keep_first=False,
                              data=args.data)
    motion = motion_of_bvh(options, read_bvh(path), path)
    if args.asf:
        model_path = subject_model_path(args.asf)
    else:
        clip = clip_named(args.data, path.stem)
        model_path = (catalog_model_path(clip[0], clip[1].name) if clip is not None
                      else default_model_path())
    return motion, model_path, None


def run(args) -> int:
    from controller.analysis import analyse
    from controller.report import write_report
    from humanoid_xml import load_model
    from upm.core.progress import progress
    from upm.motion.range_models import range_model

    limits = range_model(args.limits)
    items = _motions(args)
    models = {}
    reports = []
    quiet = True if len(items) == 1 else None
    for motion, path, info in progress(items, desc="checking", unit="motion", disable=quiet):
        if path not in models:
            models[path] = load_model(path)
        report, _ = analyse(models[path], motion, dynamics=not args.no_dynamics,
                            model_path=path, limits=limits)
        if info is not None:
            report["motion"]["split"] = info.split
        reports.append(report)
    if len(reports) == 1:
        report = reports[0]
        if args.report:
            write_report(report, args.report)
        if args.json:
            print_json(report)
        else:
            _print_one(report)
        return 0
    calibration = _calibration(reports)
    if args.report:
        _write_calibration(calibration, args.report)
    if args.json:
        print_json(calibration)
    else:
        _print_table(calibration)
    return 0


def _calibration(reports) -> dict:
    from controller.analysis import settings
    from controller.report import SCHEMA_VERSION

    rows = []
    for r in reports:
        k = r["totals"]["kinematic"]
        row = {"clip": r["motion"]["name"], "split": r["motion"].get("split", ""),
               **{key: k[key] for key in (
                   "frames", "valid_pct", "limit_violation_pct", "limit_excess_mean_deg",
                   "limit_excess_peak_deg", "self_collision_pct", "floor_penetration_pct",
                   "beyond_asf_pct")}}
        if "dynamics" in r["totals"]:
            row["residual_force_bw_mean"] = r["totals"]["dynamics"]["residual_force_bw_mean"]
        rows.append(row)

    def totals(subset) -> dict:
        frames = sum(r["totals"]["kinematic"]["frames"] for r in subset)
        out = {"clips": len(subset), "frames": frames}
        for key in ("valid", "limit_violation", "self_collision", "floor_penetration",
                    "beyond_asf"):
            count = sum(r["totals"]["kinematic"][f"{key}_frames"] for r in subset)
            out[f"{key}_pct"] = round(100 * count / max(frames, 1), 2)
        out["limit_excess_mean_deg"] = round(sum(
            r["totals"]["kinematic"]["limit_excess_mean_deg"] * r["totals"]["kinematic"]["frames"]
            for r in subset) / max(frames, 1), 4)
        if all("dynamics" in r["totals"] for r in subset):
            out["residual_force_bw_mean"] = round(sum(
                r["totals"]["dynamics"]["residual_force_bw_mean"]
                * r["totals"]["kinematic"]["frames"] for r in subset) / max(frames, 1), 4)
        return out

    by_split = {}
    for split in ("train", "test"):
        subset = [r for r in reports if r["motion"].get("split") == split]
        if subset:
            by_split[split] = totals(subset)
    return {"schema": "upm-controller/calibration", "schema_version": SCHEMA_VERSION,
            "settings": settings(), "clips": rows, "totals": totals(reports),
            "splits": by_split}


def _write_calibration(calibration: dict, path) -> None:
    """The calibration as JSON at ``path`` and a CSV beside it (one row per clip, then one
    per total)."""
    import json
    from pathlib import Path

    from controller.report import csv_text
    from upm.core.fileio import atomic_write_text

    path = Path(path)
    atomic_write_text(path, json.dumps(calibration, indent=1) + "\n")
    rows = list(calibration["clips"])
    rows += [{"clip": f"total {name}", **{k: v for k, v in t.items() if k != "clips"}}
             for name, t in [("all", calibration["totals"]), *calibration["splits"].items()]]
    csv_path = path.with_suffix(".csv") if path.suffix != ".csv" else path.with_name(
        path.name + ".csv")
    atomic_write_text(csv_path, csv_text(rows))


def _print_table(calibration: dict) -> None:
    columns = [("clip", "clip", "<"), ("split", "split", "<"), ("frames", "frames", ">d"),
               ("valid_pct", "valid%", ">.1f"), ("limit_violation_pct", "limit%", ">.1f"),
               ("limit_excess_mean_deg", "excess_mean", ">.2f"),
               ("limit_excess_peak_deg", "excess_peak", ">.1f"),
               ("self_collision_pct", "self%", ">.1f"), ("floor_penetration_pct", "floor%", ">.1f"),
               ("beyond_asf_pct", "asf%", ">.1f")]
    rows = calibration["clips"]
    if rows and "residual_force_bw_mean" in rows[0]:
        columns.append(("residual_force_bw_mean", "resid_bw", ">.3f"))
    print(format_table(rows, columns))
    print()
    for name, t in [("all", calibration["totals"]), *calibration["splits"].items()]:
        line = (f"{name}: {t['clips']} clips, {t['frames']} frames: valid {t['valid_pct']:.1f} %, "
                f"limit violation {t['limit_violation_pct']:.1f} % (mean excess "
                f"{t['limit_excess_mean_deg']:.2f} deg), self-collision "
                f"{t['self_collision_pct']:.1f} %, floor {t['floor_penetration_pct']:.1f} %; "
                f"beyond the ASF's declared limits {t['beyond_asf_pct']:.1f} % (not judged)")
        if "residual_force_bw_mean" in t:
            line += f", residual force {t['residual_force_bw_mean']:.3f} bw"
        print(line)


def _print_one(report: dict) -> None:
    m = report["motion"]
    k = report["totals"]["kinematic"]
    print(f"{m['name']}: {m['frames']} frames at {m['fps']:g} fps on a {m['mass_kg']:.1f} kg, "
          f"{m['stature_m']:.2f} m humanoid ({m['skeleton']})")
    print(f"  valid frames          {k['valid_frames']:6d} ({k['valid_pct']:.1f} %)")
    beyond = [r["limit_excess_max_deg"] for r in report["frames"] if r["limit_violation"]]
    over_beyond = sum(beyond) / len(beyond) if beyond else 0.0
    print(f"  beyond the range      {k['limit_violation_frames']:6d} "
          f"({k['limit_violation_pct']:.1f} %), largest excess per frame: mean "
          f"{over_beyond:.2f} deg over those frames ({k['limit_excess_mean_deg']:.2f} over "
          f"all), peak {k['limit_excess_peak_deg']:.2f} deg")
    print(f"  self-interpenetration {k['self_collision_frames']:6d} ({k['self_collision_pct']:.1f} "
          f"%), deepest {k['self_depth_peak_mm']:.1f} mm, {k['self_excess_peak_mm']:.1f} mm "
          f"beyond its allowance; touching only {k['self_touch_frames']} frames")
    print(f"  beyond the ASF limits {k['beyond_asf_frames']:6d} ({k['beyond_asf_pct']:.1f} %), "
          f"reported, not judged (verdict: --limits {k['limits']})")
    print(f"  floor penetration     {k['floor_penetration_frames']:6d} "
          f"({k['floor_penetration_pct']:.1f} %), deepest {k['floor_depth_peak_mm']:.1f} mm")
    if "dynamics" in report["totals"]:
        d = report["totals"]["dynamics"]
        print(f"  residual force        mean {d['residual_force_bw_mean']:.3f}, peak "
              f"{d['residual_force_bw_peak']:.3f} body weights; torque mean "
              f"{d['residual_torque_bwh_mean']:.3f}, peak {d['residual_torque_bwh_peak']:.3f} "
              "body weight x stature")
    records = report["frames"]
    rules = _peaks(records, "limit_dofs")
    if rules:
        print("\n  rule broken            frames  peak deg  at frame  mean deg (its frames)")
        for name, (count, peak, frame, mean) in rules.items():
            print(f"  {name:22s} {count:6d}  {peak:8.2f}  {frame:8d}  {mean:8.2f}")
    pairs = _peaks(records, "self_pairs")
    if pairs:
        print("\n  bodies interpenetrating  frames  deepest mm  at frame")
        for name, (count, peak, frame, _) in pairs.items():
            print(f"  {name:24s} {count:6d}  {peak:10.1f}  {frame:8d}")
    causes = (("beyond the range", "limit_violation"),
              ("self-interpenetration", "self_collision"),
              ("through the floor", "floor_penetration"))
    invalid = [r["frame"] for r in records if not r["valid"]]
    if invalid:
        print(f"\n  invalid frames: {len(invalid)}, by cause (a frame may have several):")
        for label, key in causes:
            frames = [r["frame"] for r in records if r[key]]
            if frames:
                print(f"    {label:22s} {len(frames):5d}: {_ranges(frames)}")


def _peaks(records: list[dict], key: str) -> dict[str, tuple[int, float, int, float]]:
    """Per name in the frame records' ``key`` dicts: (frames, peak, its frame, mean over
    those frames), most frames first."""
    seen: dict[str, list] = {}
    for r in records:
        for name, value in r[key].items():
            row = seen.setdefault(name, [0, -1.0, 0, 0.0])
            row[0] += 1
            row[3] += value
            if value > row[1]:
                row[1], row[2] = value, r["frame"]
    order = sorted(seen.items(), key=lambda kv: (-kv[1][0], kv[0]))
    return {name: (n, peak, frame, total / n) for name, (n, peak, frame, total) in order}


def _ranges(frames: list[int]) -> str:
    """``0-35, 40, 52-60``: every run of consecutive frames."""
    runs, start, prev = [], frames[0], frames[0]
    for f in frames[1:]:
        if f != prev + 1:
            runs.append((start, prev))
            start = f
        prev = f
    runs.append((start, prev))
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs)
