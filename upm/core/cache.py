"""Where derived data (subject models, trained maps) is cached: outside the repository.

``$UPM_CACHE`` if set, else ``$XDG_CACHE_HOME/upm-controller``, else
``~/.cache/upm-controller``. Cached files are keyed by a digest of their inputs, so a
changed input never reuses a stale result.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path


def cache_dir(*parts: str) -> Path:
    """The cache directory (or a subdirectory of it), created if missing."""
    base = os.environ.get("UPM_CACHE")
    if base:
        root = Path(base)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        root = (Path(xdg) if xdg else Path.home() / ".cache") / "upm-controller"
    path = root.joinpath(*parts)
    path.mkdir(parents=True, exist_ok=True)
    return path


def digest(*items: bytes | str, length: int = 16) -> str:
    """A short hex digest of some inputs (file contents, parameters, code versions)."""
    h = hashlib.sha256()
    for item in items:
        data = item.encode("utf-8") if isinstance(item, str) else item
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()[:length]
