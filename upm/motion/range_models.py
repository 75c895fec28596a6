"""The range-of-motion models a verdict can use, by name: ``human`` (the default), ``asf``,
or a JSON file (``--limits FILE``).

A model turns postures into a table of degrees beyond its rules, one column per rule:
``human`` has the anatomical rules of :mod:`upm.motion.human_rom`; ``asf`` the 63
posture DOFs' boxes the ASF declares (the CMU README's nominal limits). A file gives
``{"model": "human" | "asf", "ranges": {rule: [low, high], ...}}``: the named model with
some box rules replaced (for a hip or shoulder plane, ``"lfemur.swing@45": [0, 110]``).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from upm.core.errors import UsageError
from upm.motion import human_rom
from upm.motion.limits import limit_excess_deg
from upm.motion.skeleton import POSTURE_DOF_NAMES, Skeleton

#: The built-in models' names; the first is the default.
MODEL_NAMES: tuple[str, ...] = ("human", "asf")


@dataclass(frozen=True)
class RangeModel:
    """A range-of-motion model.

    Attributes
    ----------
    name : str
        ``"human"``, ``"asf"``, or the file it was read from.
    base : str
        ``"human"`` or ``"asf"``.
    overrides : dict of str to (float, float)
        Rules replaced by a file, degrees.
    """

    name: str
    base: str
    overrides: dict = field(default_factory=dict)

    @property
    def rule_names(self) -> tuple[str, ...]:
        """The columns of :meth:`excess_deg`."""
        return human_rom.RULES if self.base == "human" else POSTURE_DOF_NAMES

    def excess_deg(self, skeleton: Skeleton, posture_deg) -> np.ndarray:
        """Degrees beyond each rule, (T, len(rule_names)), non-negative."""
        posture = np.atleast_2d(np.asarray(posture_deg, dtype=float))
        if self.base == "asf":
            limits = np.array(skeleton.limits_deg)
            for rule, box in self.overrides.items():
                limits[POSTURE_DOF_NAMES.index(rule)] = box
            return limit_excess_deg(posture, limits)
        ranges = {**human_rom.TRAIN_WIDENED, **self.overrides}
        return human_rom.human_excess_deg(skeleton, posture, ranges)


def asf_excess_deg(skeleton: Skeleton, posture_deg) -> np.ndarray:
    """Degrees beyond the ASF's declared boxes (the reported column), (T, 63)."""
    return limit_excess_deg(np.atleast_2d(posture_deg), skeleton.limits_deg)


def range_model(spec: str | RangeModel | None = None) -> RangeModel:
    """The model called ``spec`` (``"human"``, ``"asf"``) or read from a JSON file.

    Raises
    ------
    UsageError
        One line naming the file or the unknown name.
    """
    if isinstance(spec, RangeModel):
        return spec
    spec = MODEL_NAMES[0] if spec is None else str(spec)
    if spec in MODEL_NAMES:
        return RangeModel(name=spec, base=spec)
    if not os.path.isfile(spec):
        raise UsageError(f"--limits {spec}: neither a model ({', '.join(MODEL_NAMES)}) nor "
                         "a file")
    return _read_file(spec)


def _read_file(path: str) -> RangeModel:
    try:
        with open(path, encoding="utf-8") as handle:
            data = json.load(handle)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise UsageError(f"{path}: not a JSON range file ({error})") from None
    if not isinstance(data, dict) or data.get("model", "human") not in MODEL_NAMES:
        raise UsageError(f"{path}: 'model' must be one of {', '.join(MODEL_NAMES)}")
    base = data.get("model", "human")
    ranges = data.get("ranges", {})
    if not isinstance(ranges, dict):
        raise UsageError(f"{path}: 'ranges' must map rule names to [low, high]")
    known = set(human_rom.RULES if base == "human" else POSTURE_DOF_NAMES)
    overrides = {}
    for rule, box in ranges.items():
        name = rule.split("@")[0] if base == "human" else rule
        if name not in known:
            raise UsageError(f"{path}: no {base} rule {rule!r}")
        if (not isinstance(box, list) or len(box) != 2
                or not all(isinstance(v, (int, float)) for v in box) or box[0] > box[1]):
            raise UsageError(f"{path}: {rule} must be [low, high] degrees, low <= high")
        overrides[rule] = (float(box[0]), float(box[1]))
    return RangeModel(name=path, base=base, overrides=overrides)
