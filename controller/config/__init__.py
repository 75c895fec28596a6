"""One frozen configuration of the free-root balance controller and the servo tracking:
every tuning constant, by section (:mod:`controller.config.sections`), passed down to the
code that uses it instead of read from module globals, written into every report
(:meth:`ControllerConfig.as_dict`) and read back from it or from a TOML file
(:meth:`ControllerConfig.from_dict`, :func:`load_config`): an experiment is a file, and a
run is reproducible from its report.

A file names only what it changes; everything else keeps its default::

    [placement]
    gain = 0.35

    [search]
    budget = 15

``[[modes]]`` tables, if any, replace the whole list of modes. An unknown key or a value
of the wrong type is a :class:`ConfigError` (a :class:`upm.core.errors.UsageError`: one
line naming the file and the key; exit code 2 on the command line).

A new section is one more field of :class:`ControllerConfig` whose type is a frozen
dataclass with defaults (the offline effort's ``offline`` section came this way):
loading, checking and writing it need nothing more.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields
from pathlib import Path

from controller.config.convert import ConfigError, from_plain, to_plain
from controller.config.offline import OfflineConfig, OfflineWeights
from controller.config.sections import (
    MODES,
    SWING_CONTACTS,
    ContactConfig,
    DropoutsConfig,
    FallsConfig,
    FootTiltConfig,
    GroundingConfig,
    LookaheadConfig,
    Mode,
    PlacementConfig,
    QPWeights,
    ReferenceConfig,
    ResidualConfig,
    SearchConfig,
    SolverConfig,
    SpineConfig,
    StepConfig,
    ToesConfig,
    TrackingConfig,
    WindowRunsConfig,
)

__all__ = ["DEFAULT", "ConfigError", "ControllerConfig", "Mode", "OfflineConfig",
           "OfflineWeights", "load_config"]


@dataclass(frozen=True)
class ControllerConfig:
    """Every tuning constant of the balance controller and the servo tracking.

    Attributes
    ----------
    step, dropouts, reference, grounding : the physics step and the reference's preparation
    tracking : the PD tracking's gains
    qp, contact, solver, spine : the whole-body QP: weights, floor contacts, the solver's
        tolerances, the spine's hold
    placement, foot_tilt, toes : the swing foot, its tilt, the toes on the floor
    modes : tuple of Mode
        The controller's modes, tried in this order where the default (the first) leads
        to trouble.
    search, lookahead : the backtracking search over the modes, the gain's lookahead
    falls, window_runs, residual : the fall rule, the free-root runs around a report's
        windows, the inverse-dynamics residual check
    offline : the offline effort's sampling search (:mod:`controller.offline`)
    """

    step: StepConfig = field(default_factory=StepConfig)
    dropouts: DropoutsConfig = field(default_factory=DropoutsConfig)
    reference: ReferenceConfig = field(default_factory=ReferenceConfig)
    grounding: GroundingConfig = field(default_factory=GroundingConfig)
    tracking: TrackingConfig = field(default_factory=TrackingConfig)
    qp: QPWeights = field(default_factory=QPWeights)
    contact: ContactConfig = field(default_factory=ContactConfig)
    solver: SolverConfig = field(default_factory=SolverConfig)
    spine: SpineConfig = field(default_factory=SpineConfig)
    placement: PlacementConfig = field(default_factory=PlacementConfig)
    foot_tilt: FootTiltConfig = field(default_factory=FootTiltConfig)
    toes: ToesConfig = field(default_factory=ToesConfig)
    modes: tuple[Mode, ...] = MODES
    search: SearchConfig = field(default_factory=SearchConfig)
    lookahead: LookaheadConfig = field(default_factory=LookaheadConfig)
    falls: FallsConfig = field(default_factory=FallsConfig)
    window_runs: WindowRunsConfig = field(default_factory=WindowRunsConfig)
    residual: ResidualConfig = field(default_factory=ResidualConfig)
    offline: OfflineConfig = field(default_factory=OfflineConfig)

    def __post_init__(self):
        problem = _problem(self)
        if problem:
            raise ConfigError(problem)

    def as_dict(self) -> dict:
        """Every field, nested dicts and lists, JSON-ready (what a report records)."""
        return to_plain(self)

    @classmethod
    def from_dict(cls, data: dict, source: str = "the controller configuration"
                  ) -> ControllerConfig:
        """The configuration ``data`` describes (a report's ``controller_config``, or the
        keys a file changes: the others keep their defaults).

        Raises
        ------
        ConfigError
            Naming ``source`` and the key, for an unknown key, a value of the wrong type
            or an inconsistent value.
        """
        return DEFAULT.updated(data, source)

    def updated(self, data: dict, source: str = "the controller configuration"
                ) -> ControllerConfig:
        """This configuration with the keys of ``data`` (nested like :meth:`as_dict`)
        changed."""
        try:
            return from_plain(ControllerConfig, data, source, base=self)
        except ConfigError as exc:
            text = str(exc)
            raise ConfigError(text if text.startswith(f"{source}: ")
                              else f"{source}: {text}") from None

    def with_search_budget(self, budget: float | None) -> ControllerConfig:
        """This configuration with the search's budget ``budget`` (None: unchanged)."""
        if budget is None:
            return self
        return self.updated({"search": {"budget": float(budget)}})

    def with_threads(self, threads: int | None) -> ControllerConfig:
        """This configuration with the offline search's ``threads`` (None: unchanged)."""
        if threads is None:
            return self
        return self.updated({"offline": {"threads": int(threads)}})

    @property
    def gains(self) -> tuple[float, ...]:
        """The foot-placement gains the lookahead chooses among, the default first."""
        return (self.placement.gain, *self.lookahead.other_gains)

    def mode_gain(self, mode: Mode) -> float:
        """A mode's foot-placement gain (its own, else :attr:`PlacementConfig.gain`)."""
        return self.placement.gain if mode.placement_gain is None else mode.placement_gain


