"""Every node waits for the recorder's reader on each recorded topic it publishes before the flight starts
(fsr_sim.ros.recorder_match): a reader that matches late must not miss a whole topic."""

from __future__ import annotations

import numpy as np
import pytest
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState

from fsr_bringup.runner.processes import executable
from fsr_sim.contract import ODOM, ROTOR_CMD, WRENCH_CMD, WRENCH_SHORTFALL, WRENCH_TRUTH
from fsr_sim.model.vehicle import load_vehicle
from fsr_sim.ros.conversions import rotor_command
from harness.graph import stamp_ns

pytestmark = pytest.mark.graph


def start_simulator(ros_graph, path, *params):
    argv = [executable("simulator"), "--ros-args", "-p", f"scenario:={path}"]
    for param in params:
        argv += ["-p", param]
    return ros_graph.start("simulator", argv)


def hover_speeds(vehicle_name):
    """Equal rotor speeds whose thrust is the weight [rad/s]."""
    v = load_vehicle(vehicle_name)
    return np.full(v.rotor_count, np.sqrt(v.weight / (v.rotor_count * v.c_f)))


def test_the_simulator_does_not_start_before_a_recorded_topic_has_a_reader(ros_graph, scenario_file):
    """No reader on wrench_truth: the handshake never completes and names the topic."""
    path = scenario_file(duration=0.1)
    sim = start_simulator(ros_graph, path, f"recorded_topics:={WRENCH_TRUTH.name},{ODOM.name}", "startup_timeout:=1.0")
    ros_graph.subscribe(ODOM.name, Odometry)
    ros_graph.publisher(ROTOR_CMD.name, JointState)
    assert ros_graph.wait_exit(sim, timeout=20.0) == 1
    assert f"no recorder reader on {WRENCH_TRUTH.name}" in ros_graph.log(sim)


def test_with_the_reader_the_flight_runs_and_the_reader_has_every_step(ros_graph, scenario_file):
    path = scenario_file(duration=0.1)
    sim = start_simulator(ros_graph, path, f"recorded_topics:={WRENCH_TRUTH.name}", "startup_timeout:=10.0")
    truth = ros_graph.subscribe(WRENCH_TRUTH.name, WrenchStamped)
    command = ros_graph.publisher(ROTOR_CMD.name, JointState)
    speeds = hover_speeds("quadrotor_ex4")
    flight = ros_graph.run_controller(sim, lambda odom: rotor_command(stamp_ns(odom), speeds), command)
    assert flight.exit_code == 0 and flight.final_status.state == "finished"
    assert ros_graph.spin_until(lambda: len(truth) == 101, timeout=10.0), len(truth)


def test_the_controller_subscribes_to_odom_only_once_its_recorded_topics_have_a_reader(ros_graph, scenario_file):
    path = scenario_file(duration=0.1)
    controller = ros_graph.start("controller", [executable("controller"), "--ros-args", "-p", f"scenario:={path}",
                                                "-p", f"recorded_topics:={WRENCH_SHORTFALL.name}"])
    waiting = f"waiting for a recorder reader on {WRENCH_SHORTFALL.name}"
    assert ros_graph.spin_until(lambda: waiting in ros_graph.log(controller), timeout=20.0), ros_graph.log(controller)
    assert ros_graph.wait_for_publishers(WRENCH_CMD.name, timeout=20.0)
    assert ros_graph.node.count_subscribers(ODOM.name) == 0
    ros_graph.subscribe(WRENCH_SHORTFALL.name, WrenchStamped)
    assert ros_graph.spin_until(lambda: ros_graph.node.count_subscribers(ODOM.name) >= 1, timeout=20.0)
