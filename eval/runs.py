"""Long runs of the study made of units of work: the checkpoint that keeps finished units
as they come (a stopped run resumes where it stopped), running units on an executor
(:mod:`eval.executor`) into it, and the worker processes' set-up (one BLAS thread each,
the cores this process may use). Shared by the study, its free-root test and the
robustness table."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

from upm.core.errors import UpmError


class StudyIncomplete(UpmError):
    """Some units failed; the finished ones are kept in the checkpoint."""


def single_threaded_blas() -> None:
    for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")
    from threadpoolctl import threadpool_limits

    threadpool_limits(int(os.environ["OPENBLAS_NUM_THREADS"]), user_api="blas")


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:
        return max(1, os.cpu_count() or 1)


class Checkpoint:
    """Finished units, one JSON line each, in ``DIR/name`` (e.g. ``physics-partial.jsonl``).

    The first line states the settings the figures depend on; a file with other settings
    is not reused (it is replaced when the run starts). With ``numbers`` (the default) a
    unit's figures are read back as floats (NaN for null); else as they were written
    (``eval.robustness``: booleans and nulls kept).
    """

    def __init__(self, out_dir, settings: dict, *, name: str, format_name: str, version: int,
                 numbers: bool = True):
        self.path = Path(out_dir) / name
        self.settings = {"format": format_name, "version": version, **settings}
        self.numbers = numbers
        self.done: dict[str, dict[str, float]] = {}
        self._handle = None

    def load(self) -> int:
        """Read the finished units of an earlier run with the same settings (count)."""
        if not self.path.is_file():
            return 0
        lines = self.path.read_text(encoding="utf-8").splitlines()
        try:
            if not lines or json.loads(lines[0]) != self.settings:
                return 0
            for line in lines[1:]:
                entry = json.loads(line)
                metrics = entry["metrics"]
                if not isinstance(metrics, dict):
                    raise TypeError("metrics")
                self.done[entry["key"]] = (
                    {k: (math.nan if v is None else float(v)) for k, v in metrics.items()}
                    if self.numbers else metrics)
        except (ValueError, KeyError, TypeError, AttributeError):
            # A line cut short by a crash: keep what was read before it.
            pass
        return len(self.done)

    def open(self) -> None:
        """Start appending (rewriting the file with what was loaded)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_name(self.path.name + ".tmp")
        with open(tmp, "w", encoding="utf-8") as handle:
            handle.write(json.dumps(self.settings) + "\n")
            for key, metrics in self.done.items():
                handle.write(_line(key, metrics))
        os.replace(tmp, self.path)
        self._handle = open(self.path, "a", encoding="utf-8")

    def add(self, key: str, metrics: dict[str, float]) -> None:
        self.done[key] = metrics
        self._handle.write(_line(key, metrics))
        self._handle.flush()

    def close(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None

    def remove(self) -> None:
        self.close()
        self.path.unlink(missing_ok=True)


def run_checkpointed(runner, fn, tasks: list, checkpoint: Checkpoint, desc: str,
                     show_progress: bool = True) -> list[tuple[str, str]]:
    """Run ``tasks`` (``(key, args)`` each) on an :mod:`eval.executor` executor, adding
    each finished one to the checkpoint as it comes, with a progress bar. Stopped at any
    moment (an exception, Ctrl-C, SIGTERM in a command's session), it leaves the
    checkpoint closed with every unit finished before the stop, and the executor's
    remaining work stopped; the same call later does only the rest.

    Returns
    -------
    list of (str, str)
        The key and error of every task that failed (the others are in the checkpoint).
    """
    from upm.core.progress import progress

    failures = []
    checkpoint.open()
    bar = progress(total=len(tasks), desc=desc, unit="run",
                   disable=None if show_progress else True)
    outcomes = runner.run(fn, tasks)
    try:
        for outcome in outcomes:
            if outcome.ok:
                checkpoint.add(outcome.key, outcome.value)
            else:
                failures.append((outcome.key, outcome.error))
            bar.update()
    finally:
        checkpoint.close()  # every finished unit is on disk, whatever stopped the run
        bar.close()
        close = getattr(outcomes, "close", None)
        if close is not None:  # stopped early (Ctrl-C, SIGTERM): the executor's work too
            close()
    return failures


def _line(key: str, metrics: dict[str, float]) -> str:
    clean = {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
             for k, v in metrics.items()}
    return json.dumps({"key": key, "metrics": clean}) + "\n"
