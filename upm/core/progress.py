"""Progress bars: on stderr, and only when stderr is a terminal."""

from __future__ import annotations

import sys

from tqdm import tqdm


def progress(iterable=None, **kwargs):
    """``tqdm`` on stderr, disabled when stderr is not a terminal (``disable=None``), so
    that a failing command's stderr is its one-line error."""
    kwargs.setdefault("disable", None)
    kwargs.setdefault("file", sys.stderr)
    kwargs.setdefault("leave", False)
    kwargs.setdefault("dynamic_ncols", True)
    return tqdm(iterable, **kwargs)
