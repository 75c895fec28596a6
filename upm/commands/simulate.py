"""Join clips with transitions, drive the MuJoCo humanoid with the sequence, and report
how physically valid it is, frame by frame and window by window.

The sequence (--sequence CLIP@A:B CLIP@A:B ...) is built as by 'upm sequence': a
transition of --frames new frames by --method joins each consecutive pair (upm and som
need --map). The humanoid of the first piece's subject then

  - is checked per frame: joint limits (and, in windows, the excess beyond what the
    window's two end postures already have), self-collision, floor penetration;
  - needs an external force beyond what floor contact can supply (inverse dynamics, in
    body weights): the "hand of god" the motion asks for;
  - follows it with the root driven along the sequence ("driven": position servos) and
    with the root free on the floor ("free"): by default the balance controller (a
    whole-body inverse-dynamics QP at every physics step with the floor contacts, no
    force on the root, the joints' strength limits, and swing-foot placement), or with
    --controller servo the position servos alone (which fall within 0.5-1.4 s). Reported:
    joint error, body-position error, root drift and heading error, centre-of-mass height
    error, contact forces, joint torques and their saturation, whether and when it falls,
    and the controller's cost; plus, per window, a free-root run from 0.5 s before the window to
    0.5 s after it.

--report writes the JSON report (per frame, per window, per piece, totals) and a CSV
summary beside it. --video renders offscreen (no GPU needed: OSMesa) an .mp4, a .gif, or
a .png filmstrip of the whole sequence; --amc writes what the free-root character
actually did as an AMC on the subject's skeleton, --control the torques the balance
controller applied at every physics step (.npz: replayable open-loop with
controller.balance.run.replay); --filmstrip a PNG of the frames around each
window; --viewer plays it in MuJoCo's viewer where there is a display.

A free-root run is one path of a chaotic system: whether it falls can turn on differences
far under mocap's precision. --offset-deg 0.1 with a few --offset-seed values runs the
same sequence with every joint angle moved by its own small constant, to see how often an
outcome holds.

--effort offline runs the free-root simulations (the whole sequence and each window's) as
a sampling search over the servos' targets instead (SAMCON-style; no root force): can
this body perform it at all? Tens of wall s per simulated s; --threads N for its rollouts.

--strength K multiplies every joint's torque limit by K (default 1: the strength tables'
strong adult): would a stronger body carry out what this one cannot?

--config FILE.toml changes the tuning constants of the controller, the servo tracking and
the residual check (the keys the file names; the report records the whole configuration
under settings.controller_config, so that the run can be made again from the report).

Example:
  upm simulate --map upm.npz --sequence 02_01@0:200 02_03@20:150 --report r.json --video r.mp4
"""

from __future__ import annotations

import math

HELP = "drive the humanoid with clips joined by transitions; report physical validity"

RENDER_CHOICES = ("driven", "free", "reference")


