"""ROS domain ids for concurrent runs on one machine: each run holds an exclusive lock on its id.

Fast DDS domains 0..232 are fully isolated from each other (ROS2_FROM_PIP.md). A run takes the first id
in its range whose lock file (``$TMPDIR/fsr-domains/<id>.lock``) it can lock with ``flock``; the lock is
released when the run ends or its process dies, so crashed runs never leak an id.
"""

from __future__ import annotations

import fcntl
import os
import tempfile
from pathlib import Path

MAX_DOMAIN_ID = 232
RUNNER_RANGE = range(150, MAX_DOMAIN_ID + 1)  # fsr-fly
TEST_RANGE = range(100, 150)  # graph tests


class DomainLease:
    """An exclusively held ROS domain id; ``release()`` (or process exit) frees it."""

    def __init__(self, domain_id: int, handle: int | None) -> None:
        self.domain_id = domain_id
        self._handle = handle

    def release(self) -> None:
        if self._handle is not None:
            os.close(self._handle)
            self._handle = None

    def __enter__(self) -> DomainLease:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.release()


def lock_dir() -> Path:
    path = Path(tempfile.gettempdir()) / "fsr-domains"
    path.mkdir(parents=True, exist_ok=True)
    return path


def acquire_domain(candidates: range = RUNNER_RANGE) -> DomainLease:
    """Lock and return the first free domain id of ``candidates``; RuntimeError if all are taken."""
    for domain_id in candidates:
        if not 0 <= domain_id <= MAX_DOMAIN_ID:
            raise ValueError(f"ROS domain ids are 0..{MAX_DOMAIN_ID}, got {domain_id}")
        handle = os.open(lock_dir() / f"{domain_id}.lock", os.O_CREAT | os.O_RDWR, 0o666)
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(handle)
            continue
        return DomainLease(domain_id, handle)
    raise RuntimeError(f"no free ROS domain id in {candidates.start}..{candidates.stop - 1}")


def fixed_domain(domain_id: int) -> DomainLease:
    """A user-chosen domain id (not locked: the user decided to share it)."""
    if not 0 <= domain_id <= MAX_DOMAIN_ID:
        raise ValueError(f"--domain-id must be in 0..{MAX_DOMAIN_ID}, got {domain_id}")
    return DomainLease(domain_id, None)
