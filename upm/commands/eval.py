"""The held-out study: are UPM transitions more physically valid and more natural than
linear blends (and the other methods), on real data?

The UPM and the classic SOM are trained on the train split of clips.csv (once: the maps
are cached outside the repository). Seeded transition pairs join 200-frame segments of
two different test clips (all resampled to 120 fps); every method builds the window
(upm, som, the two ablations classnn and snap, linear, slerp, inertialize, spacetime),
and each window is scored on the MuJoCo humanoid of clip 1's subject:

  - kinematic validity (the calibrated verdict: upm calibrate): valid frames (within the
    human range of motion or no further beyond it than the two end postures, no
    self-contact deeper than its body pair's soft-tissue allowance, nothing through the
    floor), the added excess, self-collision, floor penetration, and the frames beyond
    the ASF's declared limits (reported, not judged);
  - distance to the nearest real posture of the test clips outside the pair's own
    neighbourhood (deg RMS over the 45 declared DOFs);
  - joint jerk (across the joins too), foot skating (horizontal foot speed below 5 cm),
    the root residual force (inverse dynamics, body weights), the tracking error of the
    humanoid's servos following the window (root driven);
  - the time per transition.

Real windows of the test clips are scored the same way: the calibration row. Every
method gets the same root (the velocity blend), so residual force and foot skating
compare the joint angles; read the residual on the flat-floor pairs (the uneven-terrain
walk, the step-up and the 60 fps jumps need about one body weight in the real data
alone). Tracking: the humanoid's servos (human torque limits) follow each window with the
root driven along it.

The in-betweening task (--inbetween N windows, default as many as pairs, 0 to skip) gives
the literature's figures: every method and the LaFAN1 protocol's two baselines (zerovel,
interp) fill held-out windows of the test clips (10 frames of context at 30 fps, the
target after transitions of 5, 15 and 30 frames) and are scored against the recorded
frames with L2Q, L2P and NPSS as Harvey et al. 2020 define them. The data are CMU's, not
LaFAN1's: the figures compare with the literature's in kind, not in value.

The terminal gets the headline (every method, the means of the headline metrics, ms per
transition), the UPM - linear verdicts and the in-betweening figures; the output
directory gets scores.csv (every score, long-form: kind, id, window, method, metric,
value; the in-betweening rows of kind inbetween), results.json (protocol, pairs,
statistics, the in-betweening section), summary.csv, paired.csv,
summary.md (means with 95 % bootstrap intervals, UPM - X paired, by A-B distance
tercile, by seen/unseen subject, flat floor), table4.md + timing.json (ms per transition,
spacetime / UPM: these vary by run, the rest is identical for the same seed) and the
figures (fig13_window_dof.png, fig14_sequence_dof.png, metrics.png, filmstrip.png).

The default is a reduced study (100 pairs, 20-frame windows: about 2 minutes on 2 cores,
training the maps included); --full runs the whole protocol (200 pairs, windows of 10,
20 and 40 frames: about 4 minutes, and the method performed: the window as the free-root
humanoid performed feasible's, on the first --performed-pairs pairs, 20 by default, about
40 s of CPU a window; its rows of the other pairs are empty). The in-betweening task adds
about 40 % to the default study (measured on a shared, loaded 2-core machine: 490 s
instead of 355 s; --inbetween 0 skips it). The pairs of a smaller study are the first
pairs of a larger one with the same seed, scored identically.

The free-root test asks whether a body can perform each window (pairs x methods + real
windows; --physics-pairs chooses how many of the pairs get it). By default the offline
effort performs it: a sampling search over the servos' targets (controller.offline, its
[offline] section of --config) that starts from the real-time balance controller's run of
the motion, so the real-time controller's falls and joint error on the same runs are
reported beside its own (realtime_* in physics.csv, a second table in summary.md). It
costs about 20 wall s a run on two threads (30 pairs of 3 methods and their real
windows: 120 runs, about 70 minutes on 2 cores). --effort realtime has the real-time
controller alone perform it: about 5 s of CPU a run (60 pairs: 600 runs, about half an
hour on 2 cores). The checkpoint keeps the effort (a run of the other effort starts
afresh). It runs on a local process pool, or on Ray (--executor ray: a local Ray
instance, or an existing cluster with --address ray://HEAD:10001 or HEAD:6379:
docs/guides/ray-cluster.md). Ctrl-C or SIGTERM stops it at any time. Finished runs are
kept in OUT/physics-partial.jsonl as they come: if runs fail or the command is stopped,
the same command completes only what is missing. --config FILE.toml changes the balance
controller's tuning constants for the free-root test (recorded in results.json and in the
checkpoint: a run with another configuration starts afresh).

Examples:
  upm eval --out upm-eval
  upm eval --full --out upm-eval-full
  upm eval --pairs 100 --windows 10,20 --seed 1 --workers 2 --out study
  upm eval --physics --pairs 30 --methods upm linear feasible --out upm-eval-physics
  upm eval --physics --effort realtime --pairs 60 --out upm-eval-realtime
  upm eval --physics --effort realtime --pairs 60 --executor ray --address ray://head:10001
"""

