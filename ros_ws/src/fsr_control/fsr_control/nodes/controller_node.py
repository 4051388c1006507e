"""Controller node (console script ``controller``): answers every ``odom`` with the command for it.

Parameters: :data:`USAGE` (what ``controller --help`` prints; ``exit_on_finish``: :mod:`fsr_sim.ros.flight_end`).
An invalid value exits with code 2 and names it.

Subscribes ``odom`` (STREAM_QOS) and ``goal`` (GOAL_QOS) and, where the law or its observer reads them, ``imu``
and ``rotor_state`` (:attr:`fsr_control.flight_controller.FlightController.needs_imu`, ``needs_rotor_state``;
paired with the odom of their stamp by :class:`fsr_control.nodes.inputs.StampedInputs`). Each odom (stamp
``t_k``) is answered, in the callback that completes its stamp, with
``rotor_cmd`` (rotor actuation), ``wrench_cmd``, ``wrench_shortfall`` (demanded minus commanded body wrench: which
axis gave way at the rotor limits, see fsr_control.allocation), ``reference``, ``attitude_cmd`` (the commanded
attitude ``R_c``) and ``wrench_desired`` (the law's wrench before allocation), all stamped ``t_k`` (lockstep
contract): the compiled core's tick (:meth:`fsr_control.flight_controller.FlightController.command_row`, what the
in-process loop runs) packed by :class:`fsr_control.nodes.packets.ControllerPackets` and published as CDR bytes.
``odom`` is read from its CDR bytes (:func:`fsr_sim.ros.conversions.odometry_state_from_bytes`) and taken from a
wait set (``hot_subscriptions``, see
:class:`fsr_sim.ros.wait_set.WaitSetSpinner`); the node has no parameter services (parameters are read once).
NaN/inf odom or goals are dropped with a rate-limited warning. Asked to stop after the simulator ended (its
final ``sim_status``), it first answers every odom still queued up to the simulator's last state and waits
for its subscribers' acknowledgements (:mod:`fsr_sim.ros.flight_end`). At exit it logs the saturation
summary, the disturbance compensation's (``controller.compensation``: steps compensated, off in contact, late
estimates) and the callback's cost.
"""

from __future__ import annotations

import copy
import sys
import time

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node

from fsr_control.config.controller_config import controller_config
from fsr_control.controllers.catalog import LAWS
from fsr_control.flight_controller import FlightController, seconds_from_ns
from fsr_control.nodes.inputs import IMU_INPUT, ODOM_INPUT, ROTOR_STATE_INPUT, StampedInputs
from fsr_control.nodes.messages import goal_from_message
from fsr_control.nodes.packets import ControllerPackets
from fsr_sim.config.scenario import Scenario, load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import (
    BY_NAME,
    CONTROLLER,
    EXIT_CONFIG_ERROR,
    EXIT_FAILURE,
    EXIT_OK,
    GOAL,
    IMU,
    ODOM,
    ROTOR_STATE,
    SIM_STATUS,
)
from fsr_sim.model.rotors import WRENCH_AXES
from fsr_sim.nodes.commands import RotorCommandReader
from fsr_sim.ros import cdr_read
from fsr_sim.ros.conversions import odometry_state_from_bytes
from fsr_sim.ros.endpoints import publisher, subscription
from fsr_sim.ros.flight_end import FlightEnd
from fsr_sim.ros.node_usage import NodeUsage, Parameter
from fsr_sim.ros.recorder_match import RECORDED_TOPICS, recorded_topics_parameter, wait_until_recorded
from fsr_sim.ros.runtime import RateLimitedWarning, exit_on_finish_parameter, run_node

