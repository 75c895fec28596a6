"""The key-posture source a method needs, from the command line's --map and --data."""

from __future__ import annotations

import warnings


def key_source_for(method: str, map_path, catalog, follow: str | None = None,
                   performer_config=None):
    """The key-posture source for ``method``, built by its registered builder
    (:func:`upm.transitions.registry.build_key_source`).

    Parameters
    ----------
    method : str
    map_path : path-like or None
        ``--map``: required by the methods whose source is a trained map (``upm``,
        ``som``, ``feasible``).
    catalog : upm.motion.catalog.Catalog
        ``--data``: ``classnn`` and ``snap`` are fitted on its train split.
    follow : str or None
        ``performed``'s followed method (``--follow``; None: ``feasible``).
    performer_config : object or None
        ``performed``'s configuration (``--config``).

    Returns
    -------
    KeyPostureSource or None
    """
    from upm.transitions.registry import KeySourceContext, build_key_source, get_method

    spec = get_method(method)
    context = KeySourceContext(catalog=catalog, map_path=map_path, follow=follow,
                               performer_config=performer_config)
    source = build_key_source(spec, context)
    if map_path is not None and not context.map_used:
        warnings.warn(f"--map is not used by --method {method}", stacklevel=2)
    return source
