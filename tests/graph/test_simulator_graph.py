"""The simulator node as a separate process, driven by the test node acting as the lockstep controller."""

from __future__ import annotations

import math
import re
import signal
import time

import numpy as np
import pytest
from geometry_msgs.msg import QuaternionStamped, Transform, Vector3, WrenchStamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import MultiDOFJointTrajectory, MultiDOFJointTrajectoryPoint

from fsr_bringup.runner.processes import executable
from fsr_sim.contract import ATTITUDE_CMD, REFERENCE
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.vehicle import load_vehicle
from fsr_sim.ros.conversions import rotor_command, time_from_ns, wrench_stamped
from fsr_sim.ros.qos import CLOCK_QOS
from harness.graph import stamp_ns

pytestmark = pytest.mark.graph

Z0 = -10.0  # BASE_SCENARIO's initial height (NED)


def start_simulator(ros_graph, path, *params, namespace=None):
    argv = [executable("simulator"), "--ros-args", "-p", f"scenario:={path}"]
    for param in params:
        argv += ["-p", param]
    if namespace is not None:
        argv += ["-r", f"__ns:={namespace}"]
    return ros_graph.start("simulator", argv)


def hover_speeds(vehicle_name):
    """Equal rotor speeds whose thrust is the weight: ``n c_f w^2 = m g`` [rad/s]."""
    v = load_vehicle(vehicle_name)
    return np.full(v.rotor_count, math.sqrt(v.weight / (v.rotor_count * v.c_f))), v


def times_and_positions(flight):
    odoms = flight.odoms
    t = np.array([stamp_ns(m) * 1e-9 for m in odoms])
    p = np.array([[m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z] for m in odoms])
    return t, p


def assert_finished(flight, steps, failsafe_steps=0):
    assert flight.exit_code == 0, flight.log
    status = flight.final_status.as_dict()
    assert status == {
        "state": "finished", "reason": status["reason"], "sim_time": pytest.approx(steps * 1e-3), "steps": steps,
        "failsafe_steps": failsafe_steps, "incidents": 1 if failsafe_steps else 0,
        "late_commands": status["late_commands"], "longest_wait_s": status["longest_wait_s"],
    }
    assert 0.0 <= status["longest_wait_s"] < 60.0
    # t_0 .. t_N, each exactly once (the handshake never repeats a state), none missing
    assert flight.odom_stamps_ns() == [k * 1_000_000 for k in range(steps + 1)]


def rotor_answer(speeds, tilts=None, until=math.inf):
    """Answer every odom stamped before ``until`` [s] with constant rotor speeds."""

    def answer(odom):
        stamp = stamp_ns(odom)
        return rotor_command(stamp, speeds, tilts) if stamp * 1e-9 < until else None

    return answer


def test_free_fall_follows_half_g_t_squared(ros_graph, scenario_file):
    path = scenario_file(duration=0.4)
    commands = ros_graph.publisher("rotor_cmd", JointState)
    clock = ros_graph.subscribe("/clock", Clock, CLOCK_QOS)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(np.zeros(4)), commands)
    assert_finished(flight, 400)
    t, p = times_and_positions(flight)
    np.testing.assert_allclose(p[:, 2], Z0 + 0.5 * GRAVITY * t**2, rtol=0, atol=1e-9)
    np.testing.assert_allclose(p[:, :2], 0.0, atol=1e-12)
    assert "graph ready" in flight.log
    clock_ns = {m.clock.sec * 1_000_000_000 + m.clock.nanosec for m in clock.messages}
    assert clock_ns <= {stamp_ns(m) for m in flight.odoms} and len(clock_ns) > 300  # reader depth 10: may drop a few


def test_namespace_moves_every_topic_but_clock(ros_graph, scenario_file):
    path = scenario_file(duration=0.1)
    commands = ros_graph.publisher("/uav1/rotor_cmd", JointState)
    clock = ros_graph.subscribe("/clock", Clock, CLOCK_QOS)
    sim = start_simulator(ros_graph, path, "publish_clock:=false", namespace="/uav1")
    flight = ros_graph.run_controller(
        sim, rotor_answer(np.zeros(4)), commands, odom_topic="/uav1/odom", status_topic="/uav1/sim_status"
    )
    assert_finished(flight, 100)
    assert not clock.messages


