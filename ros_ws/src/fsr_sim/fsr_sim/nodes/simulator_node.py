"""Simulator node: steps the plant in lockstep with the controller and publishes the state (docs/model.md §4).

Publishes ``/clock`` (if ``publish_clock``), ``odom``, ``wrench_truth``, with actuator dynamics ``rotor_state``,
with an IMU (``sensors.imu``) ``imu``, with a measured ``odom`` (``sensors.odometry``) the true state on
``odom_truth``, and ``sim_status`` (a
:class:`fsr_sim.contract.SimStatus` as JSON: ``running``, then ``finished``, ``diverged`` or ``stopped``; also
published when the controller stops answering and when it answers again), each with its QoS of
:mod:`fsr_sim.contract`; subscribes ``rotor_cmd``
(sensor_msgs/JointState) or, with ``actuation: wrench``, ``wrench_cmd`` (geometry_msgs/WrenchStamped).
Parameters: :mod:`fsr_sim.nodes.simulator_params`.

Lockstep (default):

1. Handshake (both modes): wait until ``odom`` has ``wait_for_subscribers`` subscribers, the command topic has a
   publisher and each ``recorded_topics`` one we publish a reader (:mod:`fsr_sim.ros.recorder_match`), then
   publish the state ``t_0`` once and wait for the command stamped ``t_0``. The state is never sent twice, so
   every subscriber (the recorder too) sees exactly one message per step: the streams are transient-local
   (:mod:`fsr_sim.ros.qos`), so a reader whose side of the match completes after ``t_0`` went out (discovery
   is asynchronous) still receives it from the writer's history.
2. Step k: wait for the command stamped ``t_k`` (stale stamps ignored, NaN/inf dropped with a warning),
   apply it, run ``physics_substeps`` RK4 steps, publish the state ``t_{k+1}``. A missing command ->
   failsafe (``hold`` the last command or ``cut`` thrust); see :mod:`fsr_sim.nodes.lockstep`. While the
   controller publishes ``reference`` and ``attitude_cmd``, the state ``t_k`` is also checked against its answer
   stamped ``t_k`` (waited for like the command): an attitude error against ``R_c`` or a position error against
   ``p_d`` beyond the scenario's ``divergence`` bounds (:func:`fsr_sim.core.control_loss.control_loss`, what the
   in-process loop calls) ends the flight as diverged at ``t_k``, exit 3.
3. After ``duration``: publish the final state, ``sim_status`` finished, exit 0. Divergence (NaN state,
   speed/spin bounds, crash) -> ``sim_status`` diverged with the reason, exit 3. SIGINT/SIGTERM ->
   ``sim_status`` stopped, exit 0. A start-up handshake that does not complete -> exit 1.

Free-running (``lockstep.enabled: false``): after the same handshake, steps are paced to
``real_time_factor`` x wall time and the latest valid command (any stamp) is applied; the failsafe applies
after ``timeout`` s without one.

Waiting uses :class:`fsr_sim.ros.wait_set.SubscriptionWaitSet` on the command subscription (the fastest
measured style; the executor given by ``run_node`` is never spun, so the subscription's callback never runs).
Each step is the compiled core's lockstep step (:func:`fsr_sim.core.lockstep.advance`, the function the
in-process loop calls too); the state is published as packed CDR bytes of the core's published row
(:class:`fsr_sim.nodes.state_packets.StatePackets`). Progress for a watcher (``fsr-fly``): ``sim_progress``
(rosgraph_msgs/Clock, the simulated time) every ``PROGRESS_STEPS`` steps, so that nothing needs to follow
every ``/clock`` message.
"""

from __future__ import annotations

import sys
import time

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.duration import Duration
from rclpy.node import Node
from std_msgs.msg import String

