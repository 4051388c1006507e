"""The rule that ends a helper node after the flight: every sim_status final, then quiet."""

from __future__ import annotations

import json

import pytest

from fsr_sim.ros.flight_end import FlightEndRule, final_state


class FakeClock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def status(state: str) -> str:
    return json.dumps({"state": state, "reason": "", "sim_time": 1.0, "steps": 1000})


@pytest.mark.parametrize("state", ["finished", "diverged", "stopped"])
def test_final_states(state):
    assert final_state(status(state)) == state


@pytest.mark.parametrize("text", [status("running"), "not json", "[1, 2]", json.dumps({"reason": "x"})])
def test_not_final(text):
    assert final_state(text) is None


def test_ends_only_when_every_namespace_is_final_and_quiet():
    clock = FakeClock()
    rule = FlightEndRule(["/uav1/sim_status", "/uav2/sim_status"], quiet=0.1, linger=1.5, clock=clock)
    rule.status("/uav1/sim_status", status("finished"))
    clock.now = 10.0
    assert not rule.ended(lambda: True)  # /uav2 still flying
    rule.status("/uav2/sim_status", status("running"))
    clock.now = 20.0
    assert not rule.ended(lambda: True)
    rule.status("/uav2/sim_status", status("diverged"))
    clock.now = 20.05
    assert not rule.ended(lambda: True)  # not quiet yet
    clock.now = 20.2
    assert not rule.ended(lambda: False)  # a producer still publishes: wait for linger
    assert rule.ended(lambda: True)
    rule.activity()
    clock.now = 21.0
    assert not rule.ended(lambda: False)
    clock.now = 21.8
    assert rule.ended(lambda: False)
    assert rule.describe() == "/uav1/sim_status finished, /uav2/sim_status diverged"


def test_first_final_state_is_kept():
    rule = FlightEndRule(["/sim_status"])
    rule.status("/sim_status", status("finished"))
    rule.status("/sim_status", status("stopped"))
    assert rule.describe() == "/sim_status finished"


def test_needs_a_topic():
    with pytest.raises(ValueError, match="at least one sim_status topic"):
        FlightEndRule([])
