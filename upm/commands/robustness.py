"""How often does the free-root character stay up? Each row (a clip, or clips joined by
transitions) is followed by the balance controller, root free and no external force, on
its exact reference and on --seeds references whose joint channels are each moved by their
own constant drawn from N(0, --offset-deg) (0.1 deg: far under mocap's precision). One
free-root run is one path of a chaotic system; this says how often an outcome holds.

A row is CLIP, CLIP@A:B, or pieces joined by '+' with an optional ',METHOD' (default upm):
02_01+02_02+02_01+02_02,feasible. The default rows are the flat-floor walks and runs of the
data and the 8-12 s sequences of issue 10's table (11 rows; with the default 5 seeds, 66
runs: about 9 minutes on 2 cores); '--rows all' runs every clip of the data as a row of
its own (what stands and what falls, and when; with --seeds 0 13-20 minutes). Sequences
joined by upm or feasible use --map, else a UPM trained on the train split of clips.csv
(cached outside the repository).

Per run the figures of 'upm simulate --modes free' (fell and when, ends going down, joint
and body error, the body error in the frames the search changed and in the rest, drift,
heading, search retries, wall s per simulated s and raw mj_steps per step: runs side by
side, so read the cost with 'upm simulate' or 'upm bench'); per row, how many runs fell
and when. Written to --out: robustness.json (settings, software versions,
per row, every run), robustness.md (the table) and robustness.png (the falls on each row's
timeline). Finished runs are kept in robustness-partial.jsonl as they
come: the same command, stopped or failed, completes only what is missing.
--config FILE.toml changes the balance controller's tuning constants (recorded in
robustness.json's settings; the checkpoint of another configuration is not resumed).

--effort offline (or both, side by side) performs the rows in the offline effort too: the
sampling search over the servos' targets (the configuration's [offline] section), which
asks whether the body can perform the row at all, on the exact reference and
--offline-seeds offset ones (default 0), each run on --threads threads (default 2; the
workers default to the cores divided by them). It costs about 20-35 wall s per simulated
second on 2 cores: '--rows all --effort both --seeds 0 --max-s 4' (every clip's first 4 s)
takes about an hour. --max-s S keeps each row's first S seconds, for both efforts.

Examples:
  upm robustness --out upm-robustness
  upm robustness --rows 05_01 16_15+16_15 --seeds 10 --out r
  upm robustness --rows all --seeds 0 --out every-clip
  upm robustness --rows 02_01@0:240 --seeds 2 --workers 1 --out quick
  upm robustness --rows all --effort both --seeds 0 --max-s 4 --out every-clip-both
"""

from __future__ import annotations

HELP = "how often the free-root character stays up: clips and sequences on offset references"

DEFAULT_OUT = "upm-robustness"


def configure(parser) -> None:
    from controller.config import DEFAULT
    from eval.robustness import OFFSET_DEG, OFFSET_SEEDS
    from upm.commands.common import (
        add_config_argument,
        add_data_argument,
        add_strength_argument,
    )

    add_data_argument(parser)
    parser.add_argument("--rows", nargs="+", metavar="ROW", default=None,
                        help="clips or sequences (CLIP, CLIP@A:B, CLIP+CLIP+...[,METHOD]), "
                             "or 'all': every clip of the data once; default: issue 10's 11 "
                             "rows")
    parser.add_argument("--seeds", type=int, metavar="K", default=OFFSET_SEEDS,
                        help="offset references per row, seeds 1 to K, besides the exact one "
                             f"(default {OFFSET_SEEDS}; 0: the exact references only)")
    parser.add_argument("--offset-deg", metavar="SIGMA", type=float, default=OFFSET_DEG,
                        help="standard deviation of each joint channel's constant offset, "
                             f"degrees (default {OFFSET_DEG:g})")
    parser.add_argument("--map", metavar="MAP.npz", default=None,
                        help="UPM for the rows joined by upm or feasible (default: trained on "
                             "the train split, cached)")
    parser.add_argument("--search-budget", metavar="X", type=float, default=None,
                        help="the balance controller's search budget, in multiples of the "
                             "run's own physics steps (default: the controller's, "
                             f"{DEFAULT.search.budget:g}; over --config's)")
    add_config_argument(parser, "the balance controller")
    from upm.commands.transition import add_cut_argument

    add_cut_argument(parser)
    add_strength_argument(parser)
    parser.add_argument("--out", metavar="DIR", default=DEFAULT_OUT,
                        help=f"output directory (default: ./{DEFAULT_OUT})")
    parser.add_argument("--workers", type=int, metavar="K", default=None,
                        help="runs at once (default: the usable cores). The figures do not "
                             "depend on it")
    parser.add_argument("--executor", choices=("local", "ray"), default="local",
                        help="where the runs go: a local process pool (default) or Ray")
    parser.add_argument("--address", metavar="ADDR", default=None,
                        help="an existing Ray cluster (with --executor ray): ray://HEAD:10001 "
                             "(Ray Client) or HEAD:6379 (the head's GCS), as upm eval's")
    parser.add_argument("--effort", choices=("realtime", "offline", "both"),
                        default="realtime",
                        help="who performs the rows: 'realtime' (default) the balance "
                             "controller; 'offline' the offline effort's sampling search "
                             "(tens of wall s per simulated s); 'both' side by side")
    parser.add_argument("--offline-seeds", type=int, metavar="K", default=None,
                        help="offset references per row in the offline effort, besides the "
                             "exact one (default 0)")
    parser.add_argument("--threads", metavar="N", type=int, default=None,
                        help="threads of each offline run's rollouts (default: [offline] "
                             "threads, 2; the figures do not depend on it)")
    parser.add_argument("--max-s", metavar="S", type=float, default=None,
                        help="each row's first S seconds only, in every effort (default: "
                             "whole)")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="skip robustness.png")


