"""Stopping a run at any time: in a command's session SIGTERM raises KeyboardInterrupt as
Ctrl-C does (the previous handler afterwards); an interrupted local pool kills its worker
processes instead of waiting for the tasks they hold; the checkpoint keeps every unit
finished before the stop and a rerun does only the rest. (Stopping a run on a Ray cluster
by SIGTERM: tests/test_ray_cluster.py.)"""

from __future__ import annotations

import multiprocessing
import os
import signal
import time

import pytest

from eval.executor import LocalExecutor, executor_session
from eval.runs import Checkpoint, run_checkpointed


def _sleep(seconds: float, done_file=None) -> dict:
    time.sleep(seconds)
    if done_file is not None:
        done_file.write_text("done")
    return {"slept_s": seconds}


def test_sigterm_in_a_session_is_a_keyboard_interrupt_and_the_handler_comes_back():
    received = []

    def outside(signum, frame):  # this test's own, so that a failure cannot kill pytest
        received.append(signum)

    original = signal.signal(signal.SIGTERM, outside)
    try:
        reached = []
        with pytest.raises(KeyboardInterrupt):
            with executor_session("local", 1):
                os.kill(os.getpid(), signal.SIGTERM)
                for _ in range(50):  # the handler raises at the next bytecode
                    time.sleep(0.1)
                reached.append("end")
        assert reached == [] and received == []
        assert signal.getsignal(signal.SIGTERM) is outside
    finally:
        signal.signal(signal.SIGTERM, original)


def test_an_interrupted_local_pool_kills_its_processes(tmp_path):
    assert multiprocessing.active_children() == []
    slow, queued = tmp_path / "slow.done", tmp_path / "queued.done"
    outcomes = LocalExecutor(2).run(_sleep, [("quick", (0.0,)), ("slow", (30.0, slow)),
                                             ("queued", (30.0, queued))])
    first = next(outcomes)
    assert first.key == "quick" and first.value == {"slept_s": 0.0}
    assert len(multiprocessing.active_children()) == 2
    outcomes.close()  # what an interrupt does to the generator
    assert multiprocessing.active_children() == []
    # killed, not waited for: neither the running task nor the queued one ever finished
    assert not slow.exists() and not queued.exists()


def test_a_stopped_run_keeps_its_finished_units_and_a_rerun_does_the_rest(tmp_path):
    calls = []
    stop_at = {"c"}

    def unit(key):
        calls.append(key)
        if key in stop_at:
            raise KeyboardInterrupt  # Ctrl-C (or SIGTERM, in a session) during this unit
        return {"value": float(ord(key))}

    tasks = [(key, (key,)) for key in "abcde"]

    def checkpoint():
        return Checkpoint(tmp_path, {"seed": 0}, name="units-partial.jsonl",
                          format_name="test/units", version=1)

    with pytest.raises(KeyboardInterrupt):
        run_checkpointed(LocalExecutor(1), unit, tasks, checkpoint(), "units",
                         show_progress=False)
    again = checkpoint()
    assert again.load() == 2 and sorted(again.done) == ["a", "b"]

    calls.clear()
    stop_at.clear()
    todo = [t for t in tasks if t[0] not in again.done]
    assert run_checkpointed(LocalExecutor(1), unit, todo, again, "units",
                            show_progress=False) == []
    assert calls == ["c", "d", "e"]
    final = checkpoint()
    assert final.load() == 5
    assert final.done == {key: {"value": float(ord(key))} for key in "abcde"}
