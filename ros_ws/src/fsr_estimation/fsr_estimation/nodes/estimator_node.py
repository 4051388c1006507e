"""Estimator node: momentum-based external wrench and mass estimation on the live graph (SPEC §3.8, §4).

Subscribes ``odom`` (nav_msgs/Odometry) and ``wrench_cmd`` (geometry_msgs/WrenchStamped), pairs them by
header stamp, runs :class:`fsr_estimation.core.observer.MomentumObserver` once per pair and publishes
``wrench_estimate`` (WrenchStamped, body FRD: force ``R_b^T f_e``, torque ``Q^-T tau_e``, stamped with the
pair's stamp) and ``mass_estimate`` (Float64, kg). Time is the stamps' simulated time; the sample time is
the stamp difference, which must equal the control period (a gap or a jump back resets the observer).
Messages with NaN/inf are dropped with a rate-limited warning. Service ``~/reset`` (std_srvs/Trigger).
Parameters: :mod:`fsr_estimation.nodes.estimator_params`, and ``exit_on_finish`` (default true: end by
itself once ``sim_status`` reports the end of the flight, :mod:`fsr_sim.ros.flight_end`).
"""

from __future__ import annotations

import sys

import numpy as np
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from std_msgs.msg import Float64
from std_srvs.srv import Trigger

from fsr_estimation.core.observer import MomentumObserver
from fsr_estimation.nodes.estimator_params import PARAMETER_NAMES, node_settings
from fsr_sim.model.so3 import euler_rate_matrix, euler_zyx_from_rotation
from fsr_sim.ros.conversions import (
    ns_from_time,
    odometry_is_finite,
    state_from_odometry,
    wrench_from_msg,
    wrench_is_finite,
    wrench_stamped,
)
from fsr_sim.ros.flight_end import FlightEndWatch
from fsr_sim.ros.qos import STREAM_QOS
from fsr_sim.ros.runtime import RateLimitedWarning, exit_on_finish_parameter, run_node

MAX_PENDING = 1000  # unpaired stamps kept per topic (about 1 s at 1 kHz)
PERIOD_TOLERANCE = 0.01  # relative deviation of a stamp difference from the control period that is accepted