from fsr_sim.config.scenario import plant_from_config
from fsr_sim.contract import (
    ATTITUDE_CMD,
    CLOCK,
    DIVERGED,
    FINISHED,
    IMU,
    ODOM,
    ODOM_TRUTH,
    REFERENCE,
    ROTOR_CMD,
    ROTOR_STATE,
    RUNNING,
    SIM_PROGRESS,
    SIM_STATUS,
    STOPPED,
    WRENCH_CMD,
    WRENCH_TRUTH,
    SimStatus,
)
from fsr_sim.core import lockstep
from fsr_sim.core.control_loss import IN_CONTROL, control_loss, held_by_surface
from fsr_sim.core.odometry import PUBLISHED_SIZE
from fsr_sim.core.plant import RUNNING as PLANT_RUNNING
from fsr_sim.model.control_loss import loss_reason
from fsr_sim.model.plant import divergence_reason, has_actuator_dynamics
from fsr_sim.nodes.commands import RotorCommandReader, wrench_command_raw
from fsr_sim.nodes.lockstep import (
    AHEAD,
    CURRENT,
    CommandWait,
    CommandWatchdog,
    FreeRunPacer,
    classify_stamp,
)
from fsr_sim.nodes.simulator_params import PARAMETER_NAMES, USAGE, load_simulation, parse_parameters
from fsr_sim.nodes.state_packets import StatePackets
from fsr_sim.ros import cdr_read
from fsr_sim.ros.endpoints import publisher, subscription
from fsr_sim.ros.recorder_match import unmatched
from fsr_sim.ros.runtime import EXIT_DIVERGED, EXIT_FAILURE, EXIT_OK, RateLimitedWarning, run_node, signal_deadline
from fsr_sim.ros.wait_set import SubscriptionWaitSet

WAIT_SLICE = 0.05  # s: longest uninterrupted wait (signals, lost publisher are checked in between)
BATCH_WALL = 0.05  # s of stepping per spin_once call
LONG_WAIT = 0.1  # s: a lockstep wait at least this long is logged (a pause of the flight)
PROGRESS_STEPS = 100  # steps between two sim_progress messages (10 Hz of simulated time at 1 kHz)
ACK_TIMEOUT = 2.0  # s: bound on waiting for subscribers to acknowledge the last messages
ACK_SLICE = 0.05  # s per wait_for_all_acked call
SIGNAL_ACK_LIMIT = 1.0  # s after SIGINT/SIGTERM: the same bound when stopped by a signal

HANDSHAKE, FIRST_COMMAND, STEPPING, DONE = "handshake", "first_command", "stepping", "done"  # the node's phases


