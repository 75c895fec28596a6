"""Reading motion capture: ASF + AMC parse time and forward kinematics per frame."""

from __future__ import annotations

import numpy as np

from eval.bench import BenchContext, timeit_best

NAME = "io"


def run(context: BenchContext) -> dict:
    from upm.motion.catalog import Catalog, _read_asf_cached
    from upm.motion.kinematics import forward_kinematics

    catalog = Catalog(context.data_dir)
    names = catalog.names()
    if context.quick:
        names = names[:3]
    motions = {}

    def parse_all():
        _read_asf_cached.cache_clear()  # time the ASF reads too
        for name in names:
            motions[name] = catalog.load(name)

    parse_s = timeit_best(parse_all, repeat=1 if context.quick else 3)
    frames = sum(m.n_frames for m in motions.values())
    walk = motions.get("02_01") or next(iter(motions.values()))
    fk_s = timeit_best(lambda: forward_kinematics(walk), repeat=3 if context.quick else 10)
    # Reference: one (T, 3, 3) @ (T, 3, 3) batched matrix product per bone, the floor
    # of any batched FK on this machine.
    a = np.random.default_rng(0).normal(size=(walk.n_frames, 3, 3))
    matmul_s = timeit_best(lambda: a @ a, repeat=3 if context.quick else 20)
    n_bones = walk.skeleton.n_bones
    return {
        "clips": len(names),
        "frames": frames,
        "parse_all_clips_s": parse_s,
        "parse_us_per_frame": 1e6 * parse_s / frames,
        "fk_us_per_frame": 1e6 * fk_s / walk.n_frames,
        "reference_batched_matmul_us_per_frame_per_bone": 1e6 * matmul_s / walk.n_frames,
        "fk_ratio_to_one_matmul_per_bone": fk_s / (matmul_s * n_bones),
    }
