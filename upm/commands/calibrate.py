"""Calibrate the validity verdict against real motion: how many real frames pass, and how
many impossible ones fail.

Specificity: the share of real frames judged valid, per clip and per cause (beyond the
human range, self-interpenetration, through the floor), on the test split by default, on
any split, on clips you name, or on another data folder (--data DIR, e.g. subjects the
project has never seen). The ASF's own verdict is given beside it.

Sensitivity: impossible postures made from every --every-th real frame of the same clips,
one family at a time — knee, elbow and hip hyperextension far past the human range, a
thigh twisted 135 degrees, the thighs through each other, the body sunk 15 cm into the
floor, and a mix — and the share judged invalid, with the cause that caught them.

--refine prints what the train split gives for the human ranges and the soft-tissue
allowances (the tables committed in upm.motion.human_rom and controller.checks.tissue).
"""

from __future__ import annotations

from upm.commands.common import add_data_argument, add_limits_argument, print_json

HELP = "specificity (real frames valid) and sensitivity (impossible frames invalid)"


def configure(parser) -> None:
    parser.add_argument("clips", nargs="*", metavar="CLIP",
                        help="clips to calibrate on (default: the --split)")
    parser.add_argument("--split", choices=["train", "test", "all"], default="test",
                        help="the clips of this split of clips.csv (default: test)")
    add_data_argument(parser)
    add_limits_argument(parser)
    parser.add_argument("--every", type=int, default=10, metavar="N",
                        help="impossible postures from every N-th real frame (default 10)")
    parser.add_argument("--json", action="store_true", help="print the JSON result")
    parser.add_argument("--report", metavar="R.json", default=None,
                        help="write the JSON result (and R.md, a Markdown table) there")
    parser.add_argument("--figure", metavar="F.png", default=None,
                        help="write the specificity/sensitivity figure there")
    parser.add_argument("--refine", action="store_true",
                        help="print the train split's human ranges and tissue allowances")


def run(args) -> int:
    from upm.core.errors import UsageError
    from upm.motion.catalog import Catalog
    from upm.motion.range_models import range_model

    if args.every < 1:
        raise UsageError(f"--every must be at least 1, not {args.every}")
    catalog = Catalog(args.data)
    if args.refine:
        print_json(_refine(catalog))
        return 0
    limits = range_model(args.limits)
    names = args.clips or catalog.names(None if args.split == "all" else args.split)
    for name in names:
        if name not in catalog:
            raise UsageError(f"no clip {name!r} under {catalog.root}")
    from eval.calibration import figure, harness

    result = harness(catalog, names, limits=limits, every=args.every)
    result["data"] = str(args.data) if args.data else "default"
    if args.report:
        from pathlib import Path

        from upm.core.fileio import atomic_write_text

        atomic_write_text(args.report, _json_text(result))
        atomic_write_text(Path(args.report).with_suffix(".md"), markdown(result))
    if args.figure:
        figure(result, args.figure)
    if args.json:
        print_json(result)
    else:
        print(markdown(result))
    return 0


def _json_text(result) -> str:
    import json

    return json.dumps(result, indent=1, sort_keys=False) + "\n"


def _refine(catalog) -> dict:
    import numpy as np

    from controller.checks.contacts import contacts_over_frames
    from controller.checks.tissue import BODY_CLASS, allowance, class_pair
    from controller.qpos import to_qpos
    from humanoid_xml import catalog_model_path, load_model
    from upm.core.progress import progress
    from upm.motion.rom_refine import refine

    names = catalog.names("train")
    self_depths: dict[str, list] = {}
    floor_depths: dict[str, list] = {}
    for name in progress(names, desc="contacts of the train split", unit="clip"):
        model = load_model(catalog_model_path(catalog, catalog.info(name).subject))
        table = contacts_over_frames(model, to_qpos(model, catalog.load(name)))
        for a, b, depth in zip(table.body1, table.body2, table.depth_m, strict=True):
            na, nb = table.body_names[a], table.body_names[b]
            if a == 0:
                floor_depths.setdefault(BODY_CLASS.get(nb, nb), []).append(depth)
            else:
                self_depths.setdefault(class_pair(na, nb), []).append(depth)
    return {
        "human_ranges": refine(catalog.load(n) for n in names),
        "self_allowance_m": {k: allowance(np.array(v)) for k, v in sorted(self_depths.items())},
        "floor_allowance_m": {k: allowance(np.array(v))
                              for k, v in sorted(floor_depths.items())},
    }


def markdown(result: dict) -> str:
    """The harness's tables as Markdown."""
    spec = result["specificity"]
    t, asf = spec["totals"], spec["asf_totals"]
    rows = [{"clip": n, "frames": r["frames"], "valid": r["valid_pct"],
             "range": r["limit_violation_pct"], "self": r["self_collision_pct"],
             "floor": r["floor_penetration_pct"], "asf": r["beyond_asf_pct"],
             "rules": ", ".join(f"{k} {v}" for k, v in list(r["dofs"].items())[:2])}
            for n, r in spec["clips"].items()]
    lines = [f"Specificity ({result['limits']} verdict): {t['valid_pct']:.1f} % of "
             f"{t['frames']} real frames of {t['clips']} clips judged valid (the ASF's "
             f"declared limits: {asf['valid_pct']:.1f} %; {t['beyond_asf_pct']:.1f} % of the "
             "frames are beyond them).", "",
             "| clip | frames | valid % | beyond range % | self % | floor % | beyond ASF % "
             "| rules broken most (frames) |", "|---|---:|---:|---:|---:|---:|---:|---|"]
    lines += [f"| {r['clip']} | {r['frames']} | {r['valid']:.1f} | {r['range']:.1f} | "
              f"{r['self']:.1f} | {r['floor']:.1f} | {r['asf']:.1f} | {r['rules']} |"
              for r in rows]
    sens = result["sensitivity"]
    lines += ["", "Sensitivity: impossible frames judged invalid, by family.", "",
              "| family | frames | invalid % | by range | by self-contact | by floor |",
              "|---|---:|---:|---:|---:|---:|"]
    lines += [f"| {f} | {r['frames']} | {r['invalid_pct']:.1f} | {r['limit_frames']} | "
              f"{r['self_frames']} | {r['floor_frames']} |" for f, r in sens.items()]
    return "\n".join(lines) + "\n"