def configure(parser) -> None:
    from upm.commands.common import (
        add_config_argument,
        add_data_argument,
        add_effort_arguments,
        add_strength_argument,
    )
    from upm.commands.transition import add_cut_argument, add_method_arguments

    add_data_argument(parser)
    parser.add_argument("--sequence", nargs="+", required=True, metavar="CLIP@A:B",
                        help="the pieces, in order (CLIP, CLIP@A:B frames A to B-1, CLIP@F)")
    add_method_arguments(parser)
    add_cut_argument(parser)
    parser.add_argument("--fps", type=float, default=None,
                        help="frame rate of the sequence (default: the first piece's)")
    parser.add_argument("--report", required=True, metavar="R.json",
                        help="the JSON report to write (and a CSV summary, R.csv)")
    parser.add_argument("--modes", nargs="+", choices=["driven", "free"],
                        default=["driven", "free"],
                        help="tracking simulations to run (default: both)")
    parser.add_argument("--controller", choices=["balance", "servo"], default="balance",
                        help="the free-root controller: the balance controller (default) "
                             "or the position servos alone")
    parser.add_argument("--search-budget", metavar="X", type=float, default=None,
                        help="the balance controller's backtracking search may simulate "
                             "up to X times the sequence's physics steps in all (default "
                             f"{_default_budget():g}; 0: no search; more carries harder "
                             "sequences through at more cost; over --config's)")
    add_config_argument(parser, "the balance controller, the servo tracking and the "
                                "residual check")
    add_effort_arguments(parser)
    add_strength_argument(parser)
    parser.add_argument("--offset-deg", metavar="SIGMA", type=float, default=0.0,
                        help="move every joint angle of the sequence by its own constant "
                             "drawn from N(0, SIGMA) degrees before simulating (marker "
                             "dropouts kept): run with a few --offset-seed "
                             "values to see whether a run's outcome holds under "
                             "differences far under mocap's precision (default 0: none)")
    parser.add_argument("--offset-seed", metavar="K", type=int, default=1,
                        help="seed of --offset-deg's draws (default 1)")
    parser.add_argument("--processes", type=int, choices=[1, 2], default=_default_processes(),
                        help="processes for the balance controller's lookahead rollouts: "
                             "2 runs them side by side (the same results; less wall time "
                             "where 2 cores are free, though not always on runs whose "
                             "rollouts stray, such as 16_15's, where 1 continues the "
                             "chosen one; default: 2 on a machine with 2 or more cores "
                             "that can fork, else 1)")
    parser.add_argument("--amc", metavar="S.amc|S.bvh", default=None,
                        help="write the free-root simulated motion as AMC or BVH, by the "
                             "extension (needs free in --modes)")
    parser.add_argument("--control", metavar="C.npz", default=None,
                        help="write the balance controller's applied torques per physics "
                             "step, with its start state (needs free and --controller "
                             "balance)")
    parser.add_argument("--no-window-runs", dest="window_runs", action="store_false",
                        help="skip the free-root run around each window")
    parser.add_argument("--video", metavar="V.mp4", default=None,
                        help="render offscreen: .mp4, .gif, or .png (a filmstrip)")
    parser.add_argument("--render", choices=RENDER_CHOICES, default=None,
                        help="what --video and --viewer show (default: the first of "
                             "--modes; 'reference' is the sequence itself, unsimulated)")
    parser.add_argument("--filmstrip", metavar="F.png", default=None,
                        help="a PNG of every 5th frame around each window: the sequence "
                             "itself above, the simulation below (the paper's Fig. 11/12)")
    parser.add_argument("--viewer", action="store_true",
                        help="play it in MuJoCo's interactive viewer (needs a display)")


def _default_processes() -> int:
    import multiprocessing
    import os

    forks = "fork" in multiprocessing.get_all_start_methods()
    return 2 if forks and (os.cpu_count() or 1) >= 2 else 1


def _default_budget() -> float:
    from controller.config import DEFAULT

    return DEFAULT.search.budget


