"""The lock that lets a test run alone while the suite runs on several pytest-xdist workers (``conftest.py``).

Every test holds one lock file of the run (``$TMPDIR/fsr-pytest-<run id>.lock``) while it runs: shared for
most tests, exclusive for a test marked ``alone``. A second file is the turnstile that keeps a waiting
``alone`` test from being overtaken: a test passes it before it takes the lock, and an ``alone`` test holds it
from the moment it starts waiting until it ends, so no other test starts meanwhile. ``flock`` locks end with
their process: a worker that dies frees them.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path


class TestLock:
    """``with TestLock(run_id, exclusive):`` holds the run's lock (shared, or exclusive for an ``alone`` test)."""

    __test__ = False  # not a test class (its name starts with Test)

    def __init__(self, run_id: str, exclusive: bool) -> None:
        base = Path(tempfile.gettempdir()) / f"fsr-pytest-{run_id}"
        self.exclusive = exclusive
        self._turnstile = os.open(f"{base}.turnstile", os.O_CREAT | os.O_RDWR, 0o666)
        self._lock = os.open(f"{base}.lock", os.O_CREAT | os.O_RDWR, 0o666)

    def __enter__(self) -> TestLock:
        fcntl.flock(self._turnstile, fcntl.LOCK_EX)
        fcntl.flock(self._lock, fcntl.LOCK_EX if self.exclusive else fcntl.LOCK_SH)
        if not self.exclusive:
            fcntl.flock(self._turnstile, fcntl.LOCK_UN)
        return self

    def __exit__(self, *_exc: object) -> None:
        os.close(self._lock)  # closing the descriptor releases its lock
        os.close(self._turnstile)
