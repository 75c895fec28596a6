"""List the clips of a data directory: subject, frames, duration, frame rate, split,
description, and the share of angle samples outside the ASF's own joint limits.

Real motion capture leaves its ASF limits: over every declared DOF (the column
'out%'), 3-14 % of the CMU samples here lie outside them after wrapping to [-180, 180);
'pose_out%' counts only the 45 declared DOFs of the 21-joint posture. This is the first
calibration figure of the project: a transition method can only be judged against it.

BVH files found in the data directory or a ``bvh`` directory beside it are listed after
the clips: frames, the file's frame rate, joints, which reading ``upm convert`` applies
(``upm``: written by upm on ASF bones; ``cmu31``: the CMU 31-joint naming; ``daz43``,
``mixamo``, ``body19``: a built-in joint map; ``unmapped``: needs ``--map``), whether
frame 0 is an added rest pose, and the clip the file is named after with that clip's
rate (which ``upm convert`` uses).
"""

from __future__ import annotations

from upm.commands.common import add_data_argument, format_table, print_json

HELP = "list the clips of a data directory, with their out-of-limit share"


def configure(parser) -> None:
    add_data_argument(parser)
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    parser.add_argument("--split", choices=["train", "test"], default=None,
                        help="only the clips of this split of clips.csv")


def clip_rows(catalog, names) -> list[dict]:
    """One row per clip: the catalogue fields and the out-of-limit shares."""
    from upm.core.progress import progress
    from upm.motion.limits import outside_share

    rows = []
    for name in progress(names, desc="reading clips", unit="clip"):
        info = catalog.info(name)
        motion = catalog.load(name)
        share_all, share_posture = outside_share(motion)
        rows.append({
            "clip": name,
            "subject": info.subject,
            "frames": motion.n_frames,
            "seconds": round(motion.duration_s, 3),
            "fps": info.fps,
            "split": info.split,
            "description": info.description,
            "outside_limits_pct": round(100 * share_all, 2),
            "posture_outside_limits_pct": round(100 * share_posture, 2),
        })
    return rows


def bvh_rows(catalog) -> list[dict]:
    """One row per BVH file of the data directory (:mod:`upm.bvh.listing`)."""
    from upm.bvh.listing import bvh_files, bvh_row

    names = catalog.names()
    rows = []
    for path in bvh_files(catalog.root):
        row = bvh_row(path, names, catalog.root)
        row["clip_fps"] = catalog.info(row["clip"]).fps if row["clip"] else None
        rows.append(row)
    return rows


def run(args) -> int:
    from upm.motion.catalog import Catalog

    catalog = Catalog(args.data)
    rows = clip_rows(catalog, catalog.names(args.split))
    bvh = bvh_rows(catalog)
    if args.json:
        print_json({"data": str(catalog.root), "clips": rows, "bvh": bvh})
        return 0
    for row in rows:
        row["description"] = row["description"][:44]
    print(format_table(rows, [
        ("clip", "clip", "<"), ("subject", "subj", "<"), ("frames", "frames", ">d"),
        ("seconds", "seconds", ">.1f"), ("fps", "fps", ">g"), ("split", "split", "<"),
        ("outside_limits_pct", "out%", ">.1f"), ("posture_outside_limits_pct", "pose_out%", ">.1f"),
        ("description", "description", "<"),
    ]))
    total = sum(r["frames"] for r in rows)
    print(f"\n{len(rows)} clips, {total} frames, from {catalog.root}")
    if bvh:
        for row in bvh:
            row["rest"] = "frame 0" if row["rest_frame"] else "-"
            row["clip_fps"] = "-" if row["clip_fps"] is None else format(row["clip_fps"], "g")
            row["clip"] = row["clip"] or "-"
            row["problem"] = row["problem"][:60]
        print()
        columns = [
            ("file", "bvh file", "<"), ("frames", "frames", ">d"), ("fps", "fps", ">g"),
            ("joints", "joints", ">d"), ("figure", "figure", "<"), ("rest", "rest pose", "<"),
            ("clip", "clip", "<"), ("clip_fps", "clip fps", ">"),
        ]
        if any(row["problem"] for row in bvh):
            columns.append(("problem", "problem", "<"))
        print(format_table(bvh, columns))
        print(f"\n{len(bvh)} BVH files")
    return 0