def run(args) -> int:
    import warnings

    from controller.analysis import analyse
    from controller.qpos import to_qpos
    from controller.render import (
        VIDEO_SUFFIXES,
        filmstrip,
        filmstrip_frames,
        has_display,
        play_in_viewer,
        write_video,
    )
    from controller.report import write_report
    from humanoid_xml import catalog_model_path, load_model
    from upm.commands.common import (
        check_effort,
        check_strength,
        controller_config,
        performed_setup,
    )
    from upm.commands.transition import sequence_from_args
    from upm.core.errors import UsageError

    strength = check_strength(args.strength)
    check_effort(args)
    if (args.amc or args.control) and "free" not in args.modes:
        raise UsageError("--amc and --control need the free-root run: add free to --modes")
    if args.control and args.controller != "balance":
        raise UsageError("--control records the balance controller: use --controller "
                         "balance")
    if args.search_budget is not None:
        if not (math.isfinite(args.search_budget) and 0 <= args.search_budget <= 1000):
            raise UsageError(f"--search-budget {args.search_budget:g}: use a number from 0 "
                             "to 1000")
        if args.controller != "balance":
            raise UsageError("--search-budget is the balance controller's: use --controller "
                             "balance")
    if not (math.isfinite(args.offset_deg) and 0 <= args.offset_deg <= 10):
        raise UsageError(f"--offset-deg {args.offset_deg:g}: use a number of degrees from 0 "
                         "to 10")
    if args.amc:
        from upm.bvh.formats import check_motion_path

        check_motion_path(args.amc, "--amc")
    if args.control and not args.control.lower().endswith(".npz"):
        raise UsageError(f"--control {args.control}: use a name ending in .npz")
    render = args.render or args.modes[0]
    if render != "reference" and render not in args.modes:
        raise UsageError(f"--render {render} needs that simulation: add it to --modes")
    if args.video and not args.video.lower().endswith(VIDEO_SUFFIXES):
        raise UsageError(f"--video {args.video}: use a name ending in "
                         f"{', '.join(VIDEO_SUFFIXES)}")
    if args.filmstrip and not args.filmstrip.lower().endswith(".png"):
        raise UsageError(f"--filmstrip {args.filmstrip}: use a name ending in .png")
    if args.viewer and not has_display():
        raise UsageError("--viewer needs a display (DISPLAY is not set); use --video V.mp4 "
                         "to render offscreen instead")
    config = controller_config(args).with_threads(args.threads)
    performed_setup(args)
    catalog, refs, sequence = sequence_from_args(args, args.sequence)
    motion = sequence.motion
    if args.offset_deg > 0:
        from upm.motion.perturb import offset_joint_angles

        motion = offset_joint_angles(motion, args.offset_deg, args.offset_seed)
        print(f"joint angles moved by N(0, {args.offset_deg:g} deg) per channel, seed "
              f"{args.offset_seed}")
    if motion.n_frames < 2:
        raise UsageError("the sequence has fewer than 2 frames: nothing to simulate")
    model_path = catalog_model_path(catalog, refs[0].name)
    model = load_model(model_path, strength=strength)
    if strength != 1:
        print(f"every joint's torque limit x {strength:g} (--strength)")
    window_meta = [{"method": sequence.method, "from": str(refs[k]), "to": str(refs[k + 1]),
                    "compute_s": sequence.seconds[k]} for k in range(len(sequence.windows))]
    report, results = analyse(
        model, motion, kind="simulate", windows=sequence.windows, window_meta=window_meta,
        pieces=[(str(ref), part) for ref, part in zip(refs, sequence.pieces, strict=True)],
        tracking_modes=tuple(args.modes), window_free=args.window_runs,
        model_path=model_path, controller=args.controller, progress=True,
        processes=args.processes, strength=strength, config=config, effort=args.effort)
    report["sequence"] = {"pieces": [str(r) for r in refs], "method": sequence.method,
                          "frames": sequence.frames, "alpha": args.alpha,
                          "cut": args.cut,
                          "map": args.map, "align_heading": args.align_heading,
                          "offset_deg": args.offset_deg,
                          "offset_seed": args.offset_seed if args.offset_deg > 0 else None}
    json_path, csv_path = write_report(report, args.report)

    for mode, run_ in results["tracking"].items():
        if run_.diverged_frame is not None or run_.warnings:
            warnings.warn(f"{mode} simulation: MuJoCo warnings {run_.warnings}"
                          + (f", stopped at frame {run_.diverged_frame}"
                             if run_.diverged_frame is not None else ""), stacklevel=1)
    from upm.commands.simulate_summary import print_summary

    print_summary(report, json_path, csv_path)
    if args.amc or args.control:
        free = results["tracking"]["free"]
        if args.amc:
            print(f"simulated motion: {_write_simulated_amc(model, free.qpos, motion, args.amc)}")
        if args.control:
            print(f"control: {_write_control(free.run, args.control)}")

    trajectory = (to_qpos(model, motion) if render == "reference"
                  else results["tracking"][render].qpos)
    if args.video:
        path = write_video(model, trajectory, motion.fps, args.video,
                           windows=sequence.windows)
        print(f"video ({render}): {path}")
    if args.filmstrip:
        rows = [("sequence", to_qpos(model, motion))]
        if render != "reference":
            rows.append((f"simulated ({render})", trajectory))
        path = filmstrip(model, rows, filmstrip_frames(sequence.windows, motion.n_frames),
                         args.filmstrip, fps=motion.fps, windows=sequence.windows,
                         title=f"{motion.name}: {sequence.method}, "
                               f"{sequence.frames}-frame windows")
        print(f"filmstrip: {path}")
    if args.viewer:
        play_in_viewer(model, trajectory, motion.fps)
    return 0


def _write_simulated_amc(model, qpos, motion, path):
    """The simulated frames (up to where the run stopped) as an AMC on the skeleton."""
    import numpy as np

    from controller.qpos import from_qpos
    from upm.bvh.formats import write_motion

    simulated = qpos[np.isfinite(qpos).all(axis=1)]
    write_motion(path, from_qpos(model, simulated, motion.skeleton, motion.fps,
                              name=f"{motion.name} simulated"))
    return path


def _write_control(run, path):
    """The balance run's control and start state, for controller.balance.run.replay."""
    import numpy as np

    from upm.core.fileio import atomic_path

    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez(handle, ctrl=run.ctrl, start_qpos=run.start_qpos,
                 start_qvel=run.start_qvel, timestep_s=run.timestep_s,
                 substeps=run.substeps, fps=run.fps)
    return path
