"""The controller's packed CDR messages hold the values of the message objects it used to publish."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message

from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController
from fsr_control.nodes.messages import controller_messages
from fsr_control.nodes.packets import ControllerPackets
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.model.so3 import rotation_from_quaternion

SCENARIOS = Path(__file__).parent / "scenarios"


@pytest.mark.parametrize(("file", "overrides"), [
    ("ex4_wrench.yaml", []), ("ex4_wrench.yaml", ["actuation=rotors"]), ("ex5_voliro.yaml", []),
])
def test_packets_equal_the_message_objects(file, overrides):
    scenario = load_scenario(SCENARIOS / file, overrides)
    sim = simulation_config(scenario)
    controller = FlightController(controller_config(scenario), sim.vehicle, sim.actuation, sim.initial.position,
                                  sim.initial.rotation)
    rotors = sim.actuation == "rotors"
    packets = ControllerPackets(rotors, sim.vehicle.rotor_count, sim.vehicle.has_servos)
    rng = np.random.default_rng(5)
    for k in range(60):
        stamp = k * 1_000_000
        q = rng.normal(size=4) * ([0.1, 0.1, 1.0, 0.1] if k % 3 else [1.0, 1.0, 1.0, 1.0])
        output = controller.command(stamp * 1e-9, sim.initial.position + rng.normal(size=3) * 0.1,
                                    rotation_from_quaternion(q / np.linalg.norm(q)), rng.normal(size=3),
                                    rng.normal(size=3))
        expected = controller_messages(stamp, output, rotors)
        packed = packets.pack(stamp, controller.output)
        assert [topic for topic, _ in packed] == [topic for topic, _ in expected]
        for (topic, data), (_, message) in zip(packed, expected, strict=True):
            if topic in ("reference", "attitude_cmd"):  # quaternion and R w on floats: equal to rounding
                ours, theirs = numbers(data, type(message)), numbers(serialize_message(message), type(message))
                assert ours.keys() == theirs.keys()
                for key in ours:
                    np.testing.assert_allclose(ours[key], theirs[key], rtol=1e-14, atol=1e-14, err_msg=key)
            else:
                assert deserialize_message(data, type(message)) == message, topic


def numbers(data: bytes, cls: type) -> dict[str, np.ndarray]:
    """Every numeric field of a CDR message (dotted path -> values)."""
    from fsr_sim.recording.cdr_columns import message_layout

    layout = message_layout(data, cls)
    out = {}
    for path, (offset, dtype, count) in layout.numbers.items():
        out[path] = np.frombuffer(data, dtype=dtype, count=1 if count is None else count, offset=offset)
    return out
