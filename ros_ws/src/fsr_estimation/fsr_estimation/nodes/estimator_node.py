"""Estimator node: momentum-based external wrench and mass estimation on the live graph (docs/model.md §3.8, §4).

Subscribes ``odom`` (nav_msgs/Odometry) and ``wrench_cmd`` (geometry_msgs/WrenchStamped) -- with
``estimator.input: measured`` where the simulator publishes it, ``rotor_state`` (sensor_msgs/JointState: the
rotors' speeds and tilts, through the nominal allocation, :func:`fsr_sim.core.rotors.measured_rotor_wrench`)
instead -- and hands them to
:class:`fsr_estimation.estimator.stamped.StampedEstimator` (pairing by header stamp, sample-period checks and
resets on gaps live there), then publishes each estimate as ``wrench_estimate`` (WrenchStamped, body FRD:
force ``R_b^T f_e``, torque ``Q^-T tau_e``, stamped with the pair's stamp) and ``mass_estimate`` (Float64,
kg).
Messages with NaN/inf are dropped with a rate-limited warning. Service ``~/reset`` (std_srvs/Trigger).
Asked to stop after the simulator ended (its final ``sim_status``), it first estimates every pair still
queued up to the simulator's last state and waits for its subscribers' acknowledgements; with
``exit_on_finish`` (default true) it ends by itself once ``sim_status`` reports the end of the flight
(:mod:`fsr_sim.ros.flight_end`).
Parameters: :mod:`fsr_estimation.nodes.estimator_params` and ``exit_on_finish`` (read once: no parameter
services).
``odom`` and ``wrench_cmd`` are read from their CDR bytes (:mod:`fsr_sim.ros.cdr_read`), taken from a wait set
(``hot_subscriptions``, :class:`fsr_sim.ros.wait_set.WaitSetSpinner`); the estimates are published as packed CDR
(:class:`fsr_estimation.nodes.packets.EstimatePackets`).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from std_srvs.srv import Trigger

from fsr_estimation.estimator.stamped import Estimate, StampedEstimator
from fsr_estimation.nodes.estimator_params import PARAMETER_NAMES, USAGE, node_settings
from fsr_estimation.nodes.packets import EstimatePackets
from fsr_sim.contract import MASS_ESTIMATE, ODOM, ROTOR_STATE, WRENCH_CMD, WRENCH_ESTIMATE
from fsr_sim.core.rotors import measured_rotor_wrench
from fsr_sim.nodes.commands import RotorCommandReader
from fsr_sim.ros import cdr_read
from fsr_sim.ros.conversions import state_from_odometry_bytes
from fsr_sim.ros.endpoints import publisher, subscription
from fsr_sim.ros.flight_end import FlightEnd
from fsr_sim.ros.qos import STREAM_DEPTH
from fsr_sim.ros.recorder_match import recorded_topics_parameter, wait_until_recorded
from fsr_sim.ros.runtime import RateLimitedWarning, exit_on_finish_parameter, run_node

GATHER_S = 0.005  # s between batches of inputs (the streams are 5000 deep)


class EstimatorNode(Node):
    """Thin adapter: messages -> numpy -> StampedEstimator -> messages."""

    def __init__(self) -> None:
        super().__init__("estimator", start_parameter_services=False)
        dynamic = ParameterDescriptor(dynamic_typing=True)
        values = {name: self.declare_parameter(name, None, dynamic).value for name in PARAMETER_NAMES}
        settings = node_settings(values)
        exit_on_finish = exit_on_finish_parameter(self, "estimator")
        recorded = recorded_topics_parameter(self)
        self.config = settings.config
        self.enabled = self.config.enabled
        self.warn_input = RateLimitedWarning(self.get_logger())
        self.warn_timing = RateLimitedWarning(self.get_logger())
        c = self.config
        # Pairing keeps a whole stream queue: a backlog of one stream (after a pause) never loses samples.
        self.estimator = StampedEstimator(c.mass, c.inertia, c.c0, c.r, settings.control_period, self.warn_timing,
                                          max_pending=STREAM_DEPTH)
        if self.enabled:
            self.estimator.warm_up()  # before subscribing: the simulator steps only once we are subscribed
        self.estimates_published = 0
        self.packets = EstimatePackets()  # the bytes an in-process recording writes
        self.wrench_pub = publisher(self, WRENCH_ESTIMATE)
        self.mass_pub = publisher(self, MASS_ESTIMATE)
        recorded_publishers = {WRENCH_ESTIMATE.name: self.wrench_pub, MASS_ESTIMATE.name: self.mass_pub}
        wait_until_recorded(self, recorded_publishers, recorded)  # before odom: no state comes before
        odom = subscription(self, ODOM, self._on_odom, raw=True)
        self.rotor_allocation = settings.rotor_allocation
        if self.rotor_allocation is None:  # the commanded wrench (estimator.input: commanded)
            actuator = subscription(self, WRENCH_CMD, self._on_wrench, raw=True)
            self.hot_subscriptions = [(odom, self._on_odom), (actuator, self._on_wrench)]
        else:  # the rotors' measured speeds and tilts
            allocation, _, tilting = self.rotor_allocation
            self.rotor_reader = RotorCommandReader(allocation.shape[1] // (2 if tilting else 1), tilting)
            self.rotor_state_seen = False
            actuator = subscription(self, ROTOR_STATE, self._on_rotor_state, raw=True)
            self.hot_subscriptions = [(odom, self._on_odom), (actuator, self._on_rotor_state)]
        self.hot_gather_s = GATHER_S  # nobody waits for the estimates step by step: take them in batches
        self.create_service(Trigger, "~/reset", self._on_reset)
        period = settings.control_period
        self.flight_end = FlightEnd(self, exit_on_finish)
        self.stop_flag: object = None  # run_node's StopFlag: bounds the drain after a signal
        self.get_logger().info(
            f"estimator: c0 = {c.c0} rad/s, r = {c.r}, mass = {c.mass} kg, inertia diag = "
            f"{np.diag(c.inertia).tolist()} kg m^2, control period = "
            f"{'from stamps' if period is None else f'{period} s'}"
            + ("" if self.enabled else " (disabled by the scenario)"))

    def done(self) -> bool:
        return not self.enabled or self.flight_end.ended()

    def close(self) -> None:
        """Estimate every pair up to the simulator's last state before exiting (see the module docstring)."""
        if self.enabled:
            self.flight_end.drain(lambda: self.estimator.last_stamp, [self.wrench_pub, self.mass_pub])

    def _on_odom(self, data: bytes) -> None:
        try:
            stamp, _, rotation, velocity_world, omega_body = state_from_odometry_bytes(data)
        except ValueError as error:
            self.warn_input(f"dropped an odom: {error}")
            return
        self._publish(lambda: self.estimator.add_state(stamp, rotation, velocity_world, omega_body))

    def _on_wrench(self, data: bytes) -> None:
        try:
            stamp, values = cdr_read.wrench_stamped(data)
        except ValueError as error:
            self.warn_input(f"dropped a wrench_cmd that cannot be read: {error}")
            return
        if not all(map(math.isfinite, values)):
            self.warn_input(f"wrench_cmd at {stamp} ns holds NaN/inf: dropped")
            return
        self._publish(lambda: self.estimator.add_command(stamp, np.array(values[:3]), np.array(values[3:])))

    def _on_rotor_state(self, data: bytes) -> None:
        """``rotor_state`` (``estimator.input: measured``): the wrench of the rotors' speeds and tilts through the
        nominal allocation, paired with the state of the same stamp as ``wrench_cmd`` would be."""
        try:
            stamp, speeds, tilts = self.rotor_reader.read_stamped(data)
        except ValueError as error:
            self.warn_input(f"dropped a rotor_state that cannot be read: {error}")
            return
        allocation, c_f, tilting = self.rotor_allocation
        force, torque = measured_rotor_wrench(allocation, c_f, tilting, speeds,
                                              speeds if tilts is None else tilts)
        if not self.rotor_state_seen:  # t_0's: published once the first command came; the state of t_0 was
            self.rotor_state_seen = True  # measured before it, with the rotors at rest (the in-process loop's)
            force, torque = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        self._publish(lambda: self.estimator.add_command(stamp, np.array(force), np.array(torque)))

    def _publish(self, add: Callable[[], Estimate | None]) -> None:
        self.flight_end.activity()
        try:
            estimate = add()
        except ValueError as error:  # a control period from the stamps the filter cannot run at
            self.get_logger().error(f"cannot run the observer: {error}")
            self.enabled = False
            return
        if estimate is None:
            return
        for topic_publisher, packet in zip((self.wrench_pub, self.mass_pub), self.packets.pack(estimate), strict=True):
            topic_publisher.publish(packet)
        self.estimates_published += 1

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        self.estimator.reset()
        response.success = True
        response.message = "estimator reset: the next paired sample starts a new estimate from zero"
        return response


def main(argv: list[str] | None = None) -> int:
    return run_node(lambda _args: EstimatorNode(), sys.argv if argv is None else argv, usage=USAGE)


if __name__ == "__main__":
    raise SystemExit(main())
