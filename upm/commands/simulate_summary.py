"""What ``upm simulate`` prints of its report: the summary per part, the free-root run, the
search, the strength, and the real-time controller's run an offline search started from."""

from __future__ import annotations


def realtime_line(realtime: dict) -> str:
    """The real-time controller's run an offline search started from, in a line."""
    if realtime["fell"]:
        outcome = f"falls at {realtime['fall_time_s']:.2f} s"
    else:
        outcome = "does not fall" + (" but ends in trouble" if realtime["ends_in_trouble"]
                                     else "")
    if realtime.get("error_deg_rms") is not None:
        outcome += f", joint error {realtime['error_deg_rms']:.1f} deg RMS"
    return f"  the real-time controller, whose run the search started from: {outcome}"


def search_line(troubles: list) -> str:
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


def by_mode_line(free: dict) -> str:
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


def strength_line(by_actuator: dict, most: int = 3) -> str:
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


def print_summary(report: dict, json_path, csv_path) -> None:
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
        if free.get("realtime"):
            print(realtime_line(free["realtime"]))
        if free["fell"] and seq.get("cut") == "whole" and len(seq["pieces"]) > 1:
            print("  (the pieces are joined whole, wherever in its stride each ends or "
                  "begins: --cut matched joins each where the next one's gait phase matches)")
        if free.get("search_troubles"):
            print(search_line(free["search_troubles"]))
            split = by_mode_line(free)
            if split:
                print(split)
        strength = strength_line(free.get("torque_by_actuator", {}))
        if strength:
            print(strength)
    print(f"report: {json_path} (summary {csv_path})")