class SimulatorNode(Node):
    """The plant as a ROS node; ``run_node`` drives it through :meth:`spin_once`."""

    def __init__(self, _args: list[str]) -> None:
        super().__init__("simulator", start_parameter_services=False)
        dynamic = ParameterDescriptor(dynamic_typing=True)
        values = {name: self.declare_parameter(name, None, dynamic).value for name in PARAMETER_NAMES}
        self.params = parse_parameters(values)
        self.scenario, self.config = load_simulation(self.params)
        self.plant = plant_from_config(self.config)
        vehicle = self.config.plant_vehicle
        self.publish_rotor_state = has_actuator_dynamics(self.plant.params)
        imu = self.plant.params.sensors.imu
        truth = self.plant.params.sensors.odometry.enabled  # odom is measured: the true state beside it
        self.messages = StatePackets(vehicle.rotor_count if self.publish_rotor_state else 0, vehicle.has_servos, imu,
                                     truth)
        self.published = np.zeros(PUBLISHED_SIZE)  # the core's published row of the current state
        self.rotor_reader = RotorCommandReader(vehicle.rotor_count, vehicle.has_servos)

        command = WRENCH_CMD if self.config.actuation == "wrench" else ROTOR_CMD
        self.command_topic = command.name
        self.odom_pub = publisher(self, ODOM)
        self.wrench_pub = publisher(self, WRENCH_TRUTH)
        self.rotor_state_pub = publisher(self, ROTOR_STATE) if self.publish_rotor_state else None
        self.imu_pub = publisher(self, IMU) if imu.enabled else None
        self.truth_pub = publisher(self, ODOM_TRUTH) if truth else None
        self.clock_pub = publisher(self, CLOCK) if self.params.publish_clock else None
        self.progress_pub = publisher(self, SIM_PROGRESS)
        self.status_pub = publisher(self, SIM_STATUS)
        self.recorded_publishers = {topic.name: pub for topic, pub in (
            (ODOM, self.odom_pub), (WRENCH_TRUTH, self.wrench_pub), (ROTOR_STATE, self.rotor_state_pub),
            (IMU, self.imu_pub), (ODOM_TRUTH, self.truth_pub), (CLOCK, self.clock_pub),
            (SIM_PROGRESS, self.progress_pub), (SIM_STATUS, self.status_pub))}
        self.command_sub = subscription(self, command, _unused, raw=True)  # commands are read from their CDR bytes
        # the controller's answer to each state beyond the command: what the loss-of-control check compares it with
        self.reference_sub = subscription(self, REFERENCE, _unused, raw=True)
        self.attitude_sub = subscription(self, ATTITUDE_CMD, _unused, raw=True)
        self.wait_set = SubscriptionWaitSet(self, [self.command_sub, self.reference_sub, self.attitude_sub])
        self.control_bounds = self.config.divergence.pack()
        self.position_d, self.quaternion_c = np.zeros(3), np.zeros(4)  # p_d [m] and R_c (x y z w) of answer_ns
        self.answer_ns: list[int | None] = [None, None]  # stamps of the reference and attitude_cmd held

        self.phase = HANDSHAKE
        self.exit_code = EXIT_OK
        self.final_state: str | None = None
        self.command_wait = CommandWait(self.config.lockstep_timeout)
        self.pacer: FreeRunPacer | None = None
        self.watchdog: CommandWatchdog | None = None
        self.have_command = False  # the command for the current state was applied
        self.controller_name = "(name not discovered)"
        self.stop_flag: object = None  # run_node's StopFlag (its signal_name says why we stop)
        self.warn_bad = RateLimitedWarning(self.get_logger())
        self.warn_saturation = RateLimitedWarning(self.get_logger(), period=2.0)
        self.startup_deadline = time.monotonic() + self.params.startup_timeout
        self.wall_start = 0.0
        self.stale_commands = 0
        self.longest_wait = 0.0  # s: longest wait for a command in lockstep
        self.surfaces_at_cap: set[str] = set()  # surfaces whose effect-cap warning was logged
        mode = "lockstep" if self.config.lockstep else f"free-running at {self.config.real_time_factor}x real time"
        self.get_logger().info(
            f"scenario '{self.config.name}' ({self.scenario.source}): {self.config.plant_vehicle.name}, "
            f"{self.config.step_count} steps of {self.config.control_period * 1e3:g} ms, {mode}, "
            f"failsafe {self.config.failsafe} after {self.config.lockstep_timeout:g} s; waiting for "
            f"{self.params.wait_for_subscribers} odom subscriber(s) and a {self.command_topic} publisher"
        )

    # ----- run_node hooks ---------------------------------------------------------------------------
    def done(self) -> bool:
        return self.phase == DONE

    def spin_once(self, _executor: object, stop: object) -> None:
        """One slice of work: a handshake poll, or up to ``BATCH_WALL`` s of steps."""
        self.stop_flag = stop
        if self.phase == HANDSHAKE:
            self._handshake()
        elif self.phase == FIRST_COMMAND:
            self._first_command(stop)
        elif self.phase == STEPPING:
            step = self._lockstep_step if self.config.lockstep else self._free_step
            batch_end = time.monotonic() + BATCH_WALL
            while self.phase == STEPPING and not stop and time.monotonic() < batch_end:
                step(stop)

    def close(self) -> None:
        """Report how the run ended (``stopped`` if nothing else did) and let the last messages arrive."""
        if self.final_state is None:
            signal_name = getattr(self.stop_flag, "signal_name", None)
            reason = f"received {signal_name}" if signal_name else "stopped before the end of the flight"
            self._finish(STOPPED, reason, self.exit_code)
        start = time.monotonic()
        for pub in (self.odom_pub, self.wrench_pub, self.status_pub):
            while not pub.wait_for_all_acked(Duration(nanoseconds=int(ACK_SLICE * 1e9))):
                # re-evaluated every slice: a signal arriving meanwhile shortens the wait
                if time.monotonic() >= min(start + ACK_TIMEOUT, signal_deadline(self.stop_flag, SIGNAL_ACK_LIMIT,
                                                                                 ACK_TIMEOUT)):
                    self.get_logger().warning(
                        f"'{pub.topic_name}': not every subscriber acknowledged the last messages"
                    )
                    return

    # ----- start-up ---------------------------------------------------------------------------------
    def _handshake(self) -> None:
        subscribers = self.odom_pub.get_subscription_count()
        publishers = self.command_sub.get_publisher_count()
        unrecorded = unmatched(self.recorded_publishers, self.params.recorded_topics)
        if subscribers >= self.params.wait_for_subscribers and publishers >= 1 and not unrecorded:
            self.get_logger().info(
                f"graph ready: {subscribers} odom subscriber(s) and {publishers} {self.command_topic} publisher(s);"
                " sending the initial state"
            )
            self._publish_status(RUNNING, "")
            self._publish_state()
            self.phase = FIRST_COMMAND
            return
        if time.monotonic() > self.startup_deadline:
            self._fail_startup(
                f"only {subscribers} of {self.params.wait_for_subscribers} odom subscriber(s) and "
                f"{publishers} {self.command_topic} publisher(s) after {self.params.startup_timeout:g} s"
                + (f"; no recorder reader on {', '.join(unrecorded)}" if unrecorded else "")
            )
            return
        time.sleep(0.01)  # polling the graph (discovery is asynchronous), not waiting blindly

    def _first_command(self, stop: object) -> None:
        """Wait (in slices, so that signals are noticed) for the command answering the t_0 state."""
        expected = self.messages.stamp_ns
        if self._take_commands(expected, WAIT_SLICE):
            self.have_command = True
            self.phase = STEPPING
            if self.rotor_state_pub is not None:  # t_0's: the rotors spin at the first command from the start
                state = self.plant.core_state
                self.rotor_state_pub.publish(self.messages.rotor_state(expected, state.speeds, state.tilts))
            self.wall_start = time.monotonic()
            self._refresh_controller_name()
            self.get_logger().info(f"controller {self.controller_name} answered the initial state: stepping")
            if not self.config.lockstep:
                self.pacer = FreeRunPacer(self.config.control_period, self.config.real_time_factor, self.wall_start)
                self.watchdog = CommandWatchdog(self.config.lockstep_timeout, self.wall_start)
            return
        if stop:
            return
        if time.monotonic() > self.startup_deadline:
            timeout = self.params.startup_timeout
            self._fail_startup(f"no {self.command_topic} answered the first state within {timeout:g} s")

    def _refresh_controller_name(self) -> None:
        """Name the command publisher(s) for messages (node names may be discovered after the endpoint)."""
        infos = self.get_publishers_info_by_topic(self.command_sub.topic_name)
        names = sorted(
            {_node_path(i.node_namespace, i.node_name) for i in infos if "_UNKNOWN_" not in i.node_name}
        )
        if names:
            self.controller_name = ", ".join(names)

    def _fail_startup(self, reason: str) -> None:
        self.get_logger().error(f"start-up failed: {reason}")
        self._finish(STOPPED, f"start-up failed: {reason}", EXIT_FAILURE)

    # ----- stepping ---------------------------------------------------------------------------------
    def _lockstep_step(self, stop: object) -> None:
        waiting_since = time.monotonic()
        command_waited, answered = 0.0, True  # the first state's command was taken before stepping
        if not self.have_command:
            answered = self._await_command(self.messages.stamp_ns, stop)
            if answered is None:
                return  # stop requested while waiting
            command_waited = time.monotonic() - waiting_since
            if answered:
                if self.command_wait.answered(command_waited) == "recovered":
                    self.get_logger().info(
                        f"{self.command_topic}: the controller answers again at {self._where()} "
                        f"({self.command_wait.missed_steps} step(s) on the failsafe so far)"
                    )
                    self._publish_status(RUNNING, "controller back in the loop")
            else:
                self._on_missed(self.command_sub.get_publisher_count())
        lost = self._lost_control(self.messages.stamp_ns, stop)
        # the pause is the wait for the whole answer: a link lost between the command and the reference and
        # attitude_cmd sent after it (or a controller slow to send them) stops the flight as long as a late command
        self._note_wait(command_waited, time.monotonic() - waiting_since, answered)
        if not lost:
            self._advance()

    def _await_command(self, expected_ns: int, stop: object) -> bool | None:
        """Wait (in slices) for the command stamped ``expected_ns``; None if a stop was requested."""
        started = time.monotonic()
        deadline = started + self.command_wait.budget()
        while True:
            remaining = deadline - time.monotonic()
            late = self.stale_commands
            if self._take_commands(expected_ns, max(0.0, min(remaining, WAIT_SLICE))):
                return True
            if self.stale_commands > late:  # a late answer: the controller is catching up (lockstep.CommandWait)
                deadline = max(deadline, started + self.command_wait.budget_after_late_answer())
            if time.monotonic() >= deadline:
                return False
            if stop:
                return None
            if self.command_sub.get_publisher_count() == 0:
                return False

    def _note_wait(self, command_waited: float, waited: float, answered: bool) -> None:
        """Keep the longest lockstep wait for the controller's answer to one state (a pause: slow controller,
        network outage) and report long ones: ``waited`` [s] for the whole answer, of which ``command_waited``
        [s] for the command (the rest for the reference and attitude_cmd the loss-of-control check needs)."""
        self.longest_wait = max(self.longest_wait, waited)
        if answered and waited >= LONG_WAIT:
            rest = "" if waited - command_waited < LONG_WAIT else (
                f"; {REFERENCE.name}, {ATTITUDE_CMD.name}: {waited - command_waited:.3f} s more")
            self.get_logger().info(
                f"lockstep paused {waited:.3f} s at {self._where()} for the controller's answer "
                f"({self.command_topic}: {command_waited:.3f} s{rest})"
            )

    def _on_missed(self, publishers: int) -> None:
        event = self.command_wait.missed(publishers)
        failsafe = self.config.failsafe
        if event == "timeout":
            self._refresh_controller_name()
            self.get_logger().warning(
                f"controller {self.controller_name} did not answer {self._where()} within "
                f"{self.config.lockstep_timeout:g} s on {self.command_topic}: applying failsafe '{failsafe}' and "
                "going on (waiting only briefly for it from now on)"
            )
        elif event == "gone":
            self.get_logger().warning(
                f"{self.command_topic} has no publisher any more (controller {self.controller_name} gone) at "
                f"{self._where()}: applying failsafe '{failsafe}' and finishing the flight without waiting"
            )
        elif event == "publisher_back":
            self.get_logger().info(f"{self.command_topic} has a publisher again at {self._where()}")
        if event in ("timeout", "gone"):  # an incident: in the latched status until the next one
            self._publish_status(RUNNING, f"failsafe '{failsafe}': controller not answering ({event})")
        if failsafe == "cut":
            self.plant.cut_thrust()

    def _free_step(self, stop: object) -> None:
        now = time.monotonic()
        deadline = self.pacer.deadline(self.plant.step_index, now)
        while now < deadline:
            self._take_commands(None, min(deadline - now, WAIT_SLICE))
            if stop:
                return
            now = time.monotonic()
        if self.watchdog.expired(now):
            publishers = self.command_sub.get_publisher_count()
            why = "no publisher" if publishers == 0 else f"no valid command for {self.config.lockstep_timeout:g} s"
            self.get_logger().warning(
                f"{self.command_topic}: {why} (controller {self.controller_name}) at {self._where()}: "
                f"applying failsafe '{self.config.failsafe}'"
            )
            if self.config.failsafe == "cut":
                self.plant.cut_thrust()
        if self._lost_control(None, stop):
            return
        self._advance()

    def _lost_control(self, expected_ns: int | None, stop: object) -> bool:
        """Check the current state against the controller's answer stamped ``expected_ns`` (lockstep: waited for up to
        the command's budget while it is published; free-running, ``None``: the latest answer); a loss of control
        ends the flight as diverged. True when it did."""
        if expected_ns is not None and self.answer_ns != [expected_ns, expected_ns] and (
                self.reference_sub.get_publisher_count() and self.attitude_sub.get_publisher_count()):
            deadline = time.monotonic() + self.command_wait.budget()
            while self.answer_ns != [expected_ns, expected_ns] and not stop and time.monotonic() < deadline:
                self._take_commands(expected_ns, max(0.0, min(deadline - time.monotonic(), WAIT_SLICE)))
        if None in self.answer_ns or (expected_ns is not None and self.answer_ns != [expected_ns, expected_ns]):
            return False
        plant = self.plant
        code = control_loss(self.control_bounds, plant.core_state.x, self.position_d, self.quaternion_c,
                            held_by_surface(plant.core_state))
        if code == IN_CONTROL:
            return False
        reason = loss_reason(code, self.config.divergence, plant.core_state.x, self.position_d, self.quaternion_c,
                             plant.time)
        self.get_logger().error(f"simulation diverged at t = {plant.time:.4f} s: {reason}")
        self._finish(DIVERGED, reason, EXIT_DIVERGED)
        return True

    def _advance(self) -> None:
        """Step the plant one control period, then publish the new state or end the run."""
        self.have_command = False
        plant = self.plant
        code = lockstep.advance(plant.params, plant.core_state, self.published)
        if (plant.ground_cap_steps or plant.ceiling_cap_steps) and len(self.surfaces_at_cap) < 2:
            self._warn_surface_cap()
        if code != PLANT_RUNNING:
            reason = divergence_reason(code, plant.params, plant.core_state)
            if bool(np.isfinite(plant.state_vector).all()):
                self._send_state()
            self.get_logger().error(f"simulation diverged at t = {plant.time:.4f} s: {reason}")
            self._finish(DIVERGED, reason, EXIT_DIVERGED)
            return
        self._send_state()
        if plant.step_index >= self.config.step_count:
            self._finish(FINISHED, f"reached the scenario duration {self.config.duration:g} s", EXIT_OK)

    def _warn_surface_cap(self) -> None:
        """Warn once per surface when its thrust ratio first reaches ``max_ratio`` (outside the model)."""
        environment = self.config.environment
        for surface, steps, max_ratio in (
            ("ground", self.plant.ground_cap_steps, environment.ground.max_ratio),
            ("ceiling", self.plant.ceiling_cap_steps, environment.ceiling.max_ratio),
        ):
            if steps and surface not in self.surfaces_at_cap:
                self.surfaces_at_cap.add(surface)
                self.get_logger().warning(
                    f"{surface} effect at its cap (thrust ratio {max_ratio:g} = max_ratio) at {self._where()}: a "
                    f"rotor is closer to the {surface} than the effect model is valid for; the steps are counted"
                )

    # ----- commands ---------------------------------------------------------------------------------
    def _take_commands(self, expected_ns: int | None, wait: float) -> bool:
        """Wait up to ``wait`` s, take every queued command, apply the valid one answering ``expected_ns``
        (lockstep) or every valid one (free-running, ``expected_ns`` None); True if one was applied."""
        applied = False
        for index, data, _info in self.wait_set.take_ready(int(wait * 1e9)):  # CDR bytes: read in place
            if index:  # a reference or an attitude_cmd
                self._take_answer(index - 1, data, expected_ns)
                continue
            if expected_ns is not None:
                try:
                    stamp_ns = cdr_read.stamp(data)
                except ValueError as error:
                    self.warn_bad(f"dropped a command at {self._where()}: {error}")
                    continue
                verdict = classify_stamp(stamp_ns, expected_ns)
                if verdict != CURRENT:
                    self._on_off_stamp(verdict, stamp_ns, expected_ns)
                    continue
            if self._apply(data):
                applied = True
        if applied and self.watchdog is not None and self.watchdog.feed(time.monotonic()):
            self.get_logger().info(f"{self.command_topic}: commands arrive again at {self._where()}")
        return applied

    def _take_answer(self, which: int, data: bytes, expected_ns: int | None) -> None:
        """Keep the reference's position (``which`` 0) or the commanded attitude (1) stamped ``expected_ns``
        (free-running, None: the latest); others are dropped."""
        try:
            stamp_ns, values = cdr_read.reference_pose(data) if which == 0 else cdr_read.quaternion_stamped(data)
        except ValueError as error:
            self.warn_bad(f"dropped a {(REFERENCE, ATTITUDE_CMD)[which].name} at {self._where()}: {error}")
            return
        if expected_ns is None or stamp_ns == expected_ns:
            if which == 0:
                self.position_d[:] = values[:3]
            else:
                self.quaternion_c[:] = values
            self.answer_ns[which] = stamp_ns

    def _on_off_stamp(self, verdict: str, stamp_ns: int, expected_ns: int) -> None:
        if verdict == AHEAD:
            sec, nanosec = divmod(stamp_ns, 1_000_000_000)
            self.warn_bad(
                f"{self.command_topic} stamped {sec}.{nanosec:09d} is ahead of the state "
                f"{expected_ns * 1e-9:.6f} s: ignored"
            )
        else:
            self.stale_commands += 1

    def _apply(self, data: bytes) -> bool:
        """Apply one command (CDR bytes) to the plant; NaN/inf or malformed -> dropped with a warning, False."""
        try:
            if self.config.actuation == "wrench":
                wrench = wrench_command_raw(data)
                self.plant.set_wrench(wrench[:3], wrench[3:])
                return True
            speeds, tilts = self.rotor_reader.read_raw(data)
        except ValueError as error:
            self.warn_bad(f"dropped a command at {self._where()}: {error}")
            return False
        if self.plant.set_rotor_command(speeds, tilts):
            self.warn_saturation(f"rotor command saturated at {self._where()} (clamped to the speed limits)")
        return True

    # ----- output -----------------------------------------------------------------------------------
    def _publish_state(self) -> None:
        """Publish the current state (the core's published row, computed here)."""
        lockstep.publish(self.plant.params, self.plant.core_state, self.published)
        self._send_state()

    def _send_state(self) -> None:
        """Publish the published row of the current state (``odom``, ``wrench_truth``, ``/clock``; with an IMU,
        ``imu``; with a measured ``odom``, ``odom_truth``) and, with actuator dynamics, ``rotor_state``."""
        messages, plant = self.messages, self.plant
        messages.fill_from_row(plant.stamp_ns, self.published)
        self.odom_pub.publish(messages.odom)  # first: it is what the controller waits for
        if self.truth_pub is not None:
            self.truth_pub.publish(messages.truth)
        self.wrench_pub.publish(messages.wrench)
        if self.rotor_state_pub is not None and self.phase != HANDSHAKE:  # t_0's: once the first command came
            state = plant.core_state
            self.rotor_state_pub.publish(messages.rotor_state(plant.stamp_ns, state.speeds, state.tilts))
        if self.imu_pub is not None:
            self.imu_pub.publish(messages.imu)
        if self.clock_pub is not None:
            self.clock_pub.publish(messages.clock)
        if plant.step_index % PROGRESS_STEPS == 0 or plant.step_index >= self.config.step_count:
            self.progress_pub.publish(messages.clock)

    def _publish_status(self, state: str, reason: str) -> None:
        status = SimStatus(state, reason, self.plant.time, self.plant.step_index, self.command_wait.missed_steps,
                           self.command_wait.incidents, self.stale_commands, round(self.longest_wait, 6))
        self.status_pub.publish(String(data=status.to_json()))

    def _finish(self, state: str, reason: str, exit_code: int) -> None:
        self.final_state = state
        self.exit_code = exit_code
        self.phase = DONE
        self._publish_status(state, reason)
        wall = time.monotonic() - self.wall_start if self.wall_start else 0.0
        speed = f", {self.plant.time / wall:.2f}x real time" if wall > 0 and self.plant.time > 0 else ""
        missed = self.command_wait.missed_steps
        summary = f"; {missed} step(s) ran on the failsafe" if missed else ""
        summary += f"; {self.stale_commands} late command(s) ignored" if self.stale_commands else ""
        saturation = self.plant.saturation.count
        summary += f"; {saturation} saturated rotor command(s)" if saturation else ""
        for surface, steps in (("ground", self.plant.ground_cap_steps), ("ceiling", self.plant.ceiling_cap_steps)):
            summary += f"; {steps} step(s) with the {surface} effect at its cap" if steps else ""
        self.get_logger().info(
            f"{state}: {reason} ({self.plant.step_index} steps, t = {self.plant.time:.4f} s in {wall:.2f} s wall"
            f"{speed}{summary})"
        )

    def _where(self) -> str:
        return f"step {self.plant.step_index} (t = {self.plant.time:.4f} s)"


def _unused(_msg: object) -> None:
    """Subscription callback that never runs: commands are taken from the wait set."""


def _node_path(namespace: str, name: str) -> str:
    return f"{namespace.rstrip('/')}/{name}"


def main(argv: list[str] | None = None) -> None:
    sys.exit(run_node(SimulatorNode, argv, usage=USAGE))


if __name__ == "__main__":
    main()
