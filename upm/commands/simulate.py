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
    _print_summary(report, json_path, csv_path)
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


def _search_line(troubles: list) -> str:
    """The balance controller's search in one line: its troubles, what it spent, and
    where it gave up (and why)."""
    given_up = [r for r in troubles if r["outcome"] != "got past"]
    line = (f"  search: {len(troubles)} trouble{'' if len(troubles) == 1 else 's'} "
            f"(first at {troubles[0]['time_s']:.2f} s), "
            f"{sum(r['retries'] for r in troubles)} retries running "
            f"{sum(r['rerun_s'] for r in troubles):.1f} simulated s again; got past "
            f"{len(troubles) - len(given_up)}")
    by_mode = [r.get("rerun_s_by_mode") for r in troubles]
    if all(by_mode):  # every trouble has them (a report of before had none): not a part sum
        seconds = [sum(column) for column in zip(*by_mode, strict=True)]
        line += (f" (seconds run again by the mode tried, 0-{len(seconds) - 1}: "
                 + " / ".join(f"{x:.1f}" for x in seconds) + ")")
    if given_up:
        line += "; gave up at " + ", ".join(
            f"{r['time_s']:.2f} s ({' and '.join(r['cause'])}: {r['outcome']})"
            for r in given_up)
    return line


def _by_mode_line(free: dict) -> str:
    """Where the free run's error comes from, in one line: the frames run in a mode the
    search changed against those in the default mode ("" when the report has no such
    split, or no frame was changed)."""
    share = free.get("search_mode_share")
    if not share:
        return ""

    def errors(part: str) -> str:
        deg, mm = free.get(f"error_deg_rms_{part}"), free.get(f"body_error_mm_mean_{part}")
        return "-" if deg is None or mm is None else f"{deg:.1f} deg / {mm:.0f} mm"

    return (f"  error by mode: the {100 * share:.0f} % of the frames the search changed "
            f"{errors('search_modes')}, the rest (the default mode) "
            f"{errors('default_mode')}")


def _strength_line(by_actuator: dict, most: int = 3) -> str:
    """The actuators most often at their strength, in one line ("" when none is), each
    with the share of those frames at which its joint turned the way it pushed
    (concentric: where a real muscle holds less than its isometric strength)."""
    at = sorted(((v["saturation_share"], name) for name, v in by_actuator.items()
                 if v["saturation_share"] > 0), reverse=True)[:most]
    if not at:
        return ""
    concentric = [by_actuator[name].get("saturated_concentric_share") for _, name in at]
    if any(c is None for c in concentric):
        return ("  at full strength most often: "
                + ", ".join(f"{name} {100 * share:.1f} %" for share, name in at)
                + " of the frames")
    return ("  at full strength most often (share of the frames; of those, concentric: the "
            "joint turning the way it pushes): "
            + ", ".join(f"{name} {100 * share:.1f} % ({100 * c:.0f} %)"
                        for (share, name), c in zip(at, concentric, strict=True)))


def _print_summary(report: dict, json_path, csv_path) -> None:
    m = report["motion"]
    seq = report["sequence"]
    print(f"{m['name']}: {m['frames']} frames at {m['fps']:g} fps, method {seq['method']}, "
          f"{seq['frames']}-frame windows, on a {m['mass_kg']:.1f} kg humanoid")
    rows = [("all", report["totals"])]
    rows += [(f"window {w['index']} ({w['start']}-{w['stop'] - 1})", w)
             for w in report["windows"]]
    for label, part in rows:
        k = part["kinematic"]
        line = (f"  {label:<24} valid {k['valid_pct']:5.1f} %  limit "
                f"{k['limit_violation_pct']:5.1f} %  self {k['self_collision_pct']:5.1f} %  "
                f"floor {k['floor_penetration_pct']:5.1f} %")
        if "added_excess_peak_deg" in k and label != "all":
            line += f"  added excess peak {k['added_excess_peak_deg']:.2f} deg"
        if "dynamics" in part:
            line += f"  residual {part['dynamics']['residual_force_bw_mean']:.3f} bw"
        tracking = part.get("tracking", {})
        if "driven" in tracking and tracking["driven"].get("error_deg_rms") is not None:
            line += f"  driven error {tracking['driven']['error_deg_rms']:.2f} deg"
        if "free_window" in tracking:
            line += "  free run: " + ("falls" if tracking["free_window"]["fell"] else "stands")
        print(line)
    free = report["totals"].get("tracking", {}).get("free")
    if free is not None:
        line = "  free root" + (f" ({free['controller']})" if "controller" in free else "")
        line += ": " + (f"falls at {free['fall_time_s']:.2f} s" if free["fell"]
                        else "does not fall")
        if free.get("ends_in_trouble") and not free["fell"]:
            line += " but ends in trouble (going down where the sequence ends)"
        if free.get("trouble_time_s"):
            line += f", {free['trouble_time_s']:.2f} s in trouble"
        if free.get("body_error_mm_mean") is not None:
            line += (f", joint error {free['error_deg_rms']:.1f} deg RMS, body error "
                     f"{free['body_error_mm_mean']:.0f} mm mean, root drift "
                     f"{free['root_drift_m']:.2f} m, heading off by up to "
                     f"{free['heading_error_deg_peak']:.0f} deg, "
                     f"{free['wall_s_per_sim_s']:.2f} wall s per simulated s")
        print(line)
        if free["fell"] and seq.get("cut") == "whole" and len(seq["pieces"]) > 1:
            print("  (the pieces are joined whole, wherever in its stride each ends or "
                  "begins: --cut matched joins each where the next one's gait phase matches)")
        if free.get("search_troubles"):
            print(_search_line(free["search_troubles"]))
            split = _by_mode_line(free)
            if split:
                print(split)
        strength = _strength_line(free.get("torque_by_actuator", {}))
        if strength:
            print(strength)
    print(f"report: {json_path} (summary {csv_path})")
