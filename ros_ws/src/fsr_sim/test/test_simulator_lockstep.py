"""Lockstep bookkeeping of the simulator node (pure logic, no ROS graph)."""

import pytest

from fsr_sim.nodes.lockstep import (
    AHEAD,
    CURRENT,
    DEGRADED,
    GONE,
    LOCKSTEP,
    RECOVERY_FACTOR,
    STALE,
    TYPICAL_WEIGHT,
    CommandWait,
    CommandWatchdog,
    FreeRunPacer,
    classify_stamp,
)


def test_classify_stamp():
    assert classify_stamp(5_000_000, 5_000_000) == CURRENT
    assert classify_stamp(4_000_000, 5_000_000) == STALE
    assert classify_stamp(6_000_000, 5_000_000) == AHEAD


def test_timeout_degrades_then_an_answer_recovers():
    wait = CommandWait(timeout=1.0, recovery_wait=0.002)
    assert wait.budget() == 1.0 and wait.answered() is None
    assert wait.missed(publisher_count=1) == "timeout"
    assert wait.mode == DEGRADED and wait.budget() == 0.002
    assert wait.missed(publisher_count=1) == "missed"
    assert wait.missed_steps == 2 and wait.incidents == 1
    assert wait.answered() == "recovered"
    assert wait.mode == LOCKSTEP and wait.budget() == 1.0
    assert wait.missed(publisher_count=1) == "timeout"
    assert wait.incidents == 2


def test_lost_publisher_stops_waiting_until_one_reappears():
    wait = CommandWait(timeout=1.0)
    assert wait.missed(publisher_count=0) == "gone"
    assert wait.mode == GONE and wait.budget() == 0.0
    assert wait.missed(publisher_count=0) == "missed"
    assert wait.missed(publisher_count=1) == "publisher_back"
    assert wait.mode == DEGRADED
    assert wait.missed(publisher_count=0) == "gone"
    assert wait.incidents == 1  # one controller outage, reported once
    assert wait.answered() == "recovered"


def test_recovery_wait_never_exceeds_timeout():
    assert CommandWait(timeout=0.001, recovery_wait=0.002).recovery_wait == 0.001
    with pytest.raises(ValueError, match="timeout must be > 0"):
        CommandWait(timeout=0.0)


def test_free_run_pacer_deadlines_and_stall_reset():
    pacer = FreeRunPacer(period=0.001, real_time_factor=2.0, start=10.0)
    assert pacer.deadline(0, now=10.0) == pytest.approx(10.0005)
    assert pacer.deadline(9, now=10.001) == pytest.approx(10.005)
    # a 1 s stall: restart the schedule from now instead of a burst of catch-up steps
    assert pacer.deadline(10, now=11.0) == 11.0
    assert pacer.deadline(11, now=11.0) == pytest.approx(11.0005)
    with pytest.raises(ValueError):
        FreeRunPacer(period=0.001, real_time_factor=0.0, start=0.0)


def test_watchdog_fires_once_per_silence():
    dog = CommandWatchdog(timeout=0.5, now=0.0)
    assert not dog.expired(0.4)
    assert dog.expired(0.6)
    assert not dog.expired(2.0)  # already reported
    assert dog.feed(2.1) is True  # commands are back
    assert not dog.expired(2.5)
    assert dog.expired(2.7)
    assert dog.feed(2.8) is True and dog.feed(2.9) is False


def test_degraded_wait_follows_the_typical_answer_time():
    """A controller whose cycle is longer than RECOVERY_WAIT (a network, a loaded machine) must be able to catch
    up after an outage: the degraded wait scales with the waits measured while it answered, capped by timeout."""
    wait = CommandWait(timeout=0.5, recovery_wait=0.002)
    for _ in range(50):
        assert wait.answered(0.004) is None  # 4 ms per answered step
    assert wait.typical_wait == pytest.approx(0.004)
    wait.answered(1.0)  # a pause (a brief outage) barely moves it
    assert wait.typical_wait == pytest.approx(0.004 + TYPICAL_WEIGHT * 3 * 0.004)
    wait.typical_wait = 0.004
    wait.missed(publisher_count=1)
    assert wait.budget() == pytest.approx(RECOVERY_FACTOR * 0.004)
    assert wait.answered(0.3) == "recovered"  # a degraded answer does not count as typical
    assert wait.typical_wait == pytest.approx(0.004)
    slow = CommandWait(timeout=0.05, recovery_wait=0.002)
    slow.answered(0.04)
    slow.missed(publisher_count=1)
    assert slow.budget() == 0.05  # never beyond the timeout
    fast = CommandWait(timeout=1.0, recovery_wait=0.002)
    fast.answered(0.0001)
    fast.missed(publisher_count=1)
    assert fast.budget() == 0.002  # never below recovery_wait


def test_a_late_answer_while_degraded_waits_as_in_lockstep():
    """A stale answer shows a controller working through the states it missed: the step waits for it up to the
    timeout, so it catches up whatever its cycle; in lockstep or with no publisher the budget is unchanged."""
    wait = CommandWait(timeout=0.5, recovery_wait=0.002)
    assert wait.budget_after_late_answer() == 0.5
    wait.missed(publisher_count=1)
    assert wait.budget() == 0.002 and wait.budget_after_late_answer() == 0.5
    assert wait.answered() == "recovered" and wait.budget_after_late_answer() == 0.5
    wait.missed(publisher_count=0)
    assert wait.mode == GONE and wait.budget_after_late_answer() == 0.0
