"""Where the study's units of work run: one interface, a local process pool or Ray.

A task is ``(key, args)``; the executor calls ``fn(*args)`` for each, in a process where
``initializer(*initargs)`` has run (once per process), and yields a :class:`Outcome` per
task as it finishes: its value, or the error it raised (never dropped). Results do not
depend on the executor or the number of workers: each task is a pure function of its
arguments, and callers order the outcomes by key.

- :class:`LocalExecutor`: ``concurrent.futures.ProcessPoolExecutor`` (fork where the
  platform has it, so loaded data is shared), or this process for one worker.
- :class:`RayExecutor`: `Ray <https://docs.ray.io>`_ tasks — an existing cluster at
  ``address`` (``ray://host:10001`` or ``host:6379``: :mod:`eval.ray_cluster` checks it
  and the token first), else a local Ray instance with ``workers`` CPUs, shut down
  afterwards. A task whose worker process dies is retried by Ray (:data:`RAY_RETRIES`); a
  task that raises is reported, not retried (the study's tasks are deterministic: the same
  error would come again).

Stopping: a command's :func:`executor_session` turns SIGTERM into KeyboardInterrupt (as
Ctrl-C), so that a stop at any moment unwinds: the checkpoint of finished units is closed
(:mod:`eval.runs`), the local pool's processes are killed, Ray's pending tasks cancelled
and its connection shut down.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
import traceback
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

#: Executors by name (``upm eval --executor``).
EXECUTORS = ("local", "ray")
#: Retries of a Ray task whose worker process died (machine lost, out of memory).
RAY_RETRIES = 2
#: Seconds each wait for a Ray task may block (signals are handled between waits).
RAY_WAIT_S = 1.0


@dataclass(frozen=True)
class Outcome:
    """One finished task.

    Attributes
    ----------
    key : str
    value : object
        What the task returned (None if it failed).
    error : str or None
        ``"ExceptionType: message"`` if it failed.
    """

    key: str
    value: object = None
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def _describe(exc: BaseException) -> str:
    lines = traceback.format_exception_only(type(exc), exc)
    return " ".join(line.strip() for line in lines)[:500]


def _call(initializer, initargs, fn, args):
    if initializer is not None:
        initializer(*initargs)
    return fn(*args)


class LocalExecutor:
    """A local process pool (``workers`` processes; 1 runs the tasks in this process)."""

    name = "local"

    def __init__(self, workers: int, initializer: Callable | None = None,
                 initargs: tuple = ()):
        self.workers = max(1, int(workers))
        self.initializer = initializer
        self.initargs = initargs

    def run(self, fn: Callable, tasks: Iterable[tuple[str, tuple]]) -> Iterator[Outcome]:
        tasks = list(tasks)
        if self.workers == 1 or len(tasks) <= 1:
            if self.initializer is not None and tasks:
                self.initializer(*self.initargs)
            for key, args in tasks:
                try:
                    yield Outcome(key, fn(*args))
                except Exception as exc:  # reported with its key, never dropped
                    yield Outcome(key, error=_describe(exc))
            return
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        methods = multiprocessing.get_all_start_methods()
        context = multiprocessing.get_context("fork" if "fork" in methods else "spawn")
        others = set(multiprocessing.active_children())
        pool = ProcessPoolExecutor(max_workers=min(self.workers, len(tasks)),
                                   mp_context=context, initializer=self.initializer,
                                   initargs=self.initargs)
        try:
            futures = {pool.submit(fn, *args): key for key, args in tasks}
            for future in as_completed(futures):
                try:
                    yield Outcome(futures[future], future.result())
                except Exception as exc:
                    yield Outcome(futures[future], error=_describe(exc))
        except BaseException:  # interrupted, or the consumer stopped early
            _kill_pool(pool, others)
            raise
        pool.shutdown(wait=True)


def _kill_pool(pool, others=frozenset()) -> None:
    """Stop a process pool now: queued tasks cancelled, running ones killed (a plain
    shutdown would wait for every task already handed to a worker). ``others``: the
    child processes that were there before the pool (left alone)."""
    import multiprocessing

    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    # the pool's manager thread may still start a worker while it shuts down, one the
    # pool no longer lists: every child process started since the pool, until none is left
    for _ in range(10):
        for process in processes:
            with contextlib.suppress(Exception):
                process.kill()
        for process in processes:
            with contextlib.suppress(Exception):
                process.join(timeout=5)
        processes = [p for p in multiprocessing.active_children() if p not in others]
        if not processes:
            break
        time.sleep(0.05)


class RayExecutor:
    """Ray tasks on the cluster at ``address``, else on a local Ray instance."""

    name = "ray"

    def __init__(self, workers: int, address: str | None = None,
                 initializer: Callable | None = None, initargs: tuple = ()):
        self.workers = max(1, int(workers))
        self.address = address
        self.initializer = initializer
        self.initargs = initargs

    def run(self, fn: Callable, tasks: Iterable[tuple[str, tuple]]) -> Iterator[Outcome]:
        ray = import_ray()
        tasks = list(tasks)
        connection = (ray_connection(ray, self.workers, self.address)
                      if not ray.is_initialized() else contextlib.nullcontext())
        with connection:
            remote = ray.remote(max_retries=RAY_RETRIES, retry_exceptions=False)(_call)
            pending = {remote.remote(self.initializer, self.initargs, fn, args): key
                       for key, args in tasks}
            try:
                while pending:
                    ready, _ = ray.wait(list(pending), num_returns=1, timeout=RAY_WAIT_S)
                    for ref in ready:
                        key = pending.pop(ref)
                        try:
                            yield Outcome(key, ray.get(ref))
                        except ray.exceptions.RayTaskError as exc:
                            yield Outcome(key, error=_describe(exc.cause or exc))
                        except ray.exceptions.RayError as exc:  # lost worker after retries
                            yield Outcome(key, error=_describe(exc))
            except BaseException:  # interrupted, or the consumer stopped early
                for ref in pending:
                    with contextlib.suppress(Exception):
                        ray.cancel(ref, force=True)
                raise


def ray_options(workers: int | None = None) -> dict:
    """``ray.init``'s keywords: workers import this project as the driver does (an
    editable install on every node, or the driver's PYTHONPATH where it exists) and run
    BLAS single-threaded; ``workers`` CPUs for a local instance."""
    import logging
    import os
    import sys

    paths = [p for p in sys.path if p and os.path.isdir(p)]
    env = {"PYTHONPATH": os.pathsep.join(paths), "OMP_NUM_THREADS": "1",
           "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    options = {"include_dashboard": False, "log_to_driver": False,
               "logging_level": logging.WARNING, "runtime_env": {"env_vars": env}}
    return options if workers is None else {**options, "num_cpus": workers}


@contextlib.contextmanager
def ray_connection(ray, workers: int, address: str | None):
    """Connected for the body to the cluster at ``address`` (checked first:
    :func:`eval.ray_cluster.cluster_connection`), or to a local instance of ``workers``
    CPUs started for it; shut down afterwards."""
    before = _sigterm_handler()
    if address:
        from eval.ray_cluster import cluster_connection

        connection = cluster_connection(ray, address, ray_options())
    else:
        connection = _local_ray(ray, workers)
    with connection:
        if before is _interrupt:  # ray.init puts its own SIGTERM handler in: ours again
            signal.signal(signal.SIGTERM, _interrupt)
        yield


@contextlib.contextmanager
def _local_ray(ray, workers: int):
    ray.init(**ray_options(workers))
    try:
        yield
    finally:
        ray.shutdown()


def _interrupt(signum, frame):
    raise KeyboardInterrupt(f"signal {signum}")


def _sigterm_handler():
    if threading.current_thread() is not threading.main_thread():
        return None
    return signal.getsignal(signal.SIGTERM)


@contextlib.contextmanager
def stop_on_sigterm():
    """SIGTERM raises KeyboardInterrupt in the body (as Ctrl-C does), so that a stopped
    run unwinds and keeps what it wrote; the previous handler afterwards. Only in the main
    thread (elsewhere signals cannot be handled)."""
    before = _sigterm_handler()
    if before is None or before is _interrupt:
        yield
        return
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, before)


@contextlib.contextmanager
def executor_session(name: str, workers: int, address: str | None = None):
    """One command's run: SIGTERM stops it as Ctrl-C does (:func:`stop_on_sigterm`), and
    with ``name == "ray"`` one Ray connection is kept for its several runs."""
    with stop_on_sigterm():
        if name != "ray":
            yield
            return
        ray = import_ray()
        if ray.is_initialized():
            yield
            return
        with ray_connection(ray, workers, address):
            yield


def check_executor(name: str, address: str | None) -> None:
    """Before a command loads anything: Ray installed (``name == "ray"``), and the cluster
    at ``address`` there and taking the token (:func:`eval.ray_cluster.check_cluster`).

    Raises
    ------
    UsageError
        One line saying what is wrong and the fix.
    """
    from upm.core.errors import UsageError

    if address and name != "ray":
        raise UsageError("--address goes with --executor ray")
    if name != "ray":
        return
    import_ray()
    if address:
        from eval.ray_cluster import check_cluster

        check_cluster(address)


def import_ray():
    """The ``ray`` module, or a one-line UsageError saying how to install it."""
    try:
        import ray
    except ImportError:
        from upm.core.errors import UsageError

        raise UsageError("--executor ray needs Ray: pip install -e '.[ray]' (or "
                         "pip install 'ray>=2.9')") from None
    return ray


def make_executor(name: str, workers: int, address: str | None = None,
                  initializer: Callable | None = None, initargs: tuple = ()):
    """The executor called ``name`` (:data:`EXECUTORS`)."""
    from upm.core.errors import UsageError

    if name == "local":
        if address:
            raise UsageError("--address goes with --executor ray")
        return LocalExecutor(workers, initializer, initargs)
    if name == "ray":
        return RayExecutor(workers, address, initializer, initargs)
    raise UsageError(f"no executor {name!r} (executors: {', '.join(EXECUTORS)})")