def run(args) -> int:
    import json
    import math
    import sys
    from pathlib import Path

    from eval.robustness import CHECKPOINT_NAME, DEFAULT_ROWS, Settings, parse_rows, run_robustness
    from eval.robustness_report import plot, summary, table_markdown
    from upm.commands.common import check_strength, controller_config
    from upm.core.errors import UsageError
    from upm.core.fileio import atomic_path
    from upm.motion.catalog import Catalog

    if not 0 <= args.seeds <= 1000:
        raise UsageError(f"--seeds must be from 0 to 1000, not {args.seeds}")
    if not (math.isfinite(args.offset_deg) and 0 < args.offset_deg <= 10):
        raise UsageError(f"--offset-deg {args.offset_deg:g}: use a number of degrees above 0 "
                         "and at most 10")
    if args.search_budget is not None and not (math.isfinite(args.search_budget)
                                               and 0 <= args.search_budget <= 1000):
        raise UsageError(f"--search-budget {args.search_budget:g}: use a number from 0 to "
                         "1000")
    strength = check_strength(args.strength)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, not {args.workers}")
    if args.map is not None and not Path(args.map).is_file():
        raise UsageError(f"--map {args.map}: no such file")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: exists and is not a directory")
    efforts = ("realtime", "offline") if args.effort == "both" else (args.effort,)
    if "offline" not in efforts:
        for flag, value in (("--offline-seeds", args.offline_seeds),
                            ("--threads", args.threads)):
            if value is not None:
                raise UsageError(f"{flag} is the offline effort's: add --effort offline "
                                 "or --effort both")
    offline_seeds = 0 if args.offline_seeds is None else args.offline_seeds
    if not 0 <= offline_seeds <= 100:
        raise UsageError(f"--offline-seeds must be from 0 to 100, not {offline_seeds}")
    if args.threads is not None and not 1 <= args.threads <= 64:
        raise UsageError(f"--threads {args.threads}: use a whole number from 1 to 64")
    if args.max_s is not None and not (math.isfinite(args.max_s) and args.max_s > 0):
        raise UsageError(f"--max-s {args.max_s:g}: use a number of seconds above 0")
    if efforts == ("offline",) and args.search_budget is not None:
        raise UsageError("--search-budget is the real-time controller's: with --effort "
                         "offline the search's budget is [offline] budget in --config")
    config = controller_config(args, unused=("residual", "window_runs")
                               ).with_threads(args.threads)
    from eval.executor import check_executor

    check_executor(args.executor, args.address)  # Ray, and the cluster there, before loading
    catalog = Catalog(args.data)
    rows = parse_rows(args.rows, catalog.names()) if args.rows else list(DEFAULT_ROWS)
    for piece in sorted({p for row in rows for p in row.pieces}):
        if catalog.load_ref(piece).n_frames < 2:  # a one-line error for a bad clip or range
            raise UsageError(f"--rows: {piece} is one frame: nothing to simulate")
    settings = Settings(data_dir=str(catalog.root.resolve()), map_path=args.map,
                        offset_deg=float(args.offset_deg), controller_config=config,
                        cut=args.cut, strength=strength, max_s=args.max_s)
    parts = []
    if "realtime" in efforts:
        parts.append(f"real time: {args.seeds + 1} references (exact + {args.seeds} offset by "
                     f"N(0, {args.offset_deg:g} deg))")
    if "offline" in efforts:
        parts.append(f"offline effort: {offline_seeds + 1} references")
    print(f"upm robustness: {len(rows)} rows; " + "; ".join(parts)
          + (f"; each row's first {args.max_s:g} s" if args.max_s is not None else ""),
          file=sys.stderr)
    from eval.executor import executor_session
    from eval.runs import default_workers

    with executor_session(args.executor, args.workers or default_workers(), args.address):
        result = run_robustness(settings, rows, args.seeds, out, executor=args.executor,
                                address=args.address, workers=args.workers,
                                efforts=efforts, offline_seeds=offline_seeds)
    report = summary(result)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_path(out / "robustness.json") as tmp:
        Path(tmp).write_text(json.dumps(report, indent=1, allow_nan=False) + "\n",
                             encoding="utf-8")
    table = table_markdown(report)
    with atomic_path(out / "robustness.md") as tmp:
        Path(tmp).write_text(table, encoding="utf-8")
    if args.figures:
        plot(report, out / "robustness.png")
    (out / CHECKPOINT_NAME).unlink(missing_ok=True)
    print(table, end="")
    print(f"({result.workers} {result.executor} workers, {result.wall_s:.0f} s"
          + (f", {result.resumed} runs resumed" if result.resumed else "") + ")")
    print(f"written to {out}/: robustness.json, robustness.md"
          + (", robustness.png" if args.figures else ""))
    return 0
