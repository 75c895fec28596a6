"""The transition methods by name, and how each one's key source is built: one registry.

A method is a :class:`~upm.transitions.base.TransitionMethod`. A key-posture method also
carries its ``key_source`` builder, which gets a :class:`KeySourceContext` (the catalogue,
the ``--map`` file or the study's cached maps, the training postures) and returns the
source. So a new method is one module plus one line in :data:`_BUILT_IN` below (or one
:func:`register` call at run time), and ``upm transition / sequence / simulate / eval /
bench``, the studio and the study all pick it up through :data:`METHODS`,
:func:`get_method` and :func:`build_key_source`.

This module imports the method modules and nothing that imports it back
(:mod:`upm.transitions.join` imports this one), so there is no import cycle.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, replace

import numpy as np

from upm.core.errors import UsageError
from upm.transitions import (
    feasible,
    inertialize,
    keyposture,
    linear,
    performed,
    slerp,
    spacetime,
)
from upm.transitions.base import KeyPostureSource, TransitionMethod


def _performed_key_source(context):
    """``performed``'s key source: the followed method's, built by this registry."""
    return performed.key_source_of(context, get_method, build_key_source)


#: The methods the project ships, in table order.
_BUILT_IN: tuple[TransitionMethod, ...] = (
    keyposture.UPM, keyposture.SOM, keyposture.CLASSNN, keyposture.SNAP, linear.METHOD,
    slerp.METHOD, inertialize.METHOD, spacetime.METHOD, feasible.METHOD,
    replace(performed.METHOD, key_source=_performed_key_source),
)

#: Every transition method, by name (registration order).
METHODS: dict[str, TransitionMethod] = {}


def register(method: TransitionMethod) -> TransitionMethod:
    """Add a method to :data:`METHODS` (UsageError if the name is taken).

    Returns
    -------
    TransitionMethod
        ``method``, so that a module can write ``METHOD = register(TransitionMethod(...))``.
    """
    if not isinstance(method, TransitionMethod):
        raise UsageError(f"register() takes a TransitionMethod, not {type(method).__name__}")
    if method.name in METHODS:
        raise UsageError(f"a transition method called {method.name!r} is already registered")
    if method.needs_key_source and method.key_source is None:
        raise UsageError(f"method {method.name!r} has a key kind but no key_source builder")
    METHODS[method.name] = method
    return method


def unregister(name: str) -> None:
    """Remove a method added by :func:`register` (the built-in ones stay)."""
    if any(m.name == name for m in _BUILT_IN):
        raise UsageError(f"{name!r} is a built-in method")
    METHODS.pop(name, None)


def get_method(name: str) -> TransitionMethod:
    """The registered method called ``name`` (UsageError listing them if unknown)."""
    try:
        return METHODS[name]
    except KeyError:
        raise UsageError(f"no transition method {name!r} (methods: {', '.join(METHODS)})") from None


def map_free_methods() -> list[str]:
    """Methods that need no ``--map`` (no key source, or one built from the data)."""
    return [n for n, m in METHODS.items() if not m.needs_map]


def methods_with_role(role: str) -> list[str]:
    """The registered methods of one role (:data:`upm.transitions.base.ROLES`), in
    registration order."""
    return [n for n, m in METHODS.items() if m.role == role]


@dataclass
class KeySourceContext:
    """What a key-source builder may use; shared by the methods of one command or study,
    so that a map or the training postures are loaded once.

    Attributes
    ----------
    catalog : upm.motion.catalog.Catalog or None
        The data (``--data``): the train split of ``clips.csv``, the subjects.
    map_path : path-like or None
        ``--map``: a saved posture map.
    train_maps : bool
        Without ``map_path``, train the maps on the train split (cached by
        :func:`upm.maps.map_cache.trained_map`) instead of failing: the study and the bench.
    progress : bool
        Progress bars while training maps.
    train_step : int
        Every ``train_step``-th training frame for the sources fitted on postures.
    method : str
        The method being built (set by :func:`build_key_source`; for error messages).
    map_used : bool
        Whether a builder read ``map_path`` (``--map`` given but unused is warned about).
    follow : str or None
        ``performed``'s followed method (``--follow``; None: ``feasible``).
    performer_config : object or None
        ``performed``'s performer configuration (a
        :class:`controller.config.ControllerConfig`, ``--config``; None: the defaults).
    """

    catalog: object | None = None
    map_path: str | os.PathLike | None = None
    train_maps: bool = False
    progress: bool = False
    train_step: int = 1
    method: str = ""
    map_used: bool = False
    follow: str | None = None
    performer_config: object | None = None
    _maps: dict = field(default_factory=dict, repr=False)
    _postures: np.ndarray | None = field(default=None, repr=False)

    def posture_map(self, kind: str):
        """The posture map of ``kind`` ("upm" or "som"): ``--map``, or trained (cached)."""
        if kind in self._maps:
            return self._maps[kind]
        if self.map_path is not None:
            source = self._load_map(kind)
        elif self.train_maps:
            from upm.maps.map_cache import trained_map

            source = trained_map(self._require_catalog(), kind, progress=self.progress)
        else:
            raise UsageError(f"--method {self.method} needs --map MAP.npz (train one with "
                             f"'upm train --kind {kind} --out MAP.npz'), or use a method "
                             f"without a map: {', '.join(map_free_methods())}")
        self._maps[kind] = source
        return source

    def _load_map(self, kind: str):
        from upm.maps.map_file import MAP_KINDS, load_map

        if kind not in MAP_KINDS:
            raise UsageError(f"no map kind {kind!r} (known: {', '.join(MAP_KINDS)})")
        if not os.path.isfile(self.map_path):
            raise UsageError(f"--map {self.map_path}: no such file")
        source = load_map(self.map_path)
        found = getattr(source, "kind", None)
        if isinstance(found, str) and found != kind:
            raise UsageError(f"{self.map_path} holds a {found!r} map; --method {self.method} "
                             f"needs a {kind!r} one")
        self.map_used = True
        return source

    def training_postures(self) -> np.ndarray:
        """Every ``train_step``-th frame of the train split's clips, (N, 63) degrees."""
        if self._postures is None:
            from upm.transitions.sources import training_postures

            self._postures = training_postures(self._require_catalog(), "train",
                                               self.train_step)
        return self._postures

    def _require_catalog(self):
        if self.catalog is None:
            raise UsageError(f"--method {self.method} needs the data (--data) for its key "
                             "source")
        return self.catalog


def build_key_source(method: str | TransitionMethod, context: KeySourceContext):
    """The key source of a method, built from ``context`` (None for methods without one).

    Raises
    ------
    UsageError
        When what the builder needs is missing (e.g. ``--map``).
    """
    spec = get_method(method) if isinstance(method, str) else method
    if not spec.needs_key_source:
        return None
    context.method = spec.name
    source = spec.key_source(context)
    if not isinstance(source, KeyPostureSource):
        raise UsageError(f"the key-source builder of {spec.name!r} returned a "
                         f"{type(source).__name__}, not a key-posture source")
    return source


for _method in _BUILT_IN:
    register(_method)
