"""Controller node (console script ``controller``): answers every ``odom`` with the command for it.

Parameters: ``scenario`` (built-in name or YAML path; its ``controller`` and ``trajectory`` sections),
``controller_type`` (``geometric`` | ``voliro``, overrides the scenario), gain overrides ``k_p``, ``k_v``,
``k_d``, ``k_r``, ``k_w`` (3 numbers, the diagonal), ``exit_on_finish`` (default true: end by itself once
``sim_status`` reports the end of the flight, :mod:`fsr_sim.ros.flight_end`). An invalid value exits with
code 2 and names it.

Subscribes ``odom`` (STREAM_QOS) and ``goal`` (GOAL_QOS). Each odom (stamp ``t_k``) is answered, in the callback, with
``rotor_cmd`` (rotor actuation), ``wrench_cmd`` and ``reference``, all stamped ``t_k`` (lockstep contract).
NaN/inf odom or goals are dropped with a rate-limited warning. At exit it logs the saturation summary and
the callback's cost.
"""

from __future__ import annotations

import copy
import sys
import time

from geometry_msgs.msg import PoseStamped, WrenchStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory

from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController, seconds_from_ns
from fsr_control.nodes.messages import goal_from_message, reference_message
from fsr_sim.config.scenario import Scenario, load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.ros.conversions import (
    ns_from_time,
    odometry_is_finite,
    rotor_command,
    state_from_odometry,
    wrench_stamped,
)
from fsr_sim.ros.flight_end import FlightEndWatch
from fsr_sim.ros.qos import GOAL_QOS, STREAM_QOS
from fsr_sim.ros.runtime import RateLimitedWarning, exit_on_finish_parameter, run_node

GAIN_PARAMETERS = ("k_p", "k_v", "k_d", "k_r", "k_w")


def scenario_with_parameters(scenario: Scenario, controller_type: str, gains: dict[str, list[float]]) -> Scenario:
    """A copy of ``scenario`` with the node's parameter overrides applied to its ``controller`` section."""
    data = copy.deepcopy(scenario.data)
    controller = data.get("controller") or {}
    if controller_type:
        controller["type"] = controller_type
    if gains:
        controller["gains"] = {**(controller.get("gains") or {}), **gains}
    data["controller"] = controller
    return Scenario(data=data, source=scenario.source, base_dir=scenario.base_dir)


class ControllerNode(Node):
    def __init__(self) -> None:
        super().__init__("controller")
        name = self.declare_parameter("scenario", "").value
        controller_type = self.declare_parameter("controller_type", "").value
        exit_on_finish = exit_on_finish_parameter(self, "controller")
        if not name:
            raise ConfigError("scenario", "parameter is required (-p scenario:=<name or path>)", "controller")
        gains = {}
        for gain in GAIN_PARAMETERS:
            value = self.declare_parameter(gain, None, ParameterDescriptor(dynamic_typing=True)).value
            if value is None:
                continue
            if isinstance(value, (str, bool, int, float)) or len(value) != 3:
                raise ConfigError(f"parameter '{gain}'", f"must be 3 numbers (the diagonal), got {value!r}",
                                  "controller")
            gains[gain] = [float(v) for v in value]
        scenario = load_scenario(name)
        try:
            config = controller_config(scenario_with_parameters(scenario, controller_type, gains))
        except ConfigError as error:
            overridden = {"controller.type": "controller_type", **{f"controller.gains.{g}": g for g in gains}}
            if error.key in overridden:
                raise ConfigError(f"parameter '{overridden[error.key]}'", error.reason, "controller") from None
            raise
        sim = simulation_config(scenario)
        self.controller = FlightController(
            config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation
        )
        self.rotors = sim.actuation == "rotors"
        self.rotor_pub = self.create_publisher(JointState, "rotor_cmd", STREAM_QOS) if self.rotors else None
        self.wrench_pub = self.create_publisher(WrenchStamped, "wrench_cmd", STREAM_QOS)
        self.reference_pub = self.create_publisher(MultiDOFJointTrajectory, "reference", STREAM_QOS)
        self.create_subscription(Odometry, "odom", self.on_odom, STREAM_QOS)
        self.create_subscription(PoseStamped, "goal", self.on_goal, GOAL_QOS)
        self.flight_end = FlightEndWatch(self) if exit_on_finish else None
        self.warn = RateLimitedWarning(self.get_logger())
        self.callback_seconds = 0.0
        self.callbacks = 0
        self.get_logger().info(
            f"{config.type} controller for '{sim.vehicle.name}' ({sim.actuation} actuation), "
            f"{len(config.waypoints)} waypoint(s)"
        )

    def done(self) -> bool:
        return self.flight_end is not None and self.flight_end.ended()

    def on_odom(self, msg: Odometry) -> None:
        start = time.perf_counter()
        if self.flight_end is not None:
            self.flight_end.activity()
        if not odometry_is_finite(msg):
            self.warn("dropped an odom with NaN/inf values")
            return
        stamp_ns = ns_from_time(msg.header.stamp)
        position, rotation, velocity_world, angular_velocity = state_from_odometry(msg)
        try:
            output = self.controller.command(
                seconds_from_ns(stamp_ns), position, rotation, velocity_world, angular_velocity
            )
        except (ValueError, ArithmeticError) as error:  # never crash mid-flight; the simulator holds/fails safe
            self.warn(f"no command for odom at {stamp_ns * 1e-9:.3f} s: {error}")
            return
        if self.rotor_pub is not None:
            self.rotor_pub.publish(rotor_command(stamp_ns, output.rotor_speeds, output.tilt_angles))
        self.wrench_pub.publish(wrench_stamped(stamp_ns, output.force_body, output.torque_body))
        self.reference_pub.publish(reference_message(stamp_ns, output.reference))
        self.callback_seconds += time.perf_counter() - start
        self.callbacks += 1

    def on_goal(self, msg: PoseStamped) -> None:
        try:
            position, rotation = goal_from_message(msg)
            self.controller.set_goal(position, rotation)
        except ValueError as error:
            self.warn(f"dropped goal: {error}")
            return
        self.get_logger().info(f"new goal {position.tolist()} from t = {self.controller.last_stamp:.3f} s")

    def close(self) -> None:
        saturation = self.controller.saturation
        if saturation.count:
            self.get_logger().warning(
                f"rotor saturation: {saturation.count} commands clamped, first at {saturation.first_time:.3f} s, "
                f"worst rotor {saturation.worst_rotor} ({saturation.worst_excess:.1f} rad/s beyond its limit)"
            )
        else:
            self.get_logger().info("rotor saturation: none")
        if self.callbacks:
            self.get_logger().info(
                f"{self.callbacks} odom answered, {1e6 * self.callback_seconds / self.callbacks:.0f} us per callback"
            )


def main(argv: list[str] | None = None) -> int:
    return run_node(lambda _args: ControllerNode(), argv)


if __name__ == "__main__":
    sys.exit(main())