def load_config(path) -> ControllerConfig:
    """The configuration of a TOML file (the keys it names; the rest the defaults).

    Raises
    ------
    ConfigError
        ``"FILE: ..."``: the file is missing or unreadable, not TOML (with its line), has
        an unknown key or a value of the wrong type (naming the key).
    """
    try:
        import tomllib
    except ImportError:  # Python 3.10
        import tomli as tomllib

    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ConfigError(f"{path}: cannot read the configuration ({reason})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not a TOML file: {exc}") from None
    return ControllerConfig.from_dict(data, source=str(path))


def _positive(x) -> bool:
    return x > 0


def _share(x) -> bool:
    return 0 < x <= 1


#: Values that must hold whatever the file says: (section, key, test, what it must be).
_RULES = (
    ("step", "max_step_s", _positive, "above 0"),
    ("reference", "lowpass_hz", _positive, "above 0"),
    ("grounding", "shift_hz", _positive, "above 0"),
    ("residual", "lowpass_hz", _positive, "above 0"),
    ("residual", "support_distance_m", lambda x: x >= 0, "at least 0"),
    ("search", "segment_s", _positive, "above 0"),
    ("search", "sticky_s", lambda x: x >= 0, "at least 0"),
    ("search", "max_backtrack", lambda x: x >= 0, "at least 0"),
    ("search", "budget", lambda x: x >= 0, "at least 0 (0: no search)"),
    ("lookahead", "every_s", _positive, "above 0"),
    ("lookahead", "horizon_s", _positive, "above 0"),
    ("falls", "fraction", _share, "above 0 and at most 1"),
    ("falls", "after_fall_s", lambda x: x >= 0, "at least 0"),
    ("offline", "segment_s", _positive, "above 0"),
    ("offline", "samples", _positive, "above 0"),
    ("offline", "keep", _positive, "above 0"),
    ("offline", "sigma_deg", lambda x: x >= 0, "at least 0"),
    ("offline", "upper_sigma_share", lambda x: 0 <= x <= 1, "from 0 to 1"),
    ("offline", "performed_upper_sigma_share", lambda x: 0 <= x <= 1, "from 0 to 1"),
    ("offline", "coherence", lambda x: 0 <= x <= 1, "from 0 to 1"),
    ("offline", "trouble_cost", _positive, "above 0"),
    ("offline", "backtracks", lambda x: x >= 0, "at least 0"),
    ("offline", "fall_cost", lambda x: x >= 0, "at least 0"),
    ("offline", "lookahead_s", lambda x: x >= 0, "at least 0 (0: none)"),
    ("offline", "lookahead_top", _positive, "above 0"),
    ("offline", "lookahead_weight", lambda x: x >= 0, "at least 0"),
    ("offline", "budget", lambda x: x >= 1, "at least 1 (one pass)"),
    ("offline", "threads", lambda x: 1 <= x <= 64, "from 1 to 64"),
    ("offline", "seed", lambda x: x >= 0, "at least 0"),
)


def _problem(config: ControllerConfig) -> str | None:
    """What is inconsistent in ``config`` (``"key: ..."``), or None."""
    for section, key, test, must in _RULES:
        value = getattr(getattr(config, section), key)
        if not test(value):
            return f"{section}.{key} must be {must}, not {value!r}"
    for key in ("pose", "root", "height", "end", "balance"):
        if getattr(config.offline.weights, key) < 0:
            return (f"offline.weights.{key} must be at least 0, not "
                    f"{getattr(config.offline.weights, key)!r}")
    if config.offline.keep > config.offline.samples:
        return (f"offline.keep ({config.offline.keep}) must be at most offline.samples "
                f"({config.offline.samples})")
    if not config.modes:
        return "modes: give at least one mode (the first is the default)"
    for i, mode in enumerate(config.modes):
        if mode.swing_contacts_excluded not in SWING_CONTACTS:
            return (f"modes[{i}].swing_contacts_excluded must be one of "
                    f"{', '.join(repr(s) for s in SWING_CONTACTS)}, not "
                    f"{mode.swing_contacts_excluded!r}")
    sweep = config.search.sweep_modes
    if list(sweep) != sorted(set(sweep)) or any(not 1 <= m < len(config.modes) for m in sweep):
        return (f"search.sweep_modes must be ascending indices of modes other than the "
                f"default (1 to {len(config.modes) - 1}), not {list(sweep)}")
    if not config.spine.free_m > config.spine.held_m:
        return (f"spine.free_m ({config.spine.free_m:g}) must be above spine.held_m "
                f"({config.spine.held_m:g})")
    if not all(math.isfinite(g) for g in config.gains):
        return "lookahead.other_gains must be finite numbers"
    return None


DEFAULT = ControllerConfig()

#: The sections (the fields of :class:`ControllerConfig`), in order.
SECTIONS = tuple(f.name for f in fields(ControllerConfig))
