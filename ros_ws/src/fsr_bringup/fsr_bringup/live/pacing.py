"""Pacing an in-process flight for watching it live.

The compiled loop flies a 1 kHz flight 50-70 times faster than real time. Watched live, it is flown in chunks of
about ``SERVE_PERIOD`` of wall time, each served as soon as it is flown, and the loop then waits until the wall
clock reaches its last state: the state stamped ``t`` is served at ``start + t / real_time_factor``, the schedule
of the free-running simulator (:class:`fsr_sim.nodes.lockstep.FreeRunPacer`, ``lockstep.real_time_factor``). A
stall longer than ``MAX_LAG`` (a loaded machine) restarts the schedule instead of serving a burst. What is flown
and recorded does not depend on the chunks (the recording is the same file, byte for byte).
"""

from __future__ import annotations

import time

from fsr_sim.nodes.lockstep import FreeRunPacer

SERVE_PERIOD = 0.02  # s of wall time per chunk: a viewer gets 50 updates per second
MAX_LAG = 1.0  # s behind the schedule before it restarts from now


class LivePace:
    """The chunks and the waits of one paced flight (module docstring)."""

    def __init__(self, control_period: float, real_time_factor: float) -> None:
        self.chunk_steps = max(1, round(SERVE_PERIOD * real_time_factor / control_period))
        self.pacer = FreeRunPacer(control_period, real_time_factor, time.perf_counter(), MAX_LAG)

    def wait_for(self, step: int) -> None:
        """Wait until state ``step`` (stamp ``step`` control periods) is due."""
        now = time.perf_counter()
        delay = self.pacer.deadline(step - 1, now) - now  # deadline(k - 1): when state k is due
        if delay > 0.0:
            time.sleep(delay)
