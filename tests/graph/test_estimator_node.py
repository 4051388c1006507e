"""Graph tests of the estimator node: a real process in its own ROS domain, driven by a test node."""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from fsr_estimation.estimator.observer import MomentumObserver

ESTIMATOR = str(Path(sys.executable).parent / "estimator")
EXAMPLE_MCAP = Path(__file__).resolve().parents[2] / "examples" / "ex3_flight_log.mcap"
SAMPLES = 300
PERIOD_NS = 1_000_000
MODEL_ARGS = ["-p", "mass:=1.5", "-p", "inertia:=[1.2416, 1.2416, 2.4832]", "-p", "c0:=10.0", "-p", "r:=2",
              "-p", "control_period:=0.001"]


def messages_for(log, k, stamp_ns):
    """(odom, wrench_cmd) of sample k of a flight log, stamped ``stamp_ns``."""
    from fsr_sim.model.so3 import euler_rate_matrix, rotation_from_euler_zyx
    from fsr_sim.ros.conversions import odometry_from_state, wrench_stamped

    rotation = rotation_from_euler_zyx(log.eta[k])
    omega = euler_rate_matrix(log.eta[k]) @ log.eta_dot[k]
    odom = odometry_from_state(stamp_ns, np.zeros(3), rotation, log.velocity_world[k], omega)
    return odom, wrench_stamped(stamp_ns, log.force_body[k], log.torque_body[k])


def offline_inputs(odom, wrench):
    """The observer inputs exactly as the node derives them from the two messages."""
    from fsr_sim.model.so3 import euler_rates, euler_zyx_from_rotation
    from fsr_sim.ros.conversions import state_from_odometry, wrench_from_msg

    _, rotation, velocity, omega = state_from_odometry(odom)
    eta = euler_zyx_from_rotation(rotation)
    return (velocity, eta, euler_rates(eta, omega), *wrench_from_msg(wrench))


def stamp_of(msg):
    return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec


@pytest.mark.graph
def test_published_estimates_equal_the_offline_observer(ros_graph):
    from geometry_msgs.msg import WrenchStamped
    from nav_msgs.msg import Odometry
    from std_msgs.msg import Float64
    from std_srvs.srv import Trigger

    from fsr_estimation.io.flight_log import load_mcap

    log = load_mcap(EXAMPLE_MCAP)
    estimator = ros_graph.start("estimator", [ESTIMATOR, "--ros-args", *MODEL_ARGS])
    odom_pub = ros_graph.publisher("odom", Odometry)
    wrench_pub = ros_graph.publisher("wrench_cmd", WrenchStamped)
    estimates = ros_graph.subscribe("wrench_estimate", WrenchStamped)
    masses = ros_graph.subscribe("mass_estimate", Float64)
    assert ros_graph.wait_for_subscribers(odom_pub, timeout=15.0), ros_graph.log(estimator)
    assert ros_graph.wait_for_subscribers(wrench_pub, timeout=5.0)
    # Handshake: warm-up pairs until one estimate comes back (both directions matched), then ~/reset.
    warm_stamp = 100 * 10**9
    deadline = time.monotonic() + 30.0
    while not ros_graph.spin_until(lambda: len(estimates) > 0, 0.2):
        assert time.monotonic() < deadline, f"no estimate after 30 s of warm-up pairs: {ros_graph.log(estimator)}"
        warm_stamp += PERIOD_NS
        for msg in messages_for(log, 0, warm_stamp):
            (odom_pub if isinstance(msg, Odometry) else wrench_pub).publish(msg)
        assert estimator.poll() is None, ros_graph.log(estimator)
    reset = ros_graph.node.create_client(Trigger, "estimator/reset")
    assert reset.wait_for_service(timeout_sec=5.0)
    future = reset.call_async(Trigger.Request())
    assert ros_graph.spin_until(future.done, 5.0) and future.result().success
    estimates.messages.clear()
    masses.messages.clear()

    offline = MomentumObserver(1.5, np.diag([1.2416, 1.2416, 2.4832]), 10.0, 2, 0.001)
    expected = {}
    for k in range(SAMPLES):
        odom, wrench = messages_for(log, k, k * PERIOD_NS)
        # alternate the arrival order: pairing is by stamp, not by order
        for msg in (odom, wrench) if k % 2 else (wrench, odom):
            (odom_pub if msg is odom else wrench_pub).publish(msg)
        offline.update(*offline_inputs(odom, wrench))
        expected[k * PERIOD_NS] = (np.concatenate(offline.wrench_body()), offline.mass_estimate)
    # a NaN odom: dropped (its pair never completes), the following samples come after a gap
    bad_odom, bad_wrench = messages_for(log, SAMPLES, SAMPLES * PERIOD_NS)
    bad_odom.twist.twist.linear.x = math.nan
    odom_pub.publish(bad_odom)
    wrench_pub.publish(bad_wrench)
    for k in range(SAMPLES + 1, SAMPLES + 6):
        odom, wrench = messages_for(log, k, k * PERIOD_NS)
        odom_pub.publish(odom)
        wrench_pub.publish(wrench)
    assert ros_graph.spin_until(lambda: len(estimates) >= SAMPLES + 5 and len(masses) >= SAMPLES + 5, 10.0), (
        len(estimates), ros_graph.log(estimator))

    received = {stamp_of(m): m for m in estimates.messages}
    assert SAMPLES * PERIOD_NS not in received  # the NaN sample never reached the filter
    worst = 0.0
    for stamp, (wrench_body, _) in expected.items():
        w = received[stamp].wrench
        got = np.array((w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z))
        worst = max(worst, float(np.abs(got - wrench_body).max()))
    assert worst < 1e-9
    assert np.abs(expected[(SAMPLES - 1) * PERIOD_NS][0]).max() > 0.1  # a non-trivial estimate was compared
    np.testing.assert_allclose([m.data for m in masses.messages[:SAMPLES]], [v[1] for v in expected.values()],
                               rtol=0, atol=1e-9)
    after_gap = [received[k * PERIOD_NS] for k in range(SAMPLES + 1, SAMPLES + 6)]
    assert after_gap[0].wrench.force.x == 0.0  # reset on the gap: a new estimate starts from zero
    assert all(math.isfinite(m.wrench.force.x) for m in after_gap)
    text = ros_graph.log(estimator)
    assert "NaN" in text and "observer reset" in text


@pytest.mark.graph
def test_negative_c0_exits_2_naming_it(ros_graph):
    process = ros_graph.start("estimator_bad", [ESTIMATOR, "--ros-args", "-p", "c0:=-1", "-p", "mass:=1.5",
                                                "-p", "inertia:=[1.0, 1.0, 2.0]"])
    assert ros_graph.wait_exit(process, timeout=15.0) == 2
    assert "c0: must be > 0" in ros_graph.log(process)
