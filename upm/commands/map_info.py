"""Describe a saved posture map: its kind, neurons per class, R (UPM) or grid (SOM),
the quantisation error on its training frames (mean and largest distance, degrees, from
a frame's class sub-vector to the nearest neuron), its parameters and the clips it was
trained on.
"""

from __future__ import annotations

HELP = "describe a saved posture map (neurons per class, R, quantisation error)"


def configure(parser) -> None:
    parser.add_argument("map", metavar="MAP.npz", help="a map saved by 'upm train'")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args) -> int:
    import os

    from upm.commands.common import print_json
    from upm.commands.train import print_summary, summary_rows
    from upm.maps.class_maps import FORMAT_VERSION
    from upm.maps.map_file import load_map

    posture_map = load_map(args.map)
    prov = posture_map.provenance
    info = {
        "map": os.fspath(args.map),
        "kind": posture_map.kind,
        "format_version": FORMAT_VERSION,
        "bytes": os.path.getsize(args.map),
        "classes": summary_rows(posture_map),
        "params": posture_map.params,
        "clips": prov.get("clip_names", []),
        "samples": prov.get("n_samples"),
        "train_seconds": prov.get("train_seconds"),
    }
    if args.json:
        print_json(info)
        return 0
    name = {"upm": "Uniform Posture Map", "som": "Kohonen SOM"}[posture_map.kind]
    print_summary(posture_map, f"{args.map}: {name} (format version {FORMAT_VERSION}, "
                               f"{info['bytes']} bytes)")
    clips = info["clips"]
    n_clips = f"{len(clips)} clip" + ("" if len(clips) == 1 else "s")
    print(f"\ntrained on {n_clips} ({info['samples']} frames) in "
          f"{info['train_seconds']:.1f} s: {' '.join(clips)}")
    params = {k: v for k, v in posture_map.params.items()
              if k not in ("radius_deg", "neighbourhood_deg", "grid")}
    print("parameters: " + ", ".join(f"{k}={v}" for k, v in params.items()))
    return 0
