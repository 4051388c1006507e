"""Lockstep bookkeeping of the simulator: which command answers which state, and how long to wait for it.

Contract (docs/model.md §4): the simulator publishes the state stamped ``t_k`` and applies the command stamped
``t_k`` over ``[t_k, t_k + T]``. A command with an older stamp is stale (a late answer to a step that was
already taken on the failsafe); a newer stamp cannot be an answer to anything published yet.

:class:`CommandWait` is the per-step waiting policy, three modes:

* ``lockstep``: wait up to ``timeout`` [s] for the answer. If it does not come, apply the failsafe and
  switch to ``degraded``.
* ``degraded``: the controller missed a step; wait only ``recovery_wait`` [s] per step, or ``RECOVERY_FACTOR``
  times the typical wait of the answered steps if that is longer (a controller on one host answers in well
  under a millisecond; over a network, or on a loaded machine, a cycle takes longer, and a controller that
  has to work through the states it missed could never catch up with a simulator stepping faster than it
  answers), so that a hung controller does not cost ``timeout`` per step. A late answer (a stale stamp)
  arriving meanwhile shows the controller alive and working through the states it missed: the step then waits
  as in ``lockstep``, up to ``timeout`` from its start (:meth:`CommandWait.budget_after_late_answer`), so the
  controller catches up however slow its cycle is next to the simulator's (a loaded machine), instead of racing
  it. The first answer in time switches back to ``lockstep``.
* ``gone``: the command topic has no publisher (the controller exited); do not wait at all, so the flight
  still reaches its end. A publisher that reappears moves to ``degraded``.

No rclpy here: the node feeds in what it observed and logs the returned events.
"""

from __future__ import annotations

CURRENT = "current"
STALE = "stale"
AHEAD = "ahead"

LOCKSTEP = "lockstep"
DEGRADED = "degraded"
GONE = "gone"

RECOVERY_WAIT = 0.002  # s: per-step wait after a missed step (at least)
RECOVERY_FACTOR = 4.0  # degraded wait: this many typical answered waits, if longer than RECOVERY_WAIT
TYPICAL_WEIGHT = 0.05  # weight of a new answered wait in the running mean ``typical_wait``


def classify_stamp(stamp_ns: int, expected_ns: int) -> str:
    """``current`` if a command stamped ``stamp_ns`` answers the state ``expected_ns``, else stale/ahead."""
    if stamp_ns == expected_ns:
        return CURRENT
    return STALE if stamp_ns < expected_ns else AHEAD


class CommandWait:
    """How long to wait for step k's command, and what a miss means (see the module docstring)."""

    def __init__(self, timeout: float, recovery_wait: float = RECOVERY_WAIT) -> None:
        if timeout <= 0.0:
            raise ValueError(f"timeout must be > 0 s, got {timeout}")
        self.timeout = timeout
        self.recovery_wait = min(recovery_wait, timeout)
        self.mode = LOCKSTEP
        self.missed_steps = 0  # steps run on the failsafe
        self.incidents = 0  # times the controller stopped answering (lockstep -> degraded / gone)
        self.typical_wait = 0.0  # s: running mean of the waits of steps answered in lockstep

    def budget(self) -> float:
        """Seconds to wait for the current step's command."""
        if self.mode == LOCKSTEP:
            return self.timeout
        if self.mode == DEGRADED:
            return min(self.timeout, max(self.recovery_wait, RECOVERY_FACTOR * self.typical_wait))
        return 0.0

    def budget_after_late_answer(self) -> float:
        """Seconds to wait for the current step's command, from the start of its wait, once a late answer (a stale
        stamp) came in during it: ``timeout`` while degraded (the controller is alive, catching up), else the
        budget unchanged."""
        return self.timeout if self.mode == DEGRADED else self.budget()

    def answered(self, waited: float | None = None) -> str | None:
        """The command arrived in time, after ``waited`` [s] if known; returns ``'recovered'`` when this ends a
        degraded/gone spell."""
        if self.mode == LOCKSTEP:
            if waited is not None and self.typical_wait:  # one long pause (an outage) barely moves the mean
                self.typical_wait += TYPICAL_WEIGHT * (min(waited, RECOVERY_FACTOR * self.typical_wait)
                                                       - self.typical_wait)
            elif waited is not None:
                self.typical_wait = waited
            return None
        self.mode = LOCKSTEP
        return "recovered"

    def missed(self, publisher_count: int) -> str:
        """No command within the budget (or the publisher vanished); the failsafe applies to this step.

        Returns the event to report: ``'timeout'`` (a controller that was answering stopped), ``'gone'``
        (the command topic lost its last publisher), ``'publisher_back'`` (a publisher appeared while gone)
        or ``'missed'`` (still not answering; nothing new to say).
        """
        self.missed_steps += 1
        if publisher_count == 0:
            if self.mode == GONE:
                return "missed"
            if self.mode == LOCKSTEP:
                self.incidents += 1
            self.mode = GONE
            return "gone"
        if self.mode == GONE:
            self.mode = DEGRADED
            return "publisher_back"
        if self.mode == LOCKSTEP:
            self.mode = DEGRADED
            self.incidents += 1
            return "timeout"
        return "missed"


class FreeRunPacer:
    """Wall-clock deadlines of a free-running simulation: step k ends at ``start + (k+1) T / rtf``.

    If the simulation falls behind by more than ``max_lag`` [s] (a stall), the schedule restarts from
    now instead of running a burst of catch-up steps.
    """

    def __init__(self, period: float, real_time_factor: float, start: float, max_lag: float = 0.5) -> None:
        if period <= 0.0 or real_time_factor <= 0.0:
            raise ValueError(f"period and real_time_factor must be > 0, got {period}, {real_time_factor}")
        self.wall_period = period / real_time_factor
        self.start = start
        self.first_step = 0
        self.max_lag = max_lag

    def deadline(self, step: int, now: float) -> float:
        """Wall time [s, same clock as ``now``] at which step ``step`` should be taken."""
        target = self.start + (step + 1 - self.first_step) * self.wall_period
        if now - target > self.max_lag:
            self.start, self.first_step = now, step + 1
            return now
        return target


class CommandWatchdog:
    """Free-running failsafe: fires once when no valid command arrived for ``timeout`` [s] of wall time."""

    def __init__(self, timeout: float, now: float) -> None:
        self.timeout = timeout
        self.last_command = now
        self.fired = False

    def feed(self, now: float) -> bool:
        """A valid command arrived; True if this ends a failsafe spell."""
        self.last_command = now
        recovered, self.fired = self.fired, False
        return recovered

    def expired(self, now: float) -> bool:
        """True exactly once per silence longer than ``timeout``."""
        if self.fired or now - self.last_command <= self.timeout:
            return False
        self.fired = True
        return True
