"""Hand-made ASF/AMC text for tests: the CMU bone set with chosen geometry."""

from __future__ import annotations

from upm.motion.skeleton import JOINTS

#: Bones of the CMU hierarchy that are not among the 21 joints.
_OTHER = ("lhipjoint", "rhipjoint", "upperneck", "lwrist", "rwrist", "lfingers", "rfingers",
          "lthumb", "rthumb")


def make_asf(bones: dict[str, dict], hierarchy: dict[str, list[str]] | None = None,
             length_unit: float = 1.0) -> str:
    """ASF text with every 21-joint bone present.

    ``bones`` gives, per bone name, any of ``direction`` (3), ``length``, ``axis`` (3),
    ``dof`` (list) and ``limits`` (list of pairs); bones not given are zero-length,
    DOF-less children of the root. ``hierarchy`` maps parent -> children for the given
    bones (default: all children of the root).
    """
    names = list(bones) + [j for j in JOINTS if j not in bones]
    hierarchy = {k: list(v) for k, v in (hierarchy or {"root": list(bones)}).items()}
    placed = {kid for kids in hierarchy.values() for kid in kids}
    hierarchy.setdefault("root", [])
    hierarchy["root"] += [n for n in names if n not in placed]
    out = [":version 1.10", ":name TEST", ":units", "  mass 1.0", f"  length {length_unit}",
           "  angle deg", ":documentation", "  hand-made test skeleton", ":root",
           "  order TX TY TZ RX RY RZ", "  axis XYZ", "  position 0 0 0",
           "  orientation 0 0 0", ":bonedata"]
    for i, name in enumerate(names, start=1):
        spec = bones.get(name, {})
        direction = spec.get("direction", (0.0, 1.0, 0.0))
        out += ["  begin", f"    id {i}", f"    name {name}",
                "    direction " + " ".join(map(str, direction)),
                f"    length {spec.get('length', 0.0)}",
                "    axis " + " ".join(map(str, spec.get("axis", (0, 0, 0)))) + " XYZ"]
        dofs = spec.get("dof", [])
        if dofs:
            limits = spec.get("limits", [(-180, 180)] * len(dofs))
            out.append("    dof " + " ".join(dofs))
            out.append(f"    limits ({limits[0][0]} {limits[0][1]})")
            out += [f"           ({lo} {hi})" for lo, hi in limits[1:]]
        out.append("  end")
    out += [":hierarchy", "  begin"]
    out += [f"    {parent} {' '.join(kids)}" for parent, kids in hierarchy.items() if kids]
    out += ["  end", ""]
    return "\n".join(out)


def make_amc(frames: list[dict[str, list[float]]]) -> str:
    """AMC text: one dict per frame of bone -> values (the root first)."""
    out = ["#!OML:ASF test.asf", ":FULLY-SPECIFIED", ":DEGREES"]
    for number, frame in enumerate(frames, start=1):
        out.append(str(number))
        out += [f"{bone} {' '.join(map(str, values))}" for bone, values in frame.items()]
    return "\n".join(out) + "\n"
