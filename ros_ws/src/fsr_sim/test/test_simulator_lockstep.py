"""Lockstep bookkeeping of the simulator node (pure logic, no ROS graph)."""

import pytest

from fsr_sim.nodes.lockstep import (
    AHEAD,
    CURRENT,
    DEGRADED,
    GONE,
    LOCKSTEP,
    STALE,
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
