"""Synthetic flight recordings with known errors, written with the shared RecordingWriter.

The flight (2 s at 1 kHz, quadrotor_ex4, plant mass 1.25 kg) is built so that every metric has a value
known in closed form; see :data:`EXPECTED`.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import QuaternionStamped, Transform, Twist, WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, String
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

from fsr_sim.recording.writer import RecordingWriter
from fsr_sim.ros.conversions import time_from_ns

STEPS = 2000
DT_NS = 1_000_000
SCENARIO_YAML = """\
name: synthetic_flight
vehicle: quadrotor_ex4
duration: 2.0
physics_dt: 0.001
plant: {mass: 1.25}
initial_state: {position: [0, 0, -1]}
environment: {ground: {enabled: true, height: 0.0}}
"""
TRUE_FORCE = np.array([1.0, 1.0, 0.0])
TRUE_TORQUE = np.array([0.0, 0.0, -0.4])
ESTIMATE_BIAS = np.array([0.02, -0.01, 0.0, 0.0, 0.0, 0.005])
RADIUS = 0.12  # quadrotor_ex4 rotor radius [m]
YAW_RATE = math.radians(10.0)  # rad/s of the reference
COMMAND_YAW_OFFSET = math.radians(4.0)  # attitude_cmd = reference yaw + 4 deg (the vehicle: + 2 deg, then + 10 deg)

EXPECTED = {
    "steps": STEPS,
    "position_final": 0.3, "position_peak": 0.5, "position_peak_time": 1.0,
    "attitude_final": 6.0, "attitude_peak": 6.0, "attitude_reference_final": 10.0,
    "velocity_error": 0.2, "angular_velocity_error": 0.1,
    "saturation_steps": 210, "saturation_first": 0.5, "worst_rotor": 3, "at_max": 200, "at_min": 10,
    # wrench_shortfall: axis -> (steps that gave way, max |shortfall|, its time); rounding-size values do not count
    "gave_way": {"torque_z": (200, 0.3, 0.6), "force_z": (10, 0.5, 1.5), "torque_x": (0, 0.0, None)},
    "mass_final": 1.26, "mass_true": 1.25, "mass_nominal": 1.2,
    "ground_ratio": [1 / (1 - (RADIUS / 8.0) ** 2), 1 / (1 - (RADIUS / 4.0) ** 2)],
}


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))


def position_error_x(t: float) -> float:
    """0 -> 0.5 m at t = 1 s (peak), then down to 0.3 m at t = 2 s."""
    return 0.5 * t if t <= 1.0 else 0.5 - 0.2 * (t - 1.0)


def write_synthetic(path: Path, *, topics: tuple[str, ...] | None = None, scenario: bool = True,
                    chunk_size: int = 16 * 1024) -> Path:
    """Write the synthetic flight to ``path`` (only ``topics`` if given, e.g. ``("odom",)``)."""

    def wanted(name: str) -> bool:
        return topics is None or name in topics

    metadata = {"fsr_scenario": {"yaml": SCENARIO_YAML}} if scenario else None
    with RecordingWriter(path, metadata=metadata, chunk_size=chunk_size) as writer:
        if wanted("sim_status"):
            status = {"state": "running", "reason": "", "sim_time": 0.0, "steps": 0}
            writer.write_message("/sim_status", String(data=json.dumps(status)), 0)
        for k in range(STEPS + 1):
            stamp_ns = k * DT_NS
            t = k * 1e-3
            stamp = time_from_ns(stamp_ns)
            ref_pos = np.array([t, 0.0, -1.0 - 0.5 * t])
            ref_yaw = YAW_RATE * t
            yaw = ref_yaw + math.radians(10.0 if t >= 1.5 else 2.0)
            v_d = np.array([1.0, 0.0, -0.5])
            if wanted("odom"):
                odom = Odometry()
                odom.header.stamp = stamp
                odom.header.frame_id = "world_ned"
                odom.child_frame_id = "base_link_frd"
                p = ref_pos + [position_error_x(t), 0.0, 0.0]
                odom.pose.pose.position.x, odom.pose.pose.position.y, odom.pose.pose.position.z = p
                o = odom.pose.pose.orientation
                o.x, o.y, o.z, o.w = yaw_quaternion(yaw)
                v_world = v_d + [0.0, 0.2, 0.0]
                c, s = math.cos(yaw), math.sin(yaw)
                v_body = [c * v_world[0] + s * v_world[1], -s * v_world[0] + c * v_world[1], v_world[2]]
                lin = odom.twist.twist.linear
                lin.x, lin.y, lin.z = v_body
                ang = odom.twist.twist.angular
                ang.x, ang.y, ang.z = 0.1, 0.0, YAW_RATE  # body; the reference's is R_d [0, 0, YAW_RATE]
                writer.write_message("/odom", odom, stamp_ns)
            if wanted("reference"):
                ref = MultiDOFJointTrajectory()
                ref.header.stamp = stamp
                ref.header.frame_id = "world_ned"
                ref.joint_names = ["base_link_frd"]
                point = MultiDOFJointTrajectoryPoint()
                transform = Transform()
                transform.translation.x, transform.translation.y, transform.translation.z = ref_pos
                r = transform.rotation
                r.x, r.y, r.z, r.w = yaw_quaternion(ref_yaw)
                velocity = Twist()
                velocity.linear.x, velocity.linear.y, velocity.linear.z = v_d
                velocity.angular.z = YAW_RATE  # world axes (fsr_control.nodes.messages)
                point.transforms = [transform]
                point.velocities = [velocity]
                point.accelerations = [Twist()]
                ref.points = [point]
                writer.write_message("/reference", ref, stamp_ns)
            if wanted("attitude_cmd"):
                command = QuaternionStamped()
                command.header.stamp = stamp
                command.header.frame_id = "world_ned"
                q = command.quaternion
                q.x, q.y, q.z, q.w = yaw_quaternion(ref_yaw + COMMAND_YAW_OFFSET)
                writer.write_message("/attitude_cmd", command, stamp_ns)
            if wanted("rotor_cmd"):
                speeds = [500.0] * 4
                if 500 <= k < 700:
                    speeds[2] = 1000.0
                if 1500 <= k < 1510:
                    speeds[0] = 0.0
                cmd = JointState()
                cmd.header.stamp = stamp
                cmd.name = [f"rotor_{i + 1}" for i in range(4)]
                cmd.velocity = speeds
                cmd.position = [0.0] * 4
                writer.write_message("/rotor_cmd", cmd, stamp_ns)
            if wanted("wrench_cmd"):
                thrust = 12.5 - (12.5 - 11.772) * t / 2.0
                writer.write_message("/wrench_cmd", _wrench(stamp, [0.0, 0.0, -thrust], [0.0, 0.0, 0.0]), stamp_ns)
            if wanted("wrench_shortfall"):
                shortfall = [0.0, 0.0, 0.0, 1e-15, 0.0, 0.0]  # rounding, not giving way
                if 500 <= k < 700:
                    shortfall[5] = 0.3 if k == 600 else -0.1  # yaw gave way while rotor 3 was at its maximum
                if 1500 <= k < 1510:
                    shortfall[2] = -0.5  # thrust gave way while rotor 1 was at its minimum
                writer.write_message("/wrench_shortfall", _wrench(stamp, shortfall[:3], shortfall[3:]), stamp_ns)
            if wanted("wrench_desired"):
                writer.write_message("/wrench_desired", _wrench(stamp, [0.0, 0.0, -12.5], [0.0, 0.0, 0.0]), stamp_ns)
            if wanted("wrench_truth"):
                writer.write_message("/wrench_truth", _wrench(stamp, TRUE_FORCE, TRUE_TORQUE), stamp_ns)
            if wanted("wrench_estimate"):
                estimate = np.zeros(6) if t < 0.5 else np.hstack((TRUE_FORCE, TRUE_TORQUE)) + ESTIMATE_BIAS
                writer.write_message("/wrench_estimate", _wrench(stamp, estimate[:3], estimate[3:]), stamp_ns)
            if wanted("mass_estimate"):
                writer.write_message("/mass_estimate", Float64(data=1.2 + 0.06 * min(t, 1.0)), stamp_ns)
        if wanted("sim_status"):
            status = {"state": "finished", "reason": "duration reached", "sim_time": 2.0, "steps": STEPS}
            writer.write_message("/sim_status", String(data=json.dumps(status)), STEPS * DT_NS)
    return path


def _wrench(stamp: object, force: object, torque: object) -> WrenchStamped:
    msg = WrenchStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = "base_link_frd"
    msg.wrench.force.x, msg.wrench.force.y, msg.wrench.force.z = (float(v) for v in force)
    msg.wrench.torque.x, msg.wrench.torque.y, msg.wrench.torque.z = (float(v) for v in torque)
    return msg


@pytest.fixture
def expected() -> dict:
    """Closed-form metrics of the synthetic flight."""
    return EXPECTED


@pytest.fixture
def write_flight():
    """:func:`write_synthetic` (tests import nothing from conftest: pytest runs with importlib mode)."""
    return write_synthetic


@pytest.fixture(scope="session")
def synthetic_recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_synthetic(tmp_path_factory.mktemp("synthetic") / "flight.mcap")
