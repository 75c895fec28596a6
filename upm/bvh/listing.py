"""Finding and describing the BVH files of a data directory (for ``upm clips``)."""

from __future__ import annotations

from pathlib import Path

#: How deep below a searched directory .bvh files are looked for, and how many are listed.
MAX_DEPTH = 2
MAX_FILES = 1000


def bvh_files(data_root: str | Path) -> list[Path]:
    """The .bvh files in the data directory and in a ``bvh`` directory beside it (the
    shared layout keeps ``data/bvh`` next to ``data/cmu``), at most :data:`MAX_DEPTH`
    levels down, sorted, without duplicates."""
    root = Path(data_root)
    found = set()
    for top in (root, root.parent / "bvh"):
        if not top.is_dir():
            continue
        for depth in range(MAX_DEPTH + 1):
            pattern = "/".join(["*"] * depth + ["*.bvh"])
            found.update(p.resolve() for p in top.glob(pattern) if p.is_file())
            if len(found) > MAX_FILES:
                break
    return sorted(found)[:MAX_FILES]


def figure_of(bvh) -> str:
    """Which reading applies: ``"upm"`` (written by upm on ASF bones), ``"cmu31"`` (the CMU
    31-joint naming), a built-in joint map's name, or ``"unmapped"`` (needs ``--map``)."""
    from upm.bvh.joint_maps import builtin_maps
    from upm.bvh.retarget import CMU_31

    names = bvh.skeleton.names
    if names[:2] == ("root", "lhipjoint"):
        return "upm"
    if set(CMU_31) <= set(names):
        return "cmu31"
    for name, joint_map in builtin_maps().items():
        if not joint_map.missing_in(bvh.skeleton):
            return name
    return "unmapped"


def bvh_row(path: Path, clip_names, root: Path) -> dict:
    """One listing row: file, frames, fps, joints, figure, the clip it is named after
    (``""`` if none) and whether frame 0 is an added rest pose; a file that does not read
    gives its one-line error as ``problem``."""
    from upm.bvh.joint_maps import builtin_maps
    from upm.bvh.reader import read_bvh
    from upm.bvh.retarget import added_tpose
    from upm.bvh.world_retarget import added_rest_frame
    from upm.core.errors import UpmError

    try:
        shown = str(path.relative_to(root.parent.resolve()))
    except ValueError:
        shown = str(path)
    stem = path.stem
    fits = [n for n in clip_names if stem == n or stem.startswith((n + "_", n + "-"))]
    row = {"file": shown, "clip": max(fits, key=len) if fits else "", "frames": 0,
           "fps": 0.0, "joints": 0, "figure": "", "rest_frame": False, "problem": ""}
    try:
        bvh = read_bvh(path)
    except UpmError as exc:
        row["problem"] = str(exc)
        return row
    figure = figure_of(bvh)
    if figure == "cmu31":
        rest = added_tpose(bvh)
    elif figure in ("upm", "unmapped"):
        rest = False
    else:
        rest = added_rest_frame(bvh, builtin_maps()[figure])
    row.update(frames=bvh.n_frames, fps=round(bvh.fps, 2), joints=bvh.skeleton.n_joints,
               figure=figure, rest_frame=bool(rest))
    return row