GAIN_PARAMETERS = ("k_p", "k_v", "k_d", "k_r", "k_w")
USAGE = NodeUsage(
    CONTROLLER,
    "Answers every odom with the command for it: planner, control law and allocation (the lockstep).",
    (
        Parameter("scenario", "", "built-in scenario name or scenario YAML path (required): its controller and "
                                  "trajectory sections"),
        Parameter("controller_type", "", f"{' | '.join(LAWS)}: overrides the scenario's controller.type"),
        *(Parameter(gain, "", "3 numbers, the gain's diagonal: overrides the scenario's") for gain in GAIN_PARAMETERS),
        Parameter("exit_on_finish", "true", "end by itself once sim_status reports the end of the flight"),
        RECORDED_TOPICS,
    ),
    (ODOM, IMU, ROTOR_STATE, GOAL, SIM_STATUS),
    (EXIT_OK, EXIT_FAILURE, EXIT_CONFIG_ERROR),
)


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
        super().__init__("controller", start_parameter_services=False)
        name = self.declare_parameter("scenario", "").value
        controller_type = self.declare_parameter("controller_type", "").value
        exit_on_finish = exit_on_finish_parameter(self, "controller")
        recorded = recorded_topics_parameter(self)
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
        # Load the compiled tick now, on a throwaway controller (numba's start-up and its cache, ~0.3 s), before
        # subscribing: the simulator steps only once we are subscribed, so the first odom is answered at once.
        FlightController(config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation).command(
            0.0, sim.initial.position, sim.initial.rotation, sim.initial.velocity, sim.initial.angular_velocity)
        self.rotors = sim.actuation == "rotors"
        self.packets = ControllerPackets(self.rotors, sim.vehicle.rotor_count, sim.vehicle.has_servos)
        self.publishers_by_topic = {name: publisher(self, BY_NAME[name]) for name in self.packets.templates}
        wait_until_recorded(self, self.publishers_by_topic, recorded)  # before odom: no state comes before
        controller = self.controller
        self.inputs = StampedInputs(controller.needs_imu, controller.needs_rotor_state)
        self.hot_subscriptions = []
        if controller.needs_imu:  # subscribed before odom: a stamp's inputs all come from the simulator at once
            imu = subscription(self, IMU, self.on_imu, raw=True)
            self.hot_subscriptions.append((imu, self.on_imu))
        if controller.needs_rotor_state:
            self.rotor_reader = RotorCommandReader(sim.vehicle.rotor_count, sim.vehicle.has_servos)
            self.no_tilts = np.zeros(sim.vehicle.rotor_count)
            rotor_state = subscription(self, ROTOR_STATE, self.on_rotor_state, raw=True)
            self.hot_subscriptions.append((rotor_state, self.on_rotor_state))
        odom = subscription(self, ODOM, self.on_odom, raw=True)
        self.hot_subscriptions.insert(0, (odom, self.on_odom))
        subscription(self, GOAL, self.on_goal)
        self.flight_end = FlightEnd(self, exit_on_finish)
        self.stop_flag: object = None  # run_node's StopFlag: bounds the drain after a signal
        self.answered_ns: int | None = None  # stamp of the last odom handled
        self.warn = RateLimitedWarning(self.get_logger())
        self.callback_seconds = 0.0
        self.callbacks = 0
        self.get_logger().info(
            f"{config.type} controller for '{sim.vehicle.name}' ({sim.actuation} actuation), "
            + (f"{len(config.waypoints)} waypoint(s)" if config.path is None else f"a {config.trajectory_kind} path")
        )

    def done(self) -> bool:
        return self.flight_end.ended()

    def on_odom(self, data: bytes) -> None:
        """Answer one ``odom`` (CDR bytes) with every controller topic, stamped like it (once the ``imu`` and
        ``rotor_state`` of its stamp are there too, where the controller reads them)."""
        start = time.perf_counter()
        self.flight_end.activity()
        try:
            state = odometry_state_from_bytes(data)
        except ValueError as error:
            self.warn(f"dropped an odom: {error}")
            return
        if len(self.inputs.kinds) == 1:
            self.answer(start, state)
        else:
            self.offer(start, ODOM_INPUT, state[0], state)

    def on_imu(self, data: bytes) -> None:
        """Take one ``imu`` (CDR bytes): angular velocity [rad/s] and specific force [m/s^2], body FRD."""
        start = time.perf_counter()
        self.flight_end.activity()
        try:
            stamp_ns, values = cdr_read.imu(data)
        except ValueError as error:
            self.warn(f"dropped an imu: {error}")
            return
        imu = np.array(values)
        if not np.isfinite(imu).all():
            self.warn(f"dropped an imu at {stamp_ns * 1e-9:.3f} s: it holds NaN or inf")
            return
        self.offer(start, IMU_INPUT, stamp_ns, imu)

    def on_rotor_state(self, data: bytes) -> None:
        """Take one ``rotor_state`` (CDR bytes): the rotors' measured speeds [rad/s] and tilts [rad]."""
        start = time.perf_counter()
        self.flight_end.activity()
        try:
            stamp_ns, speeds, tilts = self.rotor_reader.read_stamped(data)
        except ValueError as error:
            self.warn(f"dropped a rotor_state: {error}")
            return
        self.offer(start, ROTOR_STATE_INPUT, stamp_ns, (speeds, self.no_tilts if tilts is None else tilts))

    def offer(self, start: float, kind: int, stamp_ns: int, value: object) -> None:
        """One input of a stamp; answer the stamp once it has all of them."""
        inputs = self.inputs
        values = inputs.add(kind, stamp_ns, value)
        if values is None:
            return
        found = dict(zip(inputs.kinds, values, strict=True))
        rotors = found.get(ROTOR_STATE_INPUT, (None, None))
        self.answer(start, found[ODOM_INPUT], found.get(IMU_INPUT), *rotors)

    def answer(self, start: float, state: tuple, imu: np.ndarray | None = None, speeds: np.ndarray | None = None,
               tilts: np.ndarray | None = None) -> None:
        """Publish the command for the odom ``state`` (stamp, position, rotation, velocities) and the
        measurements of its stamp."""
        stamp_ns, position, rotation, velocity_world, angular_velocity = state
        try:
            row = self.controller.command_row(
                seconds_from_ns(stamp_ns), position, rotation, velocity_world, angular_velocity, imu, speeds, tilts
            )
        except (ValueError, ArithmeticError) as error:  # never crash mid-flight; the simulator holds/fails safe
            self.warn(f"no command for odom at {stamp_ns * 1e-9:.3f} s: {error}")
            self.answered_ns = stamp_ns
            return
        publishers = self.publishers_by_topic
        for topic, packet in self.packets.pack(stamp_ns, row):
            publishers[topic].publish(packet)
        self.answered_ns = stamp_ns
        self.callback_seconds += time.perf_counter() - start
        self.callbacks += 1

    def on_goal(self, msg: object) -> None:  # geometry_msgs/PoseStamped
        known = len(self.controller.plan_adjustments)
        try:
            position, rotation = goal_from_message(msg)
            self.controller.set_goal(position, rotation)
        except ValueError as error:  # also a goal beyond the authority with trajectory.feasibility: refuse
            self.warn(f"dropped goal: {error}")
            return
        self.get_logger().info(f"new goal {position.tolist()} from t = {self.controller.last_stamp:.3f} s")
        for adjustment in self.controller.plan_adjustments[known:]:
            self.get_logger().warning(adjustment.text())

    def close(self) -> None:
        self.flight_end.drain(lambda: self.answered_ns, list(self.publishers_by_topic.values()))
        saturation = self.controller.saturation
        if saturation.count:
            self.get_logger().warning(
                f"rotor saturation: {saturation.count} commands saturated, first at {saturation.first_time:.3f} s, "
                f"worst rotor {saturation.worst_rotor} ({saturation.worst_excess:.1f} rad/s beyond its limit)"
            )
            gave_way = [f"{axis} {steps} steps (max {largest:.3g})" for axis, steps, largest in
                        zip(WRENCH_AXES, saturation.axis_steps, saturation.axis_max_shortfall, strict=True) if steps]
            self.get_logger().warning(f"gave way ({self.controller.config.allocation} allocation): "
                                      + (", ".join(gave_way) or "no axis"))
        else:
            self.get_logger().info("rotor saturation: none")
        summary = self.controller.compensation_summary()
        if summary["mode"] == "estimate":
            self.get_logger().info(
                f"compensation: estimate (own observer), {summary['compensated_steps']} steps compensated, "
                f"{summary['contact_steps']} off in contact, {summary['late_estimates']} late estimates, "
                f"{summary['gaps']} gaps"
            )
        else:
            self.get_logger().info("compensation: none")
        if self.callbacks:
            self.get_logger().info(
                f"{self.callbacks} odom answered, {1e6 * self.callback_seconds / self.callbacks:.0f} us per callback"
            )


def main(argv: list[str] | None = None) -> int:
    return run_node(lambda _args: ControllerNode(), argv, usage=USAGE)


if __name__ == "__main__":
    sys.exit(main())