from __future__ import annotations

HELP = "the held-out study: every method on seeded pairs, tables, JSON, figures"

#: The reduced default study.
DEFAULT_PAIRS = 100
DEFAULT_WINDOWS = (20,)
#: The full study (--full).
FULL_PAIRS = 200
FULL_WINDOWS = (10, 20, 40)
DEFAULT_OUT = "upm-eval"


def configure(parser) -> None:
    from eval.physics_unit import EFFORTS
    from upm.commands.common import add_config_argument, add_data_argument

    add_data_argument(parser)
    parser.add_argument("--out", metavar="DIR", default=DEFAULT_OUT,
                        help=f"output directory (default: ./{DEFAULT_OUT})")
    parser.add_argument("--full", action="store_true",
                        help=f"the full study: {FULL_PAIRS} pairs, windows "
                             f"{','.join(map(str, FULL_WINDOWS))} (unless --pairs/--windows "
                             "say otherwise)")
    parser.add_argument("--pairs", type=int, metavar="N", default=None,
                        help=f"transition pairs (default {DEFAULT_PAIRS}; --full: {FULL_PAIRS})")
    parser.add_argument("--windows", metavar="L,L,...", default=None,
                        help="window lengths in frames at 120 fps (default "
                             f"{','.join(map(str, DEFAULT_WINDOWS))}; --full: "
                             f"{','.join(map(str, FULL_WINDOWS))})")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--inbetween", type=int, metavar="N", default=None,
                        help="windows of the in-betweening task (the LaFAN1 metrics L2Q, "
                             "L2P, NPSS; default: as many as --pairs; 0: skip it)")
    parser.add_argument("--methods", nargs="+", metavar="M", default=None,
                        help="methods to run (default: all but performed; --full: all; upm "
                             "is needed for the paired comparisons and figures)")
    parser.add_argument("--performed-pairs", type=int, metavar="N", default=None,
                        help="pairs the method performed is scored on: the study's first N "
                             "(default 20; about 40 s of CPU a window; the others' rows "
                             "are left empty and out of the summaries)")
    parser.add_argument("--workers", type=int, metavar="K", default=None,
                        help="worker processes (default: the usable cores; 1: no "
                             "subprocesses). The numbers do not depend on it.")
    parser.add_argument("--no-figures", dest="figures", action="store_false",
                        help="skip the figures (no rendering)")
    parser.add_argument("--physics", action="store_true",
                        help="add the free-root test: the humanoid, root free, performs "
                             "every window (--effort: the offline effort by default)")
    parser.add_argument("--physics-pairs", type=int, metavar="N", default=None,
                        help="pairs that get the free-root test: the study's first N "
                             "(default: all of --pairs)")
    parser.add_argument("--effort", choices=EFFORTS, default=None,
                        help="who performs the --physics runs: 'offline' (default) the "
                             "offline effort's sampling search over the servos' targets, "
                             "the real-time controller's figures beside it (about 15 wall s "
                             "per simulated s on two threads: some 20 s a run); 'realtime' "
                             "the real-time balance controller alone (some 5 s a run)")
    parser.add_argument("--threads", metavar="N", type=int, default=None,
                        help="threads of each offline run's rollouts (default: [offline] "
                             "threads, 2; the workers default to the cores divided by them; "
                             "the figures do not depend on either)")
    add_config_argument(parser, "the free-root body of the --physics test (the "
                                "kinematic scores keep their own checks)")
    parser.add_argument("--executor", choices=("local", "ray"), default="local",
                        help="where the work runs: a local process pool (default) or Ray")
    parser.add_argument("--address", metavar="ADDR", default=None,
                        help="an existing Ray cluster: ray://HEAD:10001 (Ray Client, from "
                             "any machine) or HEAD:6379 (the head's GCS, from a machine of the "
                             "cluster); the token, if the cluster asks for one, from "
                             "RAY_AUTH_TOKEN, RAY_AUTH_TOKEN_PATH or ~/.ray/auth_token. "
                             "Default with --executor ray: a local Ray instance with --workers "
                             "CPUs")


