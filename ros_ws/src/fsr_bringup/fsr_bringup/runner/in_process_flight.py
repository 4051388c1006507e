"""The closed loop in one process, with exactly the per-step functions of the node graph and its lockstep.

The loop itself is compiled (:mod:`fsr_bringup.core.flight_loop`: the simulator's lockstep step, the
controller's tick and the estimator's sample, the functions the nodes call) and runs ``CHUNK_STEPS`` steps per
call; between calls this driver writes the recording (:class:`fsr_bringup.recording.flight_recording.
InProcessRecorder`: the payloads the nodes publish, packed from the loop's arrays) and polls ``stop``, so Ctrl-C
(KeyboardInterrupt) ends the flight as ``stopped`` with every step flown in the arrays and the recording.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fsr_bringup.core import flight_loop
from fsr_bringup.core.flight_measures import ROTOR_ROWS, Measurement, new_accumulators, unmeasured
from fsr_control.config.controller_config import controller_config
from fsr_control.core import controller as control_layout
from fsr_control.core.controller import COMMANDED_QUATERNION, REFERENCE_POSITION
from fsr_control.core.flatness import ATTITUDE_ERRORS
from fsr_control.flight_controller import FlightController
from fsr_control.planning.trajectory import mid_path, mid_path_note
from fsr_sim.config.scenario import Scenario, plant_from_config, simulation_config
from fsr_sim.contract import DIVERGED, EXIT_DIVERGED, EXIT_INTERRUPTED, EXIT_OK, FINISHED, RUNNING, STOPPED
from fsr_sim.core.odometry import (
    IMU_ANGULAR_VELOCITY,
    IMU_LINEAR_ACCELERATION,
    IMU_TRUE_LINEAR_ACCELERATION,
    ODOM_SIZE,
    PUBLISHED_SIZE,
    TRUE_ODOM,
    TRUTH_FORCE,
    TRUTH_TORQUE,
)
from fsr_sim.model.control_loss import loss_reason
from fsr_sim.model.plant import divergence_reason, has_actuator_dynamics
from fsr_sim.model.so3 import rotations_from_quaternions
from fsr_sim.ros.runtime import process_age

if TYPE_CHECKING:
    from fsr_bringup.live.server import LiveServer

CHUNK_STEPS = 1000  # steps per call of the compiled loop (signals and the recording are handled in between)


@dataclass
class FlightRun:
    """One flight as arrays over the published states ``k = 0..K`` (K = step count, or the last step flown).

    Attributes
    ----------
    time : numpy.ndarray, shape (K+1,)
        Simulated time [s] of each state.
    state : numpy.ndarray, shape (K+1, 13)
        Position world [m], velocity world [m/s], quaternion ``[x, y, z, w]`` (``w >= 0``, as published),
        angular velocity body [rad/s].
    reference_position, reference_velocity, reference_acceleration : numpy.ndarray, shape (K+1, 3)
        The planner's reference, world NED [m, m/s, m/s^2]; ``reference_rotation`` (K+1, 3, 3).
    rotation_commanded : numpy.ndarray, shape (K+1, 3, 3)
        The attitude the control law commanded (geometric: ``R_d`` from the thrust direction).
    force_desired, torque_desired : numpy.ndarray, shape (K+1, 3)
        The law's body wrench before allocation [N, N m].
    force_cmd, torque_cmd : numpy.ndarray, shape (K+1, 3)
        The body wrench commanded after allocation (what ``wrench_cmd`` carries) [N, N m].
    rotor_speeds, tilt_angles : numpy.ndarray, shape (K+1, n), or None
        Commanded [rad/s], [rad] (``rotor_cmd``; None in wrench actuation / for fixed rotors).
    actual_rotor_speeds, actual_tilt_angles : numpy.ndarray, shape (K+1, n), or None
        The rotors' own speeds and tilts at each state (clamped, and behind the command with actuator
        dynamics: ``rotor_state``).
    external_force_body, external_torque_body : numpy.ndarray, shape (K+1, 3)
        The true external wrench, body frame (as ``wrench_truth``) [N, N m].
    estimate_force_body, estimate_torque_body, mass_estimate : numpy.ndarray or None
        The estimator's outputs (None when it is disabled).
    imu_angular_velocity_measured, imu_specific_force_measured : numpy.ndarray, shape (K+1, 3), or None
        What ``imu`` carries (the IMU's noise, bias, delay and rate on the true values), body FRD [rad/s],
        [m/s^2]; None without an IMU (``sensors.imu``).
    odometry_measured : numpy.ndarray, shape (K+1, 13), or None
        What ``odom`` carries when it is a measurement (``sensors.odometry``): position world [m], quaternion
        ``[x, y, z, w]``, velocity body [m/s], angular velocity body [rad/s]; None when ``odom`` is the true state
        (``state`` is always the true state, what the tracking errors are taken on); ``odometry_true`` then the same
        numbers of the true state (``odom_truth``'s).
    imu_specific_force_true : numpy.ndarray, shape (K+1, 3), or None
        The true specific force ``R^T (p_ddot - g e3)`` [m/s^2], body FRD, of each state (the true angular
        velocity is :attr:`angular_velocity`); None without an IMU.
    end_reason : str
        ``finished``, ``diverged`` or ``stopped`` (interrupted); ``reason`` says why.
    plan_kind, plan_end_time : str, float
        The trajectory's ``kind`` and when its plan (with the goals received) comes to rest [s].
    notes : list of str
        What the flight's user should know: a flight that finished before its plan came to rest ended
        mid-path (``ended_mid_path``).
    compensation : dict
        ``{"mode": "none"}``, or with ``controller.compensation: estimate`` the steps compensated, the steps
        switched off by contact, the late estimates (0: the observer is in the controller) and the gaps
        (:class:`fsr_control.compensation.CompensationReport`).
    """

    time: np.ndarray
    state: np.ndarray
    reference_position: np.ndarray
    reference_velocity: np.ndarray
    reference_acceleration: np.ndarray
    reference_rotation: np.ndarray
    force_cmd: np.ndarray
    torque_cmd: np.ndarray
    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    external_force_body: np.ndarray
    external_torque_body: np.ndarray
    estimate_force_body: np.ndarray | None
    estimate_torque_body: np.ndarray | None
    mass_estimate: np.ndarray | None
    saturation: dict[str, Any]
    tilt_saturation: dict[str, Any]
    end_reason: str  # the final sim_status state: finished, diverged or stopped (fsr_sim.contract)
    reason: str
    wall_time: float
    rotation_commanded: np.ndarray | None = None
    force_desired: np.ndarray | None = None
    torque_desired: np.ndarray | None = None
    scenario: Scenario | None = None
    failures: list[str] = field(default_factory=list)
    interrupted: bool = False
    compensation: dict[str, Any] = field(default_factory=lambda: {"mode": "none"})  # FlightController's summary
    startup_time: float | None = None  # s from the process start to the first step (None: unknown)
    plan_adjustments: list[str] = field(default_factory=list)  # the legs and goals beyond the authority (texts)
    actual_rotor_speeds: np.ndarray | None = None
    actual_tilt_angles: np.ndarray | None = None
    reference_angular_velocity_world: np.ndarray | None = None  # (K+1, 3) ``R_d omega_d`` [rad/s], world
    wrench_shortfall: np.ndarray | None = None  # (K+1, 6) demanded minus commanded body wrench [N, N m]
    simulation: Any = None  # the flight's validated plant side (fsr_sim.config.scenario.SimulationConfig)
    estimator: Any = None  # its estimator config (fsr_estimation.config.estimator_config.EstimatorConfig)
    actuator_dynamics: bool = False  # the rotors lag their commands (the graph then publishes rotor_state)
    imu_angular_velocity_measured: np.ndarray | None = None  # (K+1, 3) imu's angular velocity [rad/s], body
    imu_specific_force_measured: np.ndarray | None = None  # (K+1, 3) imu's linear acceleration [m/s^2], body
    imu_specific_force_true: np.ndarray | None = None  # (K+1, 3) R^T (p_ddot - g e3) [m/s^2], body
    odometry_measured: np.ndarray | None = None  # (K+1, 13) odom's numbers when it is measured (sensors.odometry)
    odometry_true: np.ndarray | None = None  # (K+1, 13) odom_truth's numbers (the true state), beside a measured odom
    plan_kind: str = "waypoints"  # trajectory.kind
    plan_end_time: float | None = None  # [s] when the plan comes to rest (None: no plan)
    notes: list[str] = field(default_factory=list)
    recording: Path | None = None  # the file the flight was recorded into (None: not recorded)

    @property
    def sim_time(self) -> float:
        return float(self.time[-1])

    @property
    def ended_mid_path(self) -> bool:
        """The flight finished (at the scenario's duration) before its plan came to rest."""
        return mid_path(self.end_reason, self.sim_time, self.plan_end_time)

    @property
    def exit_code(self) -> int:
        if self.interrupted:
            return EXIT_INTERRUPTED
        return EXIT_DIVERGED if self.end_reason == DIVERGED else EXIT_OK

    @property
    def real_time_factor(self) -> float:
        return self.sim_time / self.wall_time if self.wall_time > 0 else float("nan")

    @property
    def position(self) -> np.ndarray:
        return self.state[:, 0:3]

    @property
    def velocity(self) -> np.ndarray:
        return self.state[:, 3:6]

    @property
    def rotation(self) -> np.ndarray:
        """(K+1, 3, 3) body -> world."""
        return rotations_from_quaternions(self.state[:, 6:10])

    @property
    def angular_velocity(self) -> np.ndarray:
        """(K+1, 3) [rad/s], body FRD."""
        return self.state[:, 10:13]

    @property
    def thrust(self) -> np.ndarray:
        return -self.force_cmd[:, 2]

    @cached_property
    def trace(self) -> Any:
        """This flight's time series as the analysis takes them: the
        :class:`fsr_bringup.analysis.load.RecordedFlight` that ``load_flight`` reads from its recording, made
        from these arrays (``odom`` what is published - the measurement when a sensor stage is on, with the
        true state on ``odom_truth`` beside it -, every topic at the states' stamps)."""
        from fsr_bringup.analysis.in_memory import recorded_flight_of_run

        return recorded_flight_of_run(self, self.recording)

    def metrics(self, **options: Any) -> dict[str, Any]:
        """The metrics of this flight, the ones its summary and ``fsr-sweep`` report
        (:func:`fsr_bringup.analysis.metrics.flight_metrics` of :attr:`trace`; ``options``: its
        ``settle_time``, ``settling``, ``after``). Tracking errors are on the true state."""
        from fsr_bringup.analysis.metrics import flight_metrics

        return flight_metrics(self.trace, **options)

    def save_mcap(self, path: str | Path) -> Path:
        """Write this flight's recording, the file ``fsr-fly --in-process`` writes: the flight is flown again
        (it is deterministic, bit for bit) with the recorder on, up to the last step of this run."""
        if self.scenario is None:
            raise ValueError("this run has no scenario to fly again")
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        again = fly_in_process(self.scenario, path, max_steps=len(self.time) - 1)
        if again.state.shape != self.state.shape or not np.array_equal(again.state, self.state):
            raise RuntimeError("the flight flown again differs from this run (is the scenario deterministic?)")
        return path




class _Stopped(KeyboardInterrupt):
    """``stop()`` asked for the end of the flight (between two steps)."""

    def __init__(self, signal_name: str) -> None:
        super().__init__(signal_name)
        self.signal_name = signal_name


@dataclass
class FlightSetup:
    """A flight ready to fly: its validated configs, the packed objects the compiled loop steps, and the arrays
    it writes (row ``k`` = step ``k``; :func:`fsr_bringup.core.flight_loop.fly`)."""

    scenario: Scenario
    simulation: Any  # fsr_sim.config.scenario.SimulationConfig
    estimation: Any  # fsr_estimation.config.estimator_config.EstimatorConfig
    plant: Any  # fsr_sim.model.plant.Plant
    controller: FlightController
    observer: Any  # fsr_estimation.estimator.observer.MomentumObserver
    steps: int
    period_ns: int
    arrays: FlightArrays

    @property
    def rotors(self) -> bool:
        return self.simulation.actuation == "rotors"

    @property
    def actuator_dynamics(self) -> bool:
        """The rotors lag their commands (the graph then publishes ``rotor_state``)."""
        return self.rotors and has_actuator_dynamics(self.plant.params)

    @property
    def imu(self) -> bool:
        """The vehicle has an IMU (the graph then publishes ``imu``)."""
        return self.simulation.imu.enabled

    @property
    def control_bounds(self) -> tuple[float, float]:
        """The scenario's ``divergence`` bounds as the compiled check takes them."""
        return self.simulation.divergence.pack()

    @property
    def odometry_measured(self) -> bool:
        """``odom`` is a measurement (a sensor stage on), not the true state (the graph then publishes
        ``odom_truth``)."""
        return bool(self.plant.params.sensors.odometry.enabled)

    def fly(self, first: int, last: int) -> tuple[int, int, int]:
        """Steps ``first..last`` in the compiled loop, written into the arrays: ``(outcome, k, detail)`` of
        :func:`fsr_bringup.core.flight_loop.fly`."""
        a = self.arrays
        estimator = flight_loop.LoopEstimator(self.estimation.enabled, self.estimation.rotor_state,
                                              self.observer.params, self.observer.state)
        trace = flight_loop.LoopTrace(a.states, a.published, a.actuators, a.control, a.estimates)
        measurement = Measurement(unmeasured(self.plant.params), self.plant.params, self.plant.core_state,
                                  a.rotor_rows, a.acc)
        return flight_loop.fly(
            flight_loop.LoopPlant(self.plant.params, self.plant.core_state),
            flight_loop.LoopController(self.controller.params, self.controller.state), estimator, first, last,
            self.steps, self.period_ns, self.control_bounds, flight_loop.RECORD, trace, measurement)

    def flown(self, outcome: int, k: int) -> int:
        """How many states ``fly`` has recorded when it returned ``(outcome, k)`` (rows ``0..flown-1``)."""
        return k + 1 if outcome != flight_loop.CONTROLLER_FAILED else k

    def end(self, outcome: int, k: int, detail: int) -> tuple[str, str] | None:
        """``(end_reason, reason)`` of a divergence, a loss of control or a failed law (``fly``'s outcome), None
        otherwise."""
        if outcome == flight_loop.LOST_CONTROL:
            a = self.arrays
            return DIVERGED, loss_reason(detail, self.simulation.divergence, a.states[k],
                                         a.control[k, REFERENCE_POSITION:REFERENCE_POSITION + 3],
                                         a.control[k, COMMANDED_QUATERNION:COMMANDED_QUATERNION + 4],
                                         k * self.period_ns * 1e-9)
        if outcome == flight_loop.DIVERGED:
            return DIVERGED, divergence_reason(detail, self.plant.params, self.plant.core_state)
        if outcome == flight_loop.CONTROLLER_FAILED:
            return DIVERGED, f"no command at t = {k * self.period_ns * 1e-9:.4f} s: {ATTITUDE_ERRORS[detail]}"
        return None

    def run(self, count: int, end_reason: str, reason: str, wall: float, interrupted: bool = False,
            startup: float | None = None, copy: bool = True) -> FlightRun:
        """The :class:`FlightRun` of rows ``0..count-1`` (``copy=False``: views of the arrays where it can)."""
        a = self.arrays
        return flight_run(self, a.states[:count], a.published[:count], a.control[:count],
                          a.estimates[:count] if self.estimation.enabled else None, end_reason, reason, wall,
                          interrupted, startup, a.actuators[:count], copy)


@dataclass
class FlightArrays:
    """The rows the compiled loop writes for ``size`` states of a vehicle with ``rotors`` rotors (reused by the
    flights of a sweep: ``fits``)."""

    states: np.ndarray  # (size, 13)
    published: np.ndarray  # (size, PUBLISHED_SIZE): odom, wrench_truth and imu (fsr_sim.core.odometry)
    actuators: np.ndarray  # (size, 2 rotors): the rotors' actual speeds and tilts (rotor_state)
    control: np.ndarray  # (size, controller output): the controller's output row
    estimates: np.ndarray  # (size, 7)
    rotor_rows: np.ndarray  # (ROTOR_ROWS, rotors), acc (new_accumulators): the loop's measurement scratch (unused here)
    acc: np.ndarray

    @classmethod
    def make(cls, size: int, rotors: int) -> FlightArrays:
        return cls(np.zeros((size, 13)), np.zeros((size, PUBLISHED_SIZE)), np.zeros((size, 2 * rotors)),
                   np.zeros((size, control_layout.output_size(rotors))), np.zeros((size, 7)),
                   np.zeros((ROTOR_ROWS, rotors)), new_accumulators())

    def fits(self, size: int, rotors: int) -> bool:
        return len(self.states) >= size and self.actuators.shape[1] == 2 * rotors


def prepare_flight(scenario: Any, max_steps: int | None = None, arrays: FlightArrays | None = None) -> FlightSetup:
    """Validate ``scenario`` (a :class:`Scenario`, or the runner's checked scenario holding one) into the packed
    objects of one flight of its duration (or ``max_steps``), writing into ``arrays`` if they fit."""
    from fsr_estimation.config.estimator_config import estimator_config
    from fsr_estimation.estimator.observer import MomentumObserver

    scenario = getattr(scenario, "scenario", scenario)
    sim = simulation_config(scenario)
    config = controller_config(scenario)
    estimation = estimator_config(scenario)
    plant = plant_from_config(sim)
    controller = FlightController(config, sim.vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
    observer = MomentumObserver(estimation.mass, estimation.inertia, estimation.c0, estimation.r,
                                sim.control_period) if estimation.enabled else MomentumObserver(1.0, (1, 1, 1),
                                                                                               1.0, 1, 1.0)
    steps = sim.step_count if max_steps is None else min(sim.step_count, int(max_steps))
    n = sim.vehicle.rotor_count
    if arrays is None or not arrays.fits(steps + 1, n):
        arrays = FlightArrays.make(steps + 1, n)
    return FlightSetup(scenario, sim, estimation, plant, controller, observer, steps,
                       int(round(sim.control_period * 1e9)), arrays)


def fly_in_process(scenario: Any, recording: Path | None = None, max_steps: int | None = None,
                   stop: Callable[[], str | None] | None = None,
                   progress: Callable[[float, float], None] | None = None,
                   record_topics: frozenset[str] | None = None, live: LiveServer | None = None) -> FlightRun:
    """Fly ``scenario`` (a :class:`Scenario`, or the runner's checked scenario holding one) in one process.

    ``recording``: write the MCAP file there. ``max_steps``: stop after that many steps (default: the
    scenario's duration). ``stop``: polled between chunks of steps; a signal name (e.g. ``"SIGINT"``) ends the
    flight there (``end_reason`` ``stopped``, ``interrupted``). A KeyboardInterrupt (Ctrl-C in a notebook)
    ends it too, at the end of the chunk being flown. ``progress``: called after each chunk with the
    simulated time [s] of the last state flown and the wall time [s] the loop has taken. ``record_topics``:
    record only these (:func:`fsr_sim.contract.recording_selection`; None: all). ``live``: serve what is
    recorded there as it is flown (:class:`fsr_bringup.live.server.LiveServer`), paced at the scenario's
    ``lockstep.real_time_factor`` (:mod:`fsr_bringup.live.pacing`).
    """
    setup = prepare_flight(scenario, max_steps)
    sim, steps, period_ns, a = setup.simulation, setup.steps, setup.period_ns, setup.arrays
    n = sim.vehicle.rotor_count
    recorder = pace = None
    if recording is not None or live is not None:
        from fsr_bringup.recording.flight_recording import InProcessRecorder

        recorder = InProcessRecorder(None if recording is None else Path(recording), setup.scenario.dump(),
                                     setup.rotors, n, sim.vehicle.has_servos, record_topics, setup.actuator_dynamics,
                                     setup.plant.params.sensors.imu, live, setup.odometry_measured)
    end_reason, reason, interrupted = FINISHED, f"reached the scenario duration {sim.duration:g} s", False
    if steps < sim.step_count:
        reason = f"stopped after {steps} steps"
    startup = process_age()
    start = time.perf_counter()
    count = 0  # steps flown and recorded (rows 0..count-1)
    if live is not None:
        from fsr_bringup.live.pacing import LivePace

        pace = LivePace(sim.control_period, sim.real_time_factor)
    chunk = CHUNK_STEPS if pace is None else pace.chunk_steps
    try:
        if recorder is not None:
            recorder.status(0, RUNNING, "", 0)
        outcome = flight_loop.GOING_ON
        while outcome == flight_loop.GOING_ON:
            signal_name = stop() if stop is not None else None
            if signal_name:
                raise _Stopped(signal_name)
            outcome, k, detail = setup.fly(count, min(count + chunk - 1, steps))
            flown = setup.flown(outcome, k)
            if recorder is not None and flown > count:
                recorder.write_steps(np.arange(count, flown, dtype=np.int64) * period_ns, a.published[count:flown],
                                     a.control[count:flown],
                                     a.estimates[count:flown] if setup.estimation.enabled else None,
                                     a.actuators[count:flown])
                if live is not None:
                    live.start()  # every topic of the flight is known now (the server's clients see them all)
            count = flown
            if progress is not None and count:
                progress((count - 1) * period_ns * 1e-9, time.perf_counter() - start)
            end_reason, reason = setup.end(outcome, k, detail) or (end_reason, reason)
            if pace is not None and count:
                pace.wait_for(count - 1)
    except KeyboardInterrupt as stopped:  # Ctrl-C (fsr-fly also turns SIGTERM into one)
        end_reason, reason, interrupted = STOPPED, f"received {getattr(stopped, 'signal_name', 'SIGINT')}", True
    finally:
        if recorder is not None:
            try:
                recorder.status(max(count - 1, 0) * period_ns, end_reason, reason, max(count - 1, 0))
            finally:
                recorder.close()
    run = setup.run(count, end_reason, reason, time.perf_counter() - start, interrupted, startup)
    run.recording = None if recording is None else Path(recording)
    return run


def flight_run(setup: FlightSetup, states: np.ndarray, published: np.ndarray, control: np.ndarray,
               estimates: np.ndarray | None, end_reason: str, reason: str, wall: float, interrupted: bool,
               startup: float | None, actuators: np.ndarray, copy: bool = True) -> FlightRun:
    """The :class:`FlightRun` of the flight loop's arrays (rows 0..K); ``copy=False``: views of them where it
    can (the state is always a copy), valid until the arrays are written again."""
    count = len(states)
    n = (control.shape[1] - control_layout.ROTOR_SPEEDS) // 2
    rotors = setup.rotors
    tilting = rotors and setup.simulation.vehicle.has_servos
    controller = setup.controller
    state = states.copy()
    state[state[:, 9] < 0.0, 6:10] *= -1.0  # odom's sign (w >= 0); the true state, not odom's measurement

    def columns(at: int, width: int = 3) -> np.ndarray:
        return control[:, at:at + width].copy() if copy else control[:, at:at + width]

    def own(values: np.ndarray) -> np.ndarray:
        return values.copy() if copy else values

    def imu(at: int) -> np.ndarray | None:
        return own(published[:, at:at + 3]) if setup.imu else None

    failures = {DIVERGED: [f"flight diverged: {reason}"], STOPPED: [f"flight interrupted ({reason})"]}
    plan_end = controller.trajectory.end_time if controller.trajectory is not None else None
    end_time = (count - 1) * setup.period_ns * 1e-9
    notes = [mid_path_note(end_time, plan_end)] if count and mid_path(end_reason, end_time, plan_end) else []
    c = control_layout
    return FlightRun(
        time=np.arange(count, dtype=np.int64) * setup.period_ns * 1e-9, state=state,
        reference_position=columns(c.REFERENCE_POSITION), reference_velocity=columns(c.REFERENCE_VELOCITY),
        reference_acceleration=columns(c.REFERENCE_ACCELERATION),
        reference_rotation=columns(c.REFERENCE_ROTATION, 9).reshape(count, 3, 3), force_cmd=columns(c.FORCE),
        torque_cmd=columns(c.TORQUE), rotor_speeds=columns(c.ROTOR_SPEEDS, n) if rotors else None,
        tilt_angles=columns(c.ROTOR_SPEEDS + n, n) if tilting else None,
        actual_rotor_speeds=own(actuators[:, :n]) if rotors else None,
        actual_tilt_angles=own(actuators[:, n:]) if tilting else None,
        external_force_body=own(published[:, TRUTH_FORCE:TRUTH_FORCE + 3]),
        external_torque_body=own(published[:, TRUTH_TORQUE:TRUTH_TORQUE + 3]),
        estimate_force_body=None if estimates is None else own(estimates[:, 0:3]),
        estimate_torque_body=None if estimates is None else own(estimates[:, 3:6]),
        mass_estimate=None if estimates is None else own(estimates[:, 6]),
        saturation=controller.saturation.as_dict(), tilt_saturation=controller.tilt_saturation.as_dict(),
        end_reason=end_reason, reason=reason, wall_time=wall,
        rotation_commanded=columns(c.COMMANDED_ROTATION, 9).reshape(count, 3, 3),
        force_desired=columns(c.DESIRED_FORCE), torque_desired=columns(c.DESIRED_TORQUE), scenario=setup.scenario,
        failures=failures.get(end_reason, []), interrupted=interrupted,
        compensation=controller.compensation_summary(), startup_time=startup,
        plan_adjustments=[item.text() for item in controller.plan_adjustments],
        reference_angular_velocity_world=columns(c.REFERENCE_ANGULAR_VELOCITY_WORLD),
        wrench_shortfall=columns(c.SHORTFALL, 6), simulation=setup.simulation, estimator=setup.estimation,
        actuator_dynamics=setup.actuator_dynamics, imu_angular_velocity_measured=imu(IMU_ANGULAR_VELOCITY),
        imu_specific_force_measured=imu(IMU_LINEAR_ACCELERATION),
        imu_specific_force_true=imu(IMU_TRUE_LINEAR_ACCELERATION),
        odometry_measured=own(published[:, :ODOM_SIZE]) if setup.odometry_measured else None,
        odometry_true=own(published[:, TRUE_ODOM:TRUE_ODOM + ODOM_SIZE]) if setup.odometry_measured else None,
        plan_kind=controller.config.trajectory_kind,
        plan_end_time=plan_end, notes=notes,
    )