@pytest.mark.parametrize("vehicle", ["quadrotor_ex4", "octocopter", "tilting_quadrotor_ex5"])
def test_rotor_hover_stays_put(ros_graph, scenario_file, vehicle):
    speeds, v = hover_speeds(vehicle)
    tilts = np.zeros(v.rotor_count) if v.has_servos else None
    path = scenario_file(vehicle=vehicle, duration=0.3, initial_state={"attitude_rpy_deg": [0, 0, 30]})
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(speeds, tilts), commands)
    assert_finished(flight, 300)
    _, p = times_and_positions(flight)
    np.testing.assert_allclose(p, np.tile([0.0, 0.0, Z0], (len(p), 1)), rtol=0, atol=1e-9)
    last = flight.odoms[-1]
    assert last.pose.pose.orientation.z == pytest.approx(math.sin(math.radians(15.0)), abs=1e-9)
    twist = last.twist.twist
    assert max(abs(twist.angular.x), abs(twist.angular.y), abs(twist.angular.z)) < 1e-9


def test_wrench_actuation_hover(ros_graph, scenario_file):
    path = scenario_file(actuation="wrench", duration=0.3)
    weight = load_vehicle("quadrotor_ex4").weight
    commands = ros_graph.publisher("wrench_cmd", WrenchStamped)
    sim = start_simulator(ros_graph, path)

    def answer(odom):
        return wrench_stamped(stamp_ns(odom), np.array((0.0, 0.0, -weight)), np.zeros(3))

    flight = ros_graph.run_controller(sim, answer, commands)
    assert_finished(flight, 300)
    _, p = times_and_positions(flight)
    np.testing.assert_allclose(p[:, 2], Z0, rtol=0, atol=1e-9)


def test_nan_and_inf_commands_are_dropped(ros_graph, scenario_file):
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.2)
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)

    def answer(odom):
        stamp = stamp_ns(odom)
        good = rotor_command(stamp, speeds)
        if 50e6 <= stamp < 60e6:  # a bad command first, then the good one, for the same state
            bad = np.array(speeds)
            bad[stamp % 4] = math.nan if stamp % 2 else math.inf
            return [rotor_command(stamp, bad), good]
        return good

    flight = ros_graph.run_controller(sim, answer, commands)
    assert_finished(flight, 200)
    assert "dropped a command" in flight.log and "NaN or inf" in flight.log
    _, p = times_and_positions(flight)
    assert np.isfinite(p).all()
    np.testing.assert_allclose(p[:, 2], Z0, rtol=0, atol=1e-9)


@pytest.mark.parametrize("failsafe", ["hold", "cut"])
def test_timeout_applies_failsafe_and_goes_on(ros_graph, scenario_file, failsafe):
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.4, lockstep={"timeout": 0.4, "failsafe": failsafe})
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(speeds, until=0.1), commands)  # silent from t = 0.1 s
    assert_finished(flight, 400, failsafe_steps=300)  # steps 100..399 on the failsafe, one incident
    assert flight.final_status.longest_wait_s >= 0.4  # the first missed step waited the whole timeout
    assert "did not answer step 100 (t = 0.1000 s)" in flight.log
    assert f"failsafe '{failsafe}'" in flight.log and "/graph_test" in flight.log
    t, p = times_and_positions(flight)
    if failsafe == "hold":
        np.testing.assert_allclose(p[:, 2], Z0, rtol=0, atol=1e-9)
    else:  # thrust cut at t = 0.1 s: free fall from rest from there on
        expected = Z0 + 0.5 * GRAVITY * np.maximum(t - 0.1, 0.0) ** 2
        np.testing.assert_allclose(p[:, 2], expected, rtol=0, atol=1e-9)


def test_a_late_reference_pauses_the_lockstep_like_a_late_command(ros_graph, scenario_file):
    """The simulator checks each state against the controller's reference and attitude_cmd of its stamp, sent after
    the command: when they come late (a link lost just after the command went out), the flight pauses for them and
    the pause is the lockstep's longest wait, as for a late command."""
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.2, lockstep={"timeout": 2.0})
    commands = ros_graph.publisher("rotor_cmd", JointState)
    references = ros_graph.publisher(REFERENCE.name, MultiDOFJointTrajectory)
    attitudes = ros_graph.publisher(ATTITUDE_CMD.name, QuaternionStamped)
    sim = start_simulator(ros_graph, path)
    late_stamp, delay = 100_000_000, 0.3  # ns, s: the state whose reference and attitude_cmd come late
    sent_late: list[float] = []

    def send_answer(stamp: int) -> None:
        reference = MultiDOFJointTrajectory()
        reference.header.stamp = time_from_ns(stamp)
        point = MultiDOFJointTrajectoryPoint()
        point.transforms = [Transform(translation=Vector3(x=0.0, y=0.0, z=Z0))]
        reference.points = [point]
        attitude = QuaternionStamped()
        attitude.header.stamp = time_from_ns(stamp)
        attitude.quaternion.w = 1.0
        references.publish(reference)
        attitudes.publish(attitude)

    def send_late() -> None:
        timer.cancel()
        sent_late.append(time.monotonic())
        send_answer(late_stamp)

    timer = ros_graph.node.create_timer(delay, send_late)
    timer.cancel()  # started by the late state's command

    def answer(odom):
        stamp = stamp_ns(odom)
        if stamp == late_stamp:
            timer.reset()  # the command now, the rest once the timer fires (the test node keeps spinning)
        else:
            send_answer(stamp)
        return rotor_command(stamp, speeds)

    flight = ros_graph.run_controller(sim, answer, commands)
    assert_finished(flight, 200)
    assert sent_late, "the late reference was never sent"
    assert delay <= flight.final_status.longest_wait_s < 2.0
    # logged with the part of the pause spent on the reference and attitude_cmd (the command came at once)
    paused = re.search(r"lockstep paused (\S+) s at step 100 .*; reference, attitude_cmd: \S+ s more", flight.log)
    assert paused and float(paused.group(1)) >= delay, flight.log
    np.testing.assert_allclose(times_and_positions(flight)[1][:, 2], Z0, rtol=0, atol=1e-9)