class EstimatorNode(Node):
    """Thin adapter: messages -> numpy -> MomentumObserver.update -> messages."""

    def __init__(self) -> None:
        super().__init__("estimator")
        dynamic = ParameterDescriptor(dynamic_typing=True)
        values = {name: self.declare_parameter(name, None, dynamic).value for name in PARAMETER_NAMES}
        settings = node_settings(values)
        exit_on_finish = exit_on_finish_parameter(self, "estimator")
        self.config = settings.config
        self.control_period = settings.control_period
        self.enabled = self.config.enabled
        self.observer: MomentumObserver | None = None
        if self.control_period is not None:
            self.observer = self._make_observer(self.control_period)
        self._odom: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._wrench: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._last_stamp: int | None = None
        self._first_sample: tuple | None = None  # held until the period is known (no scenario, no parameter)
        self.warn_input = RateLimitedWarning(self.get_logger())
        self.warn_timing = RateLimitedWarning(self.get_logger())
        self.estimates_published = 0
        self.wrench_pub = self.create_publisher(WrenchStamped, "wrench_estimate", STREAM_QOS)
        self.mass_pub = self.create_publisher(Float64, "mass_estimate", STREAM_QOS)
        self.create_subscription(Odometry, "odom", self._on_odom, STREAM_QOS)
        self.create_subscription(WrenchStamped, "wrench_cmd", self._on_wrench, STREAM_QOS)
        self.create_service(Trigger, "~/reset", self._on_reset)
        self.flight_end = FlightEndWatch(self) if exit_on_finish else None
        c = self.config
        self.get_logger().info(
            f"estimator: c0 = {c.c0} rad/s, r = {c.r}, mass = {c.mass} kg, inertia diag = "
            f"{np.diag(c.inertia).tolist()} kg m^2, control period = "
            f"{'from stamps' if self.control_period is None else f'{self.control_period} s'}"
            + ("" if self.enabled else " (disabled by the scenario)"))

    def done(self) -> bool:
        return not self.enabled or (self.flight_end is not None and self.flight_end.ended())

    def _make_observer(self, period: float) -> MomentumObserver:
        c = self.config
        return MomentumObserver(c.mass, c.inertia, c.c0, c.r, period)

    def _on_odom(self, msg: Odometry) -> None:
        stamp = ns_from_time(msg.header.stamp)
        if not odometry_is_finite(msg):
            self.warn_input(f"odom at {stamp} ns holds NaN/inf or a zero quaternion: dropped")
            return
        _, rotation, velocity_world, omega_body = state_from_odometry(msg)
        eta = euler_zyx_from_rotation(rotation)
        eta_dot = np.linalg.solve(euler_rate_matrix(eta), omega_body)
        self._store(self._odom, stamp, (velocity_world, eta, eta_dot))

    def _on_wrench(self, msg: WrenchStamped) -> None:
        stamp = ns_from_time(msg.header.stamp)
        if not wrench_is_finite(msg):
            self.warn_input(f"wrench_cmd at {stamp} ns holds NaN/inf: dropped")
            return
        self._store(self._wrench, stamp, wrench_from_msg(msg))

    def _store(self, pending: dict, stamp: int, value: tuple) -> None:
        if self.flight_end is not None:
            self.flight_end.activity()
        if self._last_stamp is not None and stamp <= self._last_stamp:
            self.warn_timing(f"sample at {stamp} ns is not newer than the last one processed: dropped")
            return
        pending[stamp] = value
        if stamp in self._odom and stamp in self._wrench:
            self._process(stamp, *self._odom.pop(stamp), *self._wrench.pop(stamp))
        for table in (self._odom, self._wrench):
            while len(table) > MAX_PENDING:
                del table[next(iter(table))]  # oldest first (insertion order)

    def _process(self, stamp: int, velocity_world: np.ndarray, eta: np.ndarray, eta_dot: np.ndarray,
                 force_body: np.ndarray, torque_body: np.ndarray) -> None:
        sample = (velocity_world, eta, eta_dot, force_body, torque_body)
        previous, self._last_stamp = self._last_stamp, stamp
        for table in (self._odom, self._wrench):  # anything older can never be paired in order any more
            for old in [s for s in table if s < stamp]:
                del table[old]
        if previous is not None and not self._period_ok(stamp - previous) and self.observer is not None:
            self.observer.reset()  # this sample becomes k = 0 of a new estimate
        if self.observer is None:
            if self._first_sample is None or previous is None:
                self._first_sample = sample
                return
            self.control_period = (stamp - previous) * 1e-9
            try:
                self.observer = self._make_observer(self.control_period)
            except ValueError as error:
                self.get_logger().error(f"cannot run the observer: {error}")
                self.enabled = False
                return
            self.observer.update(*self._first_sample)
            self._first_sample = None
        self.observer.update(*sample)
        force, torque = self.observer.wrench_body()
        self.wrench_pub.publish(wrench_stamped(stamp, force, torque))
        self.mass_pub.publish(Float64(data=self.observer.mass_estimate))
        self.estimates_published += 1

    def _period_ok(self, step_ns: int) -> bool:
        """True if the stamp difference is one control period; else warn (the caller resets)."""
        if self.control_period is None:
            return True
        expected_ns = self.control_period * 1e9
        if abs(step_ns - expected_ns) <= PERIOD_TOLERANCE * expected_ns:
            return True
        self.warn_timing(f"stamp step {step_ns * 1e-9:.6f} s differs from the control period "
                         f"{self.control_period:.6f} s (gap or dropped sample): observer reset")
        return False

    def _on_reset(self, _request: Trigger.Request, response: Trigger.Response) -> Trigger.Response:
        if self.observer is not None:
            self.observer.reset()
        self._odom.clear()
        self._wrench.clear()
        self._first_sample = None
        self._last_stamp = None
        response.success = True
        response.message = "estimator reset: the next paired sample starts a new estimate from zero"
        return response


def main(argv: list[str] | None = None) -> int:
    return run_node(lambda _args: EstimatorNode(), sys.argv if argv is None else argv)


if __name__ == "__main__":
    raise SystemExit(main())
