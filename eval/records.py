"""Results as one long-form table: (kind, id, window, method, metric, value) rows.

Every row names its metric, and the table knows the registry of metrics it may hold: a
misspelt or unknown metric is refused when the row is added, not when a writer meets it
four dictionaries deep. Writers read the table through :meth:`Records.values` (one array
per kind x window x method x metric, ordered by id) and write it with one CSV writer
(:meth:`Records.to_csv`).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping

import numpy as np

#: Row kinds: a transition pair, or a real window of a test clip (method ``"real"``).
KINDS = ("pair", "real")
#: The method name of the real-window rows.
REAL = "real"
COLUMNS = ("kind", "id", "window", "method", "metric", "value")


class Records:
    """A long-form results table.

    Parameters
    ----------
    metrics : iterable of str
        The metric names rows may carry (the registry of the study that fills it).
    """

    def __init__(self, metrics: Iterable[str]):
        self.metrics = tuple(metrics)
        self._known = frozenset(self.metrics)
        self._rows: dict[tuple[str, int, int, str, str], float] = {}

    def __len__(self) -> int:
        return len(self._rows)

    def add(self, kind: str, index: int, window: int, method: str,
            values: Mapping[str, float]) -> None:
        """Add one unit's metrics (a pair x method x window, or a real window).

        Raises
        ------
        KeyError
            If a metric is not in the registry, or the kind is unknown.
        """
        if kind not in KINDS:
            raise KeyError(f"row kind {kind!r} is not one of {KINDS}")
        unknown = sorted(set(values) - self._known)
        if unknown:
            raise KeyError(f"metric {unknown[0]!r} is not in the registry "
                           f"({', '.join(self.metrics)})")
        for metric, value in values.items():
            self._rows[(kind, int(index), int(window), method, metric)] = float(value)

    def rows(self) -> list[tuple]:
        """Every row, sorted: (kind, id, window, method, metric, value)."""
        order = {m: i for i, m in enumerate(self.metrics)}
        keys = sorted(self._rows, key=lambda k: (KINDS.index(k[0]), k[2], k[3], k[1],
                                                 order[k[4]]))
        return [(*k, self._rows[k]) for k in keys]

    def ids(self, kind: str, window: int, method: str) -> list[int]:
        """The ids that have rows for ``kind``, ``window`` and ``method``, ascending."""
        return sorted({k[1] for k in self._rows
                       if k[0] == kind and k[2] == window and k[3] == method})

    def values(self, kind: str, window: int, method: str, metric: str,
               ids: Iterable[int] | None = None) -> np.ndarray:
        """One metric over ids (all of them, ascending, by default), shape (N,).

        Raises
        ------
        KeyError
            If the metric is not in the registry, or a requested row is missing.
        """
        if metric not in self._known:
            raise KeyError(f"metric {metric!r} is not in the registry "
                           f"({', '.join(self.metrics)})")
        chosen = self.ids(kind, window, method) if ids is None else list(ids)
        return np.array([self._rows[(kind, i, window, method, metric)] for i in chosen],
                        dtype=float)

    def to_csv(self) -> str:
        """The table as CSV (header :data:`COLUMNS`; an empty value for NaN)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(COLUMNS)
        for kind, index, window, method, metric, value in self.rows():
            writer.writerow([kind, index, window, method, metric,
                             "" if math.isnan(value) else f"{value:.6g}"])
        return buffer.getvalue()