def test_controller_gone_simulator_finishes_alone(ros_graph, scenario_file):
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.4, lockstep={"timeout": 10.0, "failsafe": "cut"})
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    gone = []

    def answer(odom):
        stamp = stamp_ns(odom)
        if gone:
            return None
        if stamp * 1e-9 >= 0.1:
            ros_graph.node.destroy_publisher(commands)
            gone.append(time.monotonic())
            return None
        return rotor_command(stamp, speeds)

    flight = ros_graph.run_controller(sim, answer, commands)
    assert time.monotonic() - gone[0] < 5.0  # finished without waiting for the 10 s timeout
    assert_finished(flight, 400, failsafe_steps=300)
    assert "no publisher any more" in flight.log
    t, p = times_and_positions(flight)
    np.testing.assert_allclose(p[:, 2], Z0 + 0.5 * GRAVITY * np.maximum(t - 0.1, 0.0) ** 2, rtol=0, atol=1e-9)


def test_crash_into_the_ground_is_divergence_exit_3(ros_graph, scenario_file):
    path = scenario_file(
        duration=1.0, environment={"ground": {"enabled": True}},
        initial_state={"position": [0.0, 0.0, -1.0], "velocity": [0.0, 0.0, 8.0]},
    )
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(np.zeros(4)), commands)
    assert flight.exit_code == 3, flight.log
    status = flight.final_status
    assert status.state == "diverged" and "crashed into the ground" in status.reason
    assert 0.05 < status.sim_time < 0.2 and status.steps == round(status.sim_time * 1e3)
    assert "simulation diverged" in flight.log


def test_crash_into_the_ceiling_is_divergence_exit_3_after_a_cap_warning(ros_graph, scenario_file):
    # 8 m/s up towards a ceiling 1 m above; max_ratio 1.01 puts the ceiling effect at its cap ~0.3 m before
    # the top (0.1 m above the centre) hits the ceiling.
    path = scenario_file(
        duration=1.0, environment={"ceiling": {"enabled": True, "height": Z0 - 1.0, "max_ratio": 1.01}},
        initial_state={"position": [0.0, 0.0, Z0], "velocity": [0.0, 0.0, -8.0]},
    )
    speeds, _ = hover_speeds("quadrotor_ex4")
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(speeds), commands)
    assert flight.exit_code == 3, flight.log
    status = flight.final_status
    assert status.state == "diverged" and "crashed into the ceiling" in status.reason
    assert 0.05 < status.sim_time < 0.2 and status.steps == round(status.sim_time * 1e3)
    _, p = times_and_positions(flight)
    assert p[:, 2].min() >= Z0 - 1.0 + 0.1 - 1e-9  # never through the ceiling
    assert len(re.findall(r"ceiling effect at its cap \(thrust ratio 1\.01 = max_ratio\)", flight.log)) == 1
    assert re.search(r"diverged: .*; [1-9][0-9]* step\(s\) with the ceiling effect at its cap", flight.log), flight.log
    assert "ground effect at its cap" not in flight.log


