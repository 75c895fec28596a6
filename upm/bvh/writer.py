"""Writing BVH files (atomically: a temporary file renamed into place)."""

from __future__ import annotations

import os

import numpy as np

from upm.core.fileio import atomic_open


def write_bvh(path: str | os.PathLike, bvh, precision: int = 9) -> None:
    """Write a :class:`~upm.bvh.BvhMotion` (tabs for indentation, LF line endings).

    Values are printed with ``precision`` significant digits.
    """
    skeleton = bvh.skeleton
    children = [[] for _ in range(skeleton.n_joints)]
    for j, p in enumerate(skeleton.parents):
        if p >= 0:
            children[p].append(j)
    number = f"%.{precision}g"
    lines = ["HIERARCHY"]

    def joint(j, depth):
        pad = "\t" * depth
        kind = "ROOT" if skeleton.parents[j] < 0 else "JOINT"
        lines.append(f"{pad}{kind} {skeleton.names[j]}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}\tOFFSET " + " ".join(number % v for v in skeleton.offsets[j]))
        names = skeleton.channels[j]
        lines.append(f"{pad}\tCHANNELS {len(names)}" + "".join(f" {c}" for c in names))
        for c in children[j]:
            joint(c, depth + 1)
        if np.isfinite(skeleton.end_sites[j]).all():
            lines.append(f"{pad}\tEnd Site")
            lines.append(f"{pad}\t{{")
            lines.append(f"{pad}\t\tOFFSET "
                         + " ".join(number % v for v in skeleton.end_sites[j]))
            lines.append(f"{pad}\t}}")
        lines.append(f"{pad}}}")

    joint(0, 0)
    lines += ["MOTION", f"Frames: {bvh.n_frames}", f"Frame Time: {bvh.frame_time_s:.9g}"]
    row = " ".join([number] * bvh.values.shape[1])
    with atomic_open(path, "w", encoding="utf-8", newline="\n") as handle:
        handle.write("\n".join(lines) + "\n")
        for values in bvh.values:
            handle.write(row % tuple(values) + "\n")