def parse_windows(text: str | None, default) -> tuple[int, ...]:
    """``"10,20,40"`` -> (10, 20, 40): whole numbers >= 2, no repeats."""
    from upm.core.errors import UsageError

    if text is None:
        return tuple(default)
    try:
        values = tuple(int(v) for v in text.replace(" ", "").split(",") if v)
    except ValueError:
        raise UsageError(f"--windows must be whole numbers separated by commas, not "
                         f"{text!r}") from None
    if not values or any(v < 2 for v in values):
        raise UsageError(f"--windows needs window lengths of at least 2 frames, not {text!r}")
    if len(set(values)) != len(values):
        raise UsageError(f"--windows {text}: a window length is repeated")
    return values


def physics_effort(args) -> str:
    """The free-root test's effort of parsed ``upm eval`` arguments (:data:`DEFAULT_EFFORT
    <eval.physics_unit.DEFAULT_EFFORT>` unless told), ``--threads`` checked with it.

    Raises
    ------
    UsageError
        ``--effort`` or ``--threads`` without ``--physics``, ``--threads`` with the
        real-time effort or out of 1..64.
    """
    from eval.physics_unit import DEFAULT_EFFORT
    from upm.core.errors import UsageError

    if args.effort is not None and not args.physics:
        raise UsageError("--effort goes with --physics (the free-root test's performer)")
    effort = args.effort or DEFAULT_EFFORT
    if args.threads is not None:
        if not args.physics:
            raise UsageError("--threads goes with --physics (the offline effort's rollouts)")
        if effort != "offline":
            raise UsageError("--threads is the offline effort's: --effort realtime has no "
                             "threads")
        if not 1 <= args.threads <= 64:
            raise UsageError(f"--threads {args.threads}: use a whole number from 1 to 64")
    return effort


