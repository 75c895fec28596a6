"""Results as one long-form table: (kind, id, window, method, metric, value) rows.

Every row names its metric, and the table knows the registry of metrics it may hold: a
misspelt or unknown metric is refused when the row is added or asked for, not when a writer
meets it four dictionaries deep. Window lengths stay ints (no keys turned to strings by JSON).
The kinematic study (``scores.csv``) and the free-root test (``physics.csv``) each fill one,
writers read it through :meth:`Records.values` (one array per kind x window x method x
metric, in the order of the ids asked for), and every CSV of the study is written by the one
writer :func:`csv_text`; :meth:`Records.from_csv` reads a table back exactly.
"""

from __future__ import annotations

import csv
import io
import math
import os
from collections.abc import Iterable, Mapping, Sequence

import numpy as np

#: Row kinds: a transition pair, a real window of a test clip (method ``"real"``), or a
#: window of the in-betweening task (:mod:`eval.inbetween`; window = length at 30 fps).
KINDS = ("pair", "real", "inbetween")
#: The method name of the real-window rows.
REAL = "real"
COLUMNS = ("kind", "id", "window", "method", "metric", "value")


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, str):
        return value
    if isinstance(value, (int, np.integer)) and not isinstance(value, bool):
        return str(int(value))
    number = float(value)
    return "" if math.isnan(number) else repr(number)


def csv_text(columns: Sequence[str], rows: Iterable[Sequence]) -> str:
    """The study's one CSV writer: a header, then one line per row.

    Strings as they are, ints as ints, floats as the shortest text that reads back to the
    same float (``repr``), None and NaN as an empty cell; LF line endings.
    """
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        if len(row) != len(columns):
            raise ValueError(f"a row of {len(row)} cells under {len(columns)} columns")
        writer.writerow([_cell(v) for v in row])
    return buffer.getvalue()


def _unknown(metric: str, metrics: Sequence[str]) -> str:
    return f"metric {metric!r} is not in the registry ({', '.join(metrics)})"


class Records:
    """A long-form results table.

    Parameters
    ----------
    metrics : iterable of str
        The metric names rows may carry (the registry of the study that fills it, e.g.
        :data:`eval.metrics.METRICS` or :data:`eval.physics.PHYSICS_METRICS`).
    """

    def __init__(self, metrics: Iterable[str]):
        self.metrics = tuple(metrics)
        self._known = frozenset(self.metrics)
        self._rows: dict[tuple[str, int, int, str, str], float] = {}
        self._ids: dict[tuple[str, int, str], set[int]] = {}

    def __len__(self) -> int:
        return len(self._rows)

    def __eq__(self, other) -> bool:
        if not isinstance(other, Records):
            return NotImplemented
        return self.metrics == other.metrics and self.to_csv() == other.to_csv()

    def check_metric(self, metric: str) -> None:
        """Raise KeyError naming ``metric`` if the registry does not have it."""
        if metric not in self._known:
            raise KeyError(_unknown(metric, self.metrics))

    def add(self, kind: str, index: int, window: int, method: str,
            values: Mapping[str, float]) -> None:
        """Add one unit's metrics (a pair x method x window, or a real window).

        Raises
        ------
        KeyError
            If a metric is not in the registry, the kind is unknown, or a real-window row
            is not of the method :data:`REAL`.
        """
        if kind not in KINDS:
            raise KeyError(f"row kind {kind!r} is not one of {KINDS}")
        if (kind == REAL) != (method == REAL):
            raise KeyError(f"a {kind!r} row cannot be of the method {method!r}")
        for metric in values:
            self.check_metric(metric)
        for metric, value in values.items():
            self._rows[(kind, int(index), int(window), method, metric)] = float(value)
        self._ids.setdefault((kind, int(window), method), set()).add(int(index))

    def rows(self) -> list[tuple]:
        """Every row, sorted: (kind, id, window, method, metric, value)."""
        order = {m: i for i, m in enumerate(self.metrics)}
        keys = sorted(self._rows, key=lambda k: (KINDS.index(k[0]), k[2], k[3], k[1],
                                                 order[k[4]]))
        return [(*k, self._rows[k]) for k in keys]

    def ids(self, kind: str, window: int, method: str) -> list[int]:
        """The ids that have rows for ``kind``, ``window`` and ``method``, ascending."""
        return sorted(self._ids.get((kind, int(window), method), ()))

    def values(self, kind: str, window: int, method: str, metric: str,
               ids: Iterable[int] | None = None) -> np.ndarray:
        """One metric over ids (all of them, ascending, by default), shape (N,).

        Raises
        ------
        KeyError
            If the metric is not in the registry, or a requested row is missing.
        """
        self.check_metric(metric)
        chosen = self.ids(kind, window, method) if ids is None else list(ids)
        try:
            return np.array([self._rows[(kind, i, window, method, metric)] for i in chosen],
                            dtype=float)
        except KeyError as missing:
            raise KeyError(f"no row {missing.args[0]} in the table") from None

    def to_csv(self) -> str:
        """The table as CSV (header :data:`COLUMNS`; an empty value for NaN)."""
        return csv_text(COLUMNS, self.rows())

    @classmethod
    def from_csv(cls, text: str, metrics: Iterable[str],
                 path: str | os.PathLike = "<csv>") -> Records:
        """Read a table written by :meth:`to_csv` (values exactly as written).

        Raises
        ------
        upm.core.errors.DataFileError
            Naming ``path`` and the line at fault: a wrong header, a row of the wrong
            length, an unknown kind or metric, an id or window that is not an integer, a
            value that is not a number, a row repeated.
        """
        from upm.core.errors import DataFileError

        records = cls(metrics)
        reader = csv.reader(io.StringIO(text))
        header = next(reader, None)
        if header is None or tuple(header) != COLUMNS:
            raise DataFileError(path, f"the header must be {','.join(COLUMNS)}", 1)
        for row in reader:
            line = reader.line_num
            if len(row) != len(COLUMNS):
                raise DataFileError(path, f"{len(row)} cells, not {len(COLUMNS)}", line)
            kind, index, window, method, metric, value = row
            before = len(records)
            try:
                number = math.nan if value == "" else float(value)
                records.add(kind, int(index), int(window), method, {metric: number})
            except ValueError:
                raise DataFileError(path, f"id {index!r} and window {window!r} must be "
                                          f"integers and value {value!r} a number",
                                    line) from None
            except KeyError as error:
                raise DataFileError(path, error.args[0], line) from None
            if len(records) == before:
                raise DataFileError(path, f"a second row for {kind} {index}, window {window}, "
                                          f"{method}, {metric}", line)
        return records
