"""MuJoCo's warnings during a simulation: collected into the result instead of printed
(MuJoCo's own handler prints and appends to MUJOCO_LOG.TXT in the working directory)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

#: MuJoCo warnings after which the state is no longer the simulation's (MuJoCo resets it).
FATAL_WARNINGS = ("mjWARN_BADQPOS", "mjWARN_BADQVEL", "mjWARN_BADQACC")


@contextlib.contextmanager
def collected_warnings() -> Iterator[list[str]]:
    """Within the block, MuJoCo's warning texts are appended to the list yielded (one
    line each) instead of printed; the previous handler is restored after."""
    import mujoco

    messages: list[str] = []
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda text: messages.append(" ".join(str(text).split())))
    try:
        yield messages
    finally:
        mujoco.set_mju_user_warning(previous)


def warning_counts(data) -> dict[str, int]:
    """MuJoCo's warning counters of ``data`` that are not zero, by name."""
    import mujoco

    out = {}
    for name in mujoco.mjtWarning.__members__:
        if name == "mjNWARNING":
            continue
        count = int(data.warning[int(getattr(mujoco.mjtWarning, name))].number)
        if count:
            out[name] = count
    return out


def fatal(data) -> bool:
    """Whether MuJoCo has warned of a bad qpos, qvel or qacc in ``data``."""
    import mujoco

    return any(data.warning[int(getattr(mujoco.mjtWarning, w))].number for w in FATAL_WARNINGS)
