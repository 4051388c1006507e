"""What a viewer shows of a flight: /tf_static, /tf and markers in every recording (fsr_bringup.visualization,
fsr_bringup.recording.derived), and the Foxglove layout shipped in docs/foxglove."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_bringup.visualization.config import visualization_config
from fsr_bringup.visualization.foxglove import layout, layout_text
from fsr_bringup.visualization.frames import NED_TO_ENU, WORLD_IN_MAP, axis_quaternions
from fsr_bringup.visualization.markers import FORCE_PER_ARM, speed_colours
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import (
    BODY_FLU_FRAME,
    BODY_FRAME,
    BY_NAME,
    MAP_FRAME,
    MARKERS,
    TF,
    TF_STATIC,
    WORLD_FRAME,
    recording_selection,
    rotor_frame,
)
from fsr_sim.model.rotors import rotor_axes
from fsr_sim.model.so3 import quaternion_from_rotation, rotation_from_quaternion
from fsr_sim.ros.message_schema import message_class

ROOT = Path(__file__).resolve().parents[4]


def decoded(path: Path, topics: list[str]) -> dict[str, list[tuple[int, object]]]:
    """topic -> [(log time [ns], message)] decoded by mcap_ros2 from the schemas in the file."""
    with open(path, "rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        found: dict[str, list[tuple[int, object]]] = {}
        for _schema, channel, message, value in reader.iter_decoded_messages(topics=topics):
            found.setdefault(channel.topic, []).append((message.log_time, value))
    return found


def field_type(type_name: str, path: str) -> str:
    """The type of a Foxglove message path's field (``points[0].transforms[0].translation.x``); AssertionError
    for a field the message does not have."""
    for part in path.split("."):
        name, _, index = part.partition("[")
        fields = message_class(type_name).get_fields_and_field_types()
        assert name in fields, (type_name, name)
        type_name = fields[name]
        if index:  # an element of a sequence: sequence<pkg/Type>, double[4], ...
            type_name = type_name.removeprefix("sequence<").removesuffix(">").split("[")[0]
    return type_name


def fly(tmp_path: Path, name: str, duration: float = 0.5, **overrides: object) -> Path:
    scenario = load_scenario(name, values={"duration": duration, **overrides})
    out = tmp_path / f"{name}.mcap"
    fly_in_process(scenario, recording=out)
    return out


@pytest.fixture(scope="module")
def ex5_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fly(tmp_path_factory.mktemp("ex5"), "ex5_voliro")


@pytest.fixture(scope="module")
def ex4_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fly(tmp_path_factory.mktemp("ex4"), "ex4_geometric")


def test_map_to_world_ned_is_the_ned_enu_rotation_and_base_link_is_flu(ex4_recording):
    (_, static), = decoded(ex4_recording, [TF_STATIC.name])[TF_STATIC.name]
    transforms = {(t.header.frame_id, t.child_frame_id): t.transform for t in static.transforms}
    world = transforms[(MAP_FRAME, WORLD_FRAME)]
    q = world.rotation
    rotation = rotation_from_quaternion([q.x, q.y, q.z, q.w])
    np.testing.assert_allclose(rotation @ [1.0, 2.0, 3.0], [2.0, 1.0, -3.0], atol=1e-15)  # (n, e, d) -> (e, n, -d)
    np.testing.assert_allclose([q.x, q.y, q.z, q.w], WORLD_IN_MAP, atol=0)
    np.testing.assert_array_equal(WORLD_IN_MAP, quaternion_from_rotation(NED_TO_ENU))  # the literal, to the bit
    flu = transforms[(BODY_FRAME, BODY_FLU_FRAME)].rotation
    np.testing.assert_allclose(rotation_from_quaternion([flu.x, flu.y, flu.z, flu.w]) @ [1.0, 2.0, 3.0],
                               [1.0, -2.0, -3.0], atol=1e-15)
    vehicle = simulation_config(load_scenario("ex4_geometric")).vehicle
    for i in range(vehicle.rotor_count):  # fixed rotors: their frames are static, at the rotor centres
        t = transforms[(BODY_FRAME, rotor_frame(i))]
        np.testing.assert_allclose([t.translation.x, t.translation.y, t.translation.z], vehicle.positions[i])
        r = rotation_from_quaternion([t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w])
        np.testing.assert_allclose(r @ [0.0, 0.0, 1.0], -vehicle.thrust_axes[i], atol=1e-15)


@pytest.mark.parametrize("recording", ["ex4_recording", "ex5_recording"])
def test_every_tf_equals_the_odom_with_its_stamp(recording, request):
    path = request.getfixturevalue(recording)
    found = decoded(path, [TF.name, "/odom"])
    odom = {stamp: message.pose.pose for stamp, message in found["/odom"]}
    bodies = [(stamp, t) for stamp, message in found[TF.name] for t in message.transforms
              if t.child_frame_id == BODY_FRAME]
    assert len(bodies) == len(odom) == 501
    for stamp, transform in bodies:
        assert transform.header.frame_id == WORLD_FRAME
        assert transform.header.stamp.sec * 1_000_000_000 + transform.header.stamp.nanosec == stamp
        pose = odom[stamp]
        got = [getattr(transform.transform.translation, a) for a in "xyz"]
        got += [getattr(transform.transform.rotation, a) for a in "xyzw"]
        want = [getattr(pose.position, a) for a in "xyz"] + [getattr(pose.orientation, a) for a in "xyzw"]
        assert np.max(np.abs(np.subtract(got, want))) <= 1e-12


def test_tilting_rotor_frames_follow_the_recorded_tilts(ex5_recording):
    found = decoded(ex5_recording, [TF.name, "/rotor_cmd", TF_STATIC.name])
    vehicle = simulation_config(load_scenario("ex5_voliro")).vehicle
    n = vehicle.rotor_count
    static = found[TF_STATIC.name][0][1]
    assert rotor_frame(0) not in {t.child_frame_id for t in static.transforms}  # they move: in /tf
    commands = {stamp: message for stamp, message in found["/rotor_cmd"]}
    rotors = [(stamp, message) for stamp, message in found[TF.name] if len(message.transforms) == n]
    assert len(rotors) == 26  # 0.5 s at 50 Hz, and t = 0
    for stamp, message in rotors:
        tilts = np.array(commands[stamp].position[n:2 * n])
        axes = rotor_axes(vehicle, tilts)
        for i, transform in enumerate(message.transforms):
            assert (transform.header.frame_id, transform.child_frame_id) == (BODY_FRAME, rotor_frame(i))
            q = transform.transform.rotation
            np.testing.assert_allclose(rotation_from_quaternion([q.x, q.y, q.z, q.w]) @ [0, 0, 1], -axes[i],
                                       atol=1e-12)


def test_markers_draw_the_vehicle_where_odometry_puts_it(ex5_recording):
    found = decoded(ex5_recording, ["/" + MARKERS.name, "/odom", "/rotor_cmd",
                                    "/wrench_truth", "/wrench_estimate", "/reference"])
    scenario = load_scenario("ex5_voliro")
    vehicle = simulation_config(scenario).vehicle
    n, arm = vehicle.rotor_count, vehicle.arm_length
    by_stamp = {topic: dict(messages) for topic, messages in found.items()}
    markers = found["/" + MARKERS.name]
    assert [stamp for stamp, _ in markers] == [k * 20_000_000 for k in range(26)]  # 50 Hz of simulated time
    for stamp, array in markers:
        pose = by_stamp["/odom"][stamp].pose.pose
        p = np.array([pose.position.x, pose.position.y, pose.position.z])
        rotation = rotation_from_quaternion([pose.orientation.x, pose.orientation.y, pose.orientation.z,
                                             pose.orientation.w])
        command = by_stamp["/rotor_cmd"][stamp]
        speeds, tilts = np.array(command.velocity[:n]), np.array(command.position[n:2 * n])
        shown = {(m.ns, m.id): m for m in array.markers}
        assert all(m.header.frame_id == WORLD_FRAME and m.header.stamp.sec * 10**9 + m.header.stamp.nanosec == stamp
                   for m in array.markers)
        arms = np.array([[q.x, q.y, q.z] for q in shown[("arms", 0)].points])
        np.testing.assert_allclose(arms[1::2], p + vehicle.positions @ rotation.T, atol=1e-12)
        np.testing.assert_allclose(arms[0::2], np.broadcast_to(p, (n, 3)), atol=1e-12)
        axes = rotor_axes(vehicle, tilts) @ rotation.T
        for i in range(n):
            arrow = shown[("thrust", i)].points
            start, end = (np.array([q.x, q.y, q.z]) for q in arrow)
            length = arm * vehicle.c_f * speeds[i] ** 2 / (vehicle.weight / n)
            np.testing.assert_allclose(end - start, length * axes[i], atol=1e-12)
            colour = shown[("rotors", i)].color
            fraction = (speeds[i] - vehicle.rotor_speed_min) / (vehicle.rotor_speed_max - vehicle.rotor_speed_min)
            np.testing.assert_allclose([colour.r, colour.g, colour.b, colour.a], speed_colours(fraction), atol=1e-7)
        force = by_stamp["/wrench_truth"][stamp].wrench.force
        start, end = (np.array([q.x, q.y, q.z]) for q in shown[("force_true", 0)].points)
        np.testing.assert_allclose(end - start, rotation @ [force.x, force.y, force.z]
                                   * arm / (FORCE_PER_ARM * vehicle.weight), atol=1e-12)
        assert ("force_estimate", 0) in shown and ("path", 0) in shown and ("ground", 0) in shown
        reference = by_stamp["/reference"][stamp].points[0].transforms[0].translation
        position = shown[("reference_position", 0)].pose.position
        assert (position.x, position.y, position.z) == (reference.x, reference.y, reference.z)


def test_speed_colours_run_from_blue_at_the_lower_limit_to_red_at_the_upper():
    colours = speed_colours(np.array([-1.0, 0.0, 0.5, 1.0, 2.0]))
    assert colours[0].tolist() == colours[1].tolist() and colours[3].tolist() == colours[4].tolist()
    assert colours[1, 2] > colours[1, 0] and colours[3, 0] > colours[3, 2]  # blue, then red
    np.testing.assert_allclose(colours[2, :3], [0.87, 0.87, 0.87])


def test_axis_quaternions_turn_z_onto_the_axis():
    axes = np.array([[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0], [0, 0.6, -0.8]])
    for axis, q in zip(axes, axis_quaternions(axes), strict=True):
        np.testing.assert_allclose(rotation_from_quaternion(q) @ [0, 0, 1.0], axis, atol=1e-15)


def test_markers_off_leave_the_flight_and_the_other_topics_unchanged(tmp_path, ex4_recording):
    off = fly(tmp_path, "ex4_geometric", **{"visualization.markers": False})
    found = decoded(off, ["/" + MARKERS.name, TF.name])
    assert "/" + MARKERS.name not in found and len(found[TF.name]) == 501
    with open(off, "rb") as a, open(ex4_recording, "rb") as b:
        ours, theirs = make_reader(a), make_reader(b)
        kept = {}
        for _, channel, message in theirs.iter_messages():
            kept.setdefault(channel.topic, []).append(message.data)
        for _, channel, message in ours.iter_messages():
            kept.setdefault("off " + channel.topic, []).append(message.data)
    for topic in ("/odom", "/wrench_cmd", "/wrench_estimate", TF.name):
        assert kept["off " + topic] == kept[topic], topic


def test_the_recording_keeps_only_the_derived_topics_asked_for(tmp_path):
    scenario = load_scenario("ex4_geometric", values={"duration": 0.1})
    out = tmp_path / "only.mcap"
    fly_in_process(scenario, recording=out, record_topics=recording_selection("odom,tf"))
    found = decoded(out, [TF.name, TF_STATIC.name, "/" + MARKERS.name])
    assert set(found) == {TF.name}


def test_visualization_keys_are_checked():
    scenario = load_scenario("ex4_geometric", values={"visualization.marker_rate": 25.0})
    assert visualization_config(scenario).marker_stride(0.001) == 40
    for bad, key in (({"marker_rate": 0}, "visualization.marker_rate"), ({"markers": "yes"}, "visualization.markers"),
                     ({"marker_hz": 5}, "visualization.marker_hz")):
        with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
            values = {f"visualization.{k}": v for k, v in bad.items()}
            visualization_config(load_scenario("ex4_geometric", values=values))


def test_the_shipped_foxglove_layout_is_the_generated_one_and_names_real_fields():
    assert (ROOT / "docs" / "foxglove" / "fsr.json").read_text() == layout_text(), (
        "docs/foxglove/fsr.json differs: run `python -m fsr_bringup.visualization.foxglove > docs/foxglove/fsr.json`")
    document = layout()
    scene = document["configById"]["3D!fsr"]
    assert scene["followTf"] == MAP_FRAME and "/" + MARKERS.name in scene["topics"]
    for panel in (p for name, p in document["configById"].items() if name.startswith("Plot!")):
        for series in panel["paths"]:
            topic, _, path = series["value"].partition(".")
            assert field_type(BY_NAME[topic.lstrip("/")].type, path) in ("double", "float"), series["value"]
    json.dumps(document)  # plain JSON
