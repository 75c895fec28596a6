"""Train a posture map on motion-capture clips and save it as a .npz file.

The Uniform Posture Map (--kind upm, the default) grows one map of neurons per joint
class (body, global, medium, detail) from every frame of the chosen clips: a posture
farther than R from every neuron becomes a neuron; otherwise the nearest neuron and its
neighbours (the neurons within the neighbourhood radius of it) move toward it. R and the
neighbourhood are chosen from the data unless given (R: the 90th percentile of the
distance from a frame to the nearest of 5 N^0.54321 randomly drawn frames; the
neighbourhood: R), so no tuning is needed. --kind som trains the classic fixed-grid
Kohonen SOM on the same data instead: the paper's foil.

By default the train split of clips.csv is used. Frames are taken at each clip's own
rate (a 60 fps clip only gives fewer samples of the same motion). Training is
deterministic for a given --seed. A saved map is derived data: keep it out of version
control.
"""

from __future__ import annotations

from upm.commands.common import add_data_argument

HELP = "train a posture map (UPM, or the Kohonen SOM foil) on clips; save it as .npz"


def configure(parser) -> None:
    add_data_argument(parser)
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--split", choices=["train", "test", "all"], default=None,
                       help="train on the clips of this split of clips.csv (default: train)")
    which.add_argument("--clips", nargs="+", metavar="CLIP", default=None,
                       help="train on these clips instead (e.g. 02_02 05_01)")
    parser.add_argument("--out", metavar="MAP.npz", required=True, help="where to save the map")
    parser.add_argument("--kind", choices=["upm", "som"], default="upm",
                        help="upm: Uniform Posture Map (default); som: fixed-grid Kohonen SOM")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--json", action="store_true", help="print a JSON summary")
    upm = parser.add_argument_group("UPM parameters (default: chosen from the data)")
    upm.add_argument("--radius", type=float, metavar="DEG", default=None,
                     help="R, the largest distance at which a posture joins a neuron "
                     "(degrees, all classes)")
    upm.add_argument("--neighbourhood", type=float, metavar="DEG", default=None,
                     help="initial neighbourhood radius (degrees; default: R)")
    upm.add_argument("--learning-rate", type=float, default=0.1, metavar="ETA",
                     help="initial learning rate eta, falling linearly to 0 (default 0.1)")
    upm.add_argument("--passes", type=int, default=5, metavar="N",
                     help="passes over the data with eta > 0 (default 5; a closing pass "
                     "at eta = 0 follows)")
    upm.add_argument("--batch-size", type=int, default=512, metavar="N",
                     help="samples per vectorised step (1 = strictly sequential; default 512)")
    som = parser.add_argument_group("SOM parameters")
    som.add_argument("--grid", metavar="ROWSxCOLS", default=None,
                     help="grid size for every class, e.g. 30x40 (default: 5 N^0.54321 "
                     "neurons shaped by the data)")
    som.add_argument("--epochs", type=int, default=10, metavar="N",
                     help="batch-map epochs (default 10)")


def _grid(text):
    from upm.core.errors import UsageError

    if text is None:
        return None
    try:
        rows, cols = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UsageError(f"--grid must look like 30x40, not {text!r}") from None
    return rows, cols


def summary_rows(posture_map) -> list[dict]:
    """One row per class: neurons, R (UPM) or grid (SOM), quantisation error."""
    rows = []
    for c, s in posture_map.stats.items():
        rows.append({
            "class": c,
            "neurons": s["neurons"],
            "radius_deg": s.get("radius_deg"),
            "grid": "x".join(str(v) for v in s["grid"]) if s.get("grid") else "",
            "quantisation_error_mean_deg": s["quantisation_error_mean_deg"],
            "quantisation_error_max_deg": s["quantisation_error_max_deg"],
        })
    return rows


def print_summary(posture_map, header: str) -> None:
    from upm.commands.common import format_table

    rows = summary_rows(posture_map)
    columns = [("class", "class", "<"), ("neurons", "neurons", ">d")]
    if posture_map.kind == "upm":
        columns.append(("radius_deg", "R (deg)", ">.2f"))
    else:
        columns.append(("grid", "grid", ">"))
    columns += [("quantisation_error_mean_deg", "qerr mean (deg)", ">.2f"),
                ("quantisation_error_max_deg", "qerr max (deg)", ">.2f")]
    print(header)
    print(format_table(rows, columns))


def run(args) -> int:
    import os

    from upm.commands.common import print_json
    from upm.core.errors import UsageError
    from upm.maps.class_maps import postures_of_clips
    from upm.motion.catalog import Catalog

    catalog = Catalog(args.data)
    if args.clips:
        names = [catalog.info(n).name for n in args.clips]
    else:
        split = args.split or "train"
        names = catalog.names(None if split == "all" else split)
        if not names:
            raise UsageError(f"no clips of split {split!r} under {catalog.root} "
                             f"(is clips.csv there?)")
    postures, names = postures_of_clips(catalog, names)
    if args.kind == "upm":
        from upm.maps.posture_map import UniformPostureMap

        posture_map = UniformPostureMap(
            radius_deg=args.radius, neighbourhood_deg=args.neighbourhood,
            learning_rate=args.learning_rate, passes=args.passes, batch_size=args.batch_size,
            seed=args.seed, progress=True)
    else:
        from upm.maps.som import KohonenSOM

        posture_map = KohonenSOM(grid=_grid(args.grid), epochs=args.epochs, seed=args.seed,
                                 progress=True)
    posture_map.fit(postures, clip_names=names)
    posture_map.save(args.out)
    if args.json:
        print_json({"out": os.fspath(args.out), "kind": posture_map.kind,
                    "clips": names, "samples": len(postures),
                    "train_seconds": posture_map.provenance["train_seconds"],
                    "classes": summary_rows(posture_map)})
        return 0
    clips = f"{len(names)} clip" + ("" if len(names) == 1 else "s")
    print_summary(posture_map, f"{posture_map.kind.upper()} trained on {clips}, "
                               f"{len(postures)} frames, in "
                               f"{posture_map.provenance['train_seconds']:.1f} s")
    print(f"\nsaved {args.out}")
    return 0