@pytest.mark.parametrize(
    ("params", "scenario_overrides", "named"),
    [
        (["duration:=-1"], {}, "duration"),
        (["failsafe:=explode"], {}, "failsafe"),
        (["timeout:=0"], {}, "timeout"),
        (["wait_for_subscribers:=-2"], {}, "wait_for_subscribers"),
        (["duration:=0.0005"], {}, "duration: must be a whole number of steps"),
        ([], {"duraton": 3.0}, "duraton"),
        ([], {"lockstep": {"failsafe": "explode"}}, "lockstep.failsafe"),
    ],
)
def test_invalid_parameters_exit_2_before_any_step(ros_graph, scenario_file, params, scenario_overrides, named):
    path = scenario_file(**scenario_overrides)
    sim = start_simulator(ros_graph, path, *params)
    assert ros_graph.wait_exit(sim, 10.0) == 2
    log = ros_graph.log(sim)
    errors = [line for line in log.splitlines() if "error" in line]
    assert len(errors) == 1 and named in errors[0], log
    assert "graph ready" not in log


def test_unknown_scenario_name_exit_2(ros_graph):
    sim = ros_graph.start("simulator", [executable("simulator"), "--ros-args", "-p", "scenario:=no_such_scenario"])
    assert ros_graph.wait_exit(sim, 10.0) == 2
    assert "scenario: unknown scenario 'no_such_scenario'" in ros_graph.log(sim)


def test_sigterm_mid_flight_stops_cleanly(ros_graph, scenario_file):
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=10.0)
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    sent = []

    def answer(odom):
        stamp = stamp_ns(odom)
        if stamp >= 300_000_000 and not sent:
            sim.send_signal(signal.SIGTERM)
            sent.append(stamp)
        return rotor_command(stamp, speeds)

    flight = ros_graph.run_controller(sim, answer, commands)
    assert flight.exit_code == 0, flight.log
    status = flight.final_status
    assert status.state == "stopped" and status.reason == "received SIGTERM"
    assert 0.3 <= status.sim_time < 10.0
    assert flight.statuses[0].state == "running"


def test_startup_timeout_without_controller_exit_1(ros_graph, scenario_file):
    sim = start_simulator(ros_graph, scenario_file(), "startup_timeout:=0.5")
    assert ros_graph.wait_exit(sim, 10.0) == 1
    assert "start-up failed: only 0 of 1 odom subscriber(s) and 0 rotor_cmd publisher(s)" in ros_graph.log(sim)


def test_free_running_paces_to_real_time(ros_graph, scenario_file):
    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.5, lockstep={"enabled": False, "real_time_factor": 1.0})
    commands = ros_graph.publisher("rotor_cmd", JointState)
    sim = start_simulator(ros_graph, path)
    flight = ros_graph.run_controller(sim, rotor_answer(speeds), commands)
    assert_finished(flight, 500)
    # The simulator's own account (the test node consumes odom slower than 2 kHz, so its arrival times lag).
    speed = re.search(r"t = 0\.5000 s in ([0-9.]+) s wall, ([0-9.]+)x real time", flight.log)
    assert speed is not None, flight.log
    # Deterministic: pacing never runs ahead of wall time (a loaded machine may only make it slower).
    assert float(speed.group(2)) <= 1.02
    assert float(speed.group(1)) >= 0.5 / 1.02
    _, p = times_and_positions(flight)
    np.testing.assert_allclose(p[:, 2], Z0, rtol=0, atol=1e-9)


def test_initial_state_is_sent_once_and_reaches_a_reader_that_matches_late(ros_graph, scenario_file, tmp_path):
    """Discovery made slow on purpose: the recorder satisfies the handshake, the controller's odom reader is
    created only after the simulator sent t_0 and held it unanswered. The late reader still gets t_0 (from
    the transient-local history) and the recording holds exactly one message per step."""
    from fsr_sim.recording.reader import open_recording

    speeds, _ = hover_speeds("quadrotor_ex4")
    path = scenario_file(duration=0.2)
    out = tmp_path / "run.mcap"
    commands = ros_graph.publisher("rotor_cmd", JointState)
    recorder = ros_graph.start("recorder", [executable("fsr-record"), "--out", str(out)])
    sim = start_simulator(ros_graph, path, "wait_for_subscribers:=1")
    assert ros_graph.spin_until(lambda: "sending the initial state" in ros_graph.log(sim), 20.0), ros_graph.log(sim)
    ros_graph.spin_for(0.3)  # t_0 stays unanswered for a while: a simulator that repeated it would do it now
    flight = ros_graph.run_controller(sim, rotor_answer(speeds), commands)
    assert_finished(flight, 200)
    recorder.send_signal(signal.SIGINT)
    assert ros_graph.wait_exit(recorder, 10.0) == 0, ros_graph.log(recorder)
    recording = open_recording(out)
    for topic in ("odom", "wrench_truth"):
        assert [t for t, _ in recording.raw(topic)] == [k * 1_000_000 for k in range(201)], topic
