"""The controller's inputs of one stamp, paired: ``odom`` and, where the law or its observer reads them, ``imu``
and ``rotor_state`` (no ROS here: stamps in integer nanoseconds, values as the node reads them).

The simulator publishes them together for each state; over DDS they arrive in any order. A stamp is answered
once every input it needs has arrived (still one answer per state: the lockstep), exactly with what the
in-process loop hands the controller's tick. An input stamped at or before the last answered stamp can never
be answered any more and is dropped; an answer drops every older unpaired input.

The first state (t_0) is answered without ``rotor_state``: the simulator publishes t_0's only once the first
command came (the rotors spin at it from the start), so the tick gets the rotors' initial state instead (None:
zeros, the plant's speeds and tilts before any command), as the in-process loop hands it.
"""

from __future__ import annotations

from typing import Any

ODOM_INPUT, IMU_INPUT, ROTOR_STATE_INPUT = 0, 1, 2
INITIAL_ROTOR_STATE = (None, None)  # (speeds, tilts) of t_0: the controller's zeros


class StampedInputs:
    """Pairs the controller's inputs by stamp (module docstring); ``needs_imu``, ``needs_rotor_state``: which
    besides ``odom`` a stamp waits for."""

    def __init__(self, needs_imu: bool, needs_rotor_state: bool) -> None:
        self.kinds = (ODOM_INPUT, *((IMU_INPUT,) if needs_imu else ()),
                      *((ROTOR_STATE_INPUT,) if needs_rotor_state else ()))
        self.pending: dict[int, dict[int, Any]] = {kind: {} for kind in self.kinds}
        self.answered_ns: int | None = None
        self.dropped = 0  # inputs that came too late to be paired

    def add(self, kind: int, stamp_ns: int, value: Any) -> tuple[Any, ...] | None:
        """Take input ``kind`` of ``stamp_ns``; returns every needed input of that stamp, in the order of
        :attr:`kinds`, once it is complete (else None)."""
        if self.answered_ns is not None and stamp_ns <= self.answered_ns:
            self.dropped += 1
            return None
        self.pending[kind][stamp_ns] = value
        first = self.answered_ns is None
        needed = [other for other in self.kinds if not (first and other == ROTOR_STATE_INPUT)]
        if any(stamp_ns not in self.pending[other] for other in needed):
            return None
        values = tuple(self.pending[other].pop(stamp_ns) if other in needed else INITIAL_ROTOR_STATE
                       for other in self.kinds)
        self.answered_ns = stamp_ns
        for table in self.pending.values():
            for old in [stamp for stamp in table if stamp < stamp_ns]:
                del table[old]
                self.dropped += 1
        return values
