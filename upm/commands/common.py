"""Arguments and output helpers shared by several subcommands."""

from __future__ import annotations

import json
import sys


def add_data_argument(parser) -> None:
    """``--data DIR``: the clips' directory (:func:`upm.motion.catalog.default_data_dir`)."""
    parser.add_argument(
        "--data", metavar="DIR", default=None,
        help="directory of CMU clips (NN/NN.asf, NN/NN_MM.amc, clips.csv); "
        "default: $UPM_DATA, else shared/data/cmu beside the checkout (../shared/data/cmu "
        "from the repository root)",
    )


#: The largest --strength the commands accept.
MAX_STRENGTH = 10.0


def add_limits_argument(parser) -> None:
    """``--limits human|asf|FILE``: the range-of-motion model of the verdict."""
    parser.add_argument("--limits", default="human", metavar="human|asf|FILE",
                        help="the range of motion judged: 'human' (default: anatomical "
                             "ranges from the literature, hips and shoulders coupled), "
                             "'asf' (the ASF's declared boxes), or a JSON file "
                             "{\"model\": \"human\", \"ranges\": {rule: [low, high]}}")


def add_strength_argument(parser) -> None:
    """``--strength K``: every joint's torque limit times K (:func:`check_strength`)."""
    parser.add_argument(
        "--strength", metavar="K", type=float, default=1.0,
        help="multiply every joint's torque limit by K (default 1: the strength tables' "
             "strong adult, mean + 2 SD of measured isometric peaks); e.g. 1.5 asks whether "
             "a stronger body could do it")


def check_strength(value: float) -> float:
    """``value`` if it is a usable ``--strength``, else a :class:`upm.core.errors.UsageError`."""
    import math

    from upm.core.errors import UsageError

    if not (math.isfinite(value) and 0 < value <= MAX_STRENGTH):
        raise UsageError(f"--strength {value:g}: use a number above 0 and at most "
                         f"{MAX_STRENGTH:g}")
    return float(value)


def add_config_argument(parser, used: str) -> None:
    """``--config FILE.toml``: the controller's tuning constants (:func:`controller_config`);
    ``used``: what they set in this command, for the help."""
    parser.add_argument(
        "--config", metavar="FILE.toml", default=None,
        help=f"tuning constants of {used}, from a TOML file: the keys it names change, "
             "the others keep their defaults, and the report records them all (default: "
             "no file, the built-in constants)")


def controller_config(args, unused=()):
    """The :class:`controller.config.ControllerConfig` of ``--config`` (the defaults
    without it), its search budget replaced by ``--search-budget`` where given.

    Raises
    ------
    controller.config.ConfigError
        A :class:`upm.core.errors.UsageError`: one line naming the file and the key (an
        unknown key, a value of the wrong type, a file that is not TOML), or a section of
        ``unused`` (names of sections this command does not use) changed by the file.
    """
    from controller.config import DEFAULT, ConfigError, load_config

    if args.config is None:
        config = DEFAULT
    else:
        config = load_config(args.config)
        changed = [name for name in unused if getattr(config, name) != getattr(DEFAULT, name)]
        if changed:
            raise ConfigError(f"{args.config}: [{changed[0]}] is not used by upm "
                             f"{args.command} (remove it: this command's runs keep its "
                             "defaults)")
    return config.with_search_budget(getattr(args, "search_budget", None))


def add_effort_arguments(parser) -> None:
    """``--effort realtime|offline`` and ``--threads N``: the free-root runs' effort
    (:func:`check_effort`)."""
    parser.add_argument(
        "--effort", choices=["realtime", "offline"], default="realtime",
        help="the free-root runs: 'realtime' (default) the real-time controller of "
             "--controller; 'offline' a sampling search over the servos' targets that asks "
             "whether the body can perform the motion at all (no root force; the "
             "configuration's [offline] section; tens of wall s per simulated s)")
    parser.add_argument(
        "--threads", metavar="N", type=int, default=None,
        help="threads of the offline effort's rollouts (default: [offline] threads, 2; "
             "the results do not depend on it)")


def check_effort(args) -> None:
    """A :class:`upm.core.errors.UsageError` for options that do not go with ``--effort``."""
    from upm.core.errors import UsageError

    if args.threads is not None and not 1 <= args.threads <= 64:
        raise UsageError(f"--threads {args.threads}: use a whole number from 1 to 64")
    if args.effort != "offline":
        if args.threads is not None:
            raise UsageError("--threads is the offline effort's: add --effort offline")
        return
    for flag, used in (("--search-budget", getattr(args, "search_budget", None) is not None),
                       ("--control", bool(getattr(args, "control", None))),
                       ("--controller servo", getattr(args, "controller", None) == "servo")):
        if used:
            raise UsageError(f"{flag} is the real-time controller's: drop it with --effort "
                             "offline (its budget is [offline] budget in --config)")


def add_performed_config_argument(parser) -> None:
    """``--config FILE.toml`` of ``upm transition`` / ``upm sequence``: the ``performed``
    method's configuration (:func:`performed_setup`)."""
    parser.add_argument(
        "--config", metavar="FILE.toml", default=None,
        help="with --method performed: the humanoid's configuration (its [offline] section "
             "sets the search), from a TOML file (default: the built-in constants)")


def performed_setup(args):
    """For ``--method performed``: install the humanoid's performer and return its
    configuration (``--config``'s, else the defaults; ``args.performer_config`` too);
    for other methods a :class:`upm.core.errors.UsageError` if ``--follow`` or (where the
    command's ``--config`` is only the performer's) ``--config`` is given; None."""
    from upm.core.errors import UsageError

    own_config = args.command in ("transition", "sequence")
    if args.method != "performed":
        if getattr(args, "follow", None) is not None:
            raise UsageError("--follow goes with --method performed")
        if own_config and getattr(args, "config", None) is not None:
            raise UsageError("--config sets the humanoid of --method performed: it goes "
                             "with that method")
        args.performer_config = None
        return None
    from controller.offline.performer import install

    install()
    config = controller_config(args)
    if not own_config:
        config = config.with_threads(getattr(args, "threads", None))
    args.performer_config = config
    return config


def print_json(obj) -> None:
    """Print ``obj`` as indented JSON on stdout."""
    json.dump(obj, sys.stdout, indent=2)
    sys.stdout.write("\n")


def format_table(rows: list[dict], columns: list[tuple[str, str, str]]) -> str:
    """A plain-text table.

    Parameters
    ----------
    rows : list of dict
    columns : list of (key, header, format)
        ``format`` is a format spec such as ``">8.1f"`` or ``"<12"``.
    """
    cells = [[format(row[key], fmt.lstrip("<>^")) for key, _, fmt in columns] for row in rows]
    widths = [max([len(h)] + [len(c[i]) for c in cells]) for i, (_, h, _) in enumerate(columns)]
    align = [">" if fmt.startswith(">") else "<" for _, _, fmt in columns]

    def line(values):
        return "  ".join(f"{v:{a}{w}}" for v, a, w in zip(values, align, widths, strict=True))

    out = [line([h for _, h, _ in columns]), line(["-" * w for w in widths])]
    out += [line(c) for c in cells]
    return "\n".join(out)