def run(args) -> int:
    import sys
    from pathlib import Path

    from eval.console import headline_text, legend
    from eval.outputs import figure_window, write_outputs
    from eval.study import FULL_METHODS, STUDY_METHODS, StudyConfig, run_study
    from upm.commands.common import controller_config
    from upm.core.errors import UsageError
    from upm.motion.catalog import Catalog
    from upm.transitions import get_method

    pairs = args.pairs if args.pairs is not None else (FULL_PAIRS if args.full
                                                       else DEFAULT_PAIRS)
    if pairs < 2:
        raise UsageError(f"--pairs must be at least 2, not {pairs}")
    if args.inbetween is not None and args.inbetween < 0:
        raise UsageError(f"--inbetween must be 0 (skip) or more windows, not {args.inbetween}")
    windows = parse_windows(args.windows, FULL_WINDOWS if args.full else DEFAULT_WINDOWS)
    methods = (tuple(args.methods) if args.methods
               else FULL_METHODS if args.full else STUDY_METHODS)
    for method in methods:
        get_method(method)  # a one-line error naming the methods if unknown
    if len(set(methods)) != len(methods):
        raise UsageError("--methods: a method is repeated")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, not {args.workers}")
    if args.figures and not {"upm", "linear"} <= set(methods):
        raise UsageError("the figures compare upm with linear: keep both in --methods, or "
                         "pass --no-figures")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: exists and is not a directory")
    performed_pairs = 20 if args.performed_pairs is None else args.performed_pairs
    if args.performed_pairs is not None and "performed" not in methods:
        raise UsageError("--performed-pairs goes with the method performed (--full, or "
                         "--methods ... performed)")
    if not 1 <= performed_pairs:
        raise UsageError(f"--performed-pairs must be at least 1, not {performed_pairs}")
    physics_pairs = args.physics_pairs if args.physics_pairs is not None else pairs
    if args.physics_pairs is not None and not args.physics:
        raise UsageError("--physics-pairs goes with --physics")
    if not 1 <= physics_pairs <= pairs:
        raise UsageError(f"--physics-pairs must be between 1 and --pairs ({pairs}), "
                         f"not {physics_pairs}")
    if args.config is not None and not args.physics:
        raise UsageError("--config sets the free-root test's controller: it goes with "
                         "--physics")
    effort = physics_effort(args)
    physics_config = controller_config(args, unused=("residual", "window_runs")
                                       ).with_threads(args.threads)
    from eval.executor import check_executor

    check_executor(args.executor, args.address)  # Ray, and the cluster there, before loading
    catalog = Catalog(args.data)
    # absolute: Ray workers open it from their own working directory
    config = StudyConfig(data_dir=str(catalog.root.resolve()), pairs=pairs, windows=windows,
                         seed=args.seed, methods=methods, inbetween=args.inbetween,
                         performed_pairs=performed_pairs)
    print(f"upm eval: {pairs} pairs x {len(methods)} methods x windows "
          f"{','.join(map(str, windows))}, seed {args.seed}; in-betweening: "
          f"{config.inbetween_windows} windows", file=sys.stderr)
    from eval.executor import executor_session
    from eval.runs import default_workers

    with executor_session(args.executor, args.workers or default_workers(), args.address):
        result = run_study(config, workers=args.workers, executor=args.executor,
                           address=args.address)
        physics = None
        if args.physics:
            from eval.physics import run_physics

            print(f"upm eval: free-root test on {physics_pairs} pairs x {len(methods)} "
                  f"methods + real windows ({effort} effort, {args.executor})",
                  file=sys.stderr)
            physics = run_physics(result, physics_pairs, out, executor=args.executor,
                                  address=args.address, workers=args.workers,
                                  controller_config=physics_config, effort=effort)
    report = write_outputs(result, out, figures=args.figures, physics=physics)
    if physics is not None:
        physics.checkpoint.remove()

    frames = figure_window(windows)
    print(f"Held-out study: {pairs} pairs, window {frames} frames at 120 fps, means "
          f"({result.workers} workers, {result.wall_s:.0f} s)")
    print(headline_text(report["statistics"], report["timing"], frames, methods))
    statistics = report["statistics"]
    if "linear" in statistics.compared(frames):
        from eval.metrics import HEADLINE
        from eval.tables import DISPLAY, verdict

        print("UPM - linear, paired (UPM wins/ties/losses):")
        for metric in HEADLINE:
            c = statistics.comparison(frames, "linear", metric)
            print(f"  {DISPLAY[metric][2]:<26} {verdict(c, metric):<20} "
                  f"{c['wins']}/{c['ties']}/{c['losses']}")
    ratio = report["timing"]["spacetime_over_upm"].get(str(frames))
    if ratio is not None:
        print(f"spacetime / UPM time per transition: {ratio:.1f}x (Table 4: table4.md)")
    if report["inbetween"]:
        from eval.inbetween_report import inbetween_text

        print("\n".join(legend([
            f"In-betweening, the LaFAN1 metrics (Harvey et al. 2020; lower is better): "
            f"{len(result.inbetween)} held-out windows, transitions of 5, 15 and 30 frames "
            "at 30 fps, zerovel and interp the protocol's baselines, NPSS pooled; CMU data, "
            "not LaFAN1's: comparable in kind, not in value"])))
        print(inbetween_text(report["inbetween"]))
    if physics is not None:
        from eval.physics_report import physics_text

        performer = ("the offline effort" if effort == "offline"
                     else "the balance controller")
        print(f"Free-root test: {physics_pairs} pairs, window {frames} frames ({performer}, "
              f"{physics.workers} {physics.executor} workers, "
              f"{physics.wall_s:.0f} s" + (f", {physics.resumed} runs resumed" if
                                           physics.resumed else "") + "):")
        print(physics_text(physics.statistics, frames, methods, effort))
    print("\n".join(legend([
        f"Written to {out}/: summary.md (every table with 95 % intervals: all the metrics, "
        "the paired tests by group, the calibration per clip, the in-betweening figures), "
        "summary.csv and paired.csv (the same, long-form), scores.csv (every score), "
        "results.json (protocol and definitions), table4.md and timing.json (ms)"
        + (", physics.csv" if physics is not None else "")
        + (", the figures (*.png)" if args.figures else "")])))
    return 0
