"""fsr-fly tells every node the topics its recorder takes (fsr_sim.ros.recorder_match), and a node waits for a
reader on each of them it publishes."""

from __future__ import annotations

from pathlib import Path

import pytest

from fsr_bringup.runner.flight import VehicleLaunch, node_commands
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import CLOCK, recorded_topics, recording_selection
from fsr_sim.ros.recorder_match import parse_recorded_topics, unmatched


def parameter_of(argv: list[str]) -> frozenset[str]:
    values = [item.split(":=", 1)[1] for item in argv if item.startswith("recorded_topics:=")]
    assert len(values) == 1, argv
    return parse_recorded_topics(values[0])


@pytest.mark.parametrize("selection", [None, "odom,wrench_shortfall"])
def test_every_node_but_the_recorder_gets_the_recorders_topics(selection):
    only = None if selection is None else recording_selection(selection)
    members = [VehicleLaunch("", Path("a.yaml"), True), VehicleLaunch("/uav2", Path("b.yaml"), False)]
    commands = node_commands(members, Path("run.mcap"), Path("s.yaml"), record_topics=only)
    expected = frozenset({*recorded_topics(), CLOCK.name}) if only is None else only
    for name, argv in commands:
        if name == "recorder":
            assert not any(item.startswith("recorded_topics:=") for item in argv)
        else:
            assert parameter_of(argv) == expected, name
    assert {name for name, _ in commands} == {"recorder", "estimator", "controller", "simulator", "uav2/controller",
                                              "uav2/simulator"}


class FakePublisher:
    def __init__(self, readers: int) -> None:
        self.readers = readers

    def get_subscription_count(self) -> int:
        return self.readers


def test_unmatched_names_the_recorded_publishers_without_a_reader():
    publishers = {"odom": FakePublisher(1), "wrench_truth": FakePublisher(0), "sim_progress": FakePublisher(0),
                  "/clock": None}
    assert unmatched(publishers, frozenset({"odom", "wrench_truth", "/clock"})) == ["wrench_truth"]
    assert unmatched(publishers, frozenset()) == []


def test_the_parameter_is_a_comma_separated_list():
    assert parse_recorded_topics(" odom, /clock ,,") == frozenset({"odom", "/clock"})
    assert parse_recorded_topics("") == parse_recorded_topics(None) == frozenset()
    with pytest.raises(ConfigError, match="recorded_topics"):
        parse_recorded_topics(3)
