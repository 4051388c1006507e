"""The lock that runs a test marked ``alone`` while no other test runs on the other pytest-xdist workers
(tests/harness/alone.py): a held shared lock keeps an exclusive one waiting, a held exclusive lock keeps a
shared one waiting, and shared locks are held together."""

from __future__ import annotations

import subprocess
import sys
import tempfile
import uuid
from pathlib import Path

HOLD = """
import sys, time
sys.path.insert(0, {tests!r})
from harness.alone import TestLock
with TestLock({run!r}, exclusive={exclusive}):
    print("held", time.monotonic(), flush=True)
    time.sleep({seconds})
print("released", time.monotonic(), flush=True)
"""
TESTS = str(Path(__file__).resolve().parent)


def hold(run: str, exclusive: bool, seconds: float) -> subprocess.Popen:
    script = HOLD.format(tests=TESTS, run=run, exclusive=exclusive, seconds=seconds)
    return subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)


def wait_held(process: subprocess.Popen) -> float:
    """When ``process`` got the lock (monotonic clock), once it says so."""
    word, when = process.stdout.readline().split()
    assert word == "held"
    return float(when)


def released(process: subprocess.Popen) -> float:
    """When ``process`` let the lock go, once it has exited. Read through the same buffered stream as
    :func:`wait_held` (``communicate`` with a timeout reads the pipe itself and would miss a line that stream
    already buffered: both lines arrive in one read when this process is scheduled late)."""
    word, when = process.stdout.readline().split()
    assert process.wait(timeout=30) == 0
    process.stdout.close()
    assert word == "released"
    return float(when)


def remove(run: str) -> None:
    for suffix in (".lock", ".turnstile"):
        (Path(tempfile.gettempdir()) / f"fsr-pytest-{run}{suffix}").unlink(missing_ok=True)


def test_an_alone_test_waits_for_the_running_ones_and_holds_back_the_next():
    run = f"test-{uuid.uuid4().hex}"
    shared = hold(run, False, 1.0)
    wait_held(shared)
    alone = hold(run, True, 1.0)
    alone_start = wait_held(alone)
    assert released(shared) <= alone_start  # it waited for the running test
    late = hold(run, False, 0.0)  # starts while the alone test holds the lock
    late_start = wait_held(late)
    assert released(alone) <= late_start  # and the next test waited for it
    released(late)
    remove(run)


def test_tests_that_are_not_alone_run_together():
    run = f"test-{uuid.uuid4().hex}"
    first, second = hold(run, False, 1.0), hold(run, False, 1.0)
    first_start, second_start = wait_held(first), wait_held(second)
    assert max(first_start, second_start) < min(released(first), released(second))  # both held it at once
    remove(run)
