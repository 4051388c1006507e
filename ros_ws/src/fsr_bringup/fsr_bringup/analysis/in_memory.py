"""A flight flown in this process (:class:`fsr_bringup.runner.in_process_flight.FlightRun`) as the analysis'
:class:`fsr_bringup.analysis.load.RecordedFlight`, without writing or reading a recording: the metrics of
:mod:`fsr_bringup.analysis.metrics` then apply to it as they are.

The topics are filled with what the graph would publish at each step ``t_k``: ``odom`` as published (the
measurement when a sensor stage is on, with the true state on ``odom_truth`` beside it, as the recording holds
them), so the metrics of a flight in memory and of its recording are the same.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fsr_bringup.analysis.load import (
    LOADERS,
    Attitude,
    Imu,
    Odometry,
    RecordedFlight,
    RecordingName,
    Reference,
    RotorCommand,
    Scalar,
    Wrench,
    controller_side,
)
from fsr_sim.contract import SimStatus, resolve
from fsr_sim.model.so3 import rotations_from_quaternions


def measured_odometry(stamp_ns: np.ndarray, t: np.ndarray, rows: np.ndarray) -> Odometry:
    """The :class:`Odometry` of published ``odom`` (or ``odom_truth``) rows (K, 13): position, quaternion
    ``[x, y, z, w]``, velocity body, angular velocity body (:mod:`fsr_sim.core.odometry`), as the analysis reads
    them from a recording."""
    rotation = rotations_from_quaternions(rows[:, 3:7])
    return Odometry(stamp_ns, t, rows[:, 0:3], rows[:, 3:7], rotation, np.einsum("nij,nj->ni", rotation, rows[:, 7:10]),
                    rows[:, 10:13])


def recorded_flight_of_run(run, recording: Path | None = None) -> RecordedFlight:  # noqa: ANN001 - a FlightRun
    """The topics of ``run`` at its states' stamps (module docstring); ``run`` must come from
    :func:`fsr_bringup.api.simulate` or a sweep (it carries its validated configs). ``recording``: the file the
    flight was recorded into (named in the metrics and the figures, not read)."""
    if run.simulation is None:
        raise ValueError("this run carries no validated scenario (fly it with fsr_bringup.simulate)")
    sim = run.simulation
    stamp_ns = np.rint(run.time * 1e9).astype(np.int64)
    t = run.time
    rotation = run.rotation
    flight = RecordedFlight(None if recording is None else RecordingName(Path(recording)),  # type: ignore[arg-type]
                            "/", sim.name, sim, run.estimator)
    flight.plan = {"kind": run.plan_kind, "end_s": run.plan_end_time} if run.plan_end_time is not None else None
    flight.sim_status = [SimStatus(run.end_reason, run.reason, float(t[-1]) if len(t) else 0.0, max(len(t) - 1, 0))]
    if run.scenario is not None:  # the controller's side as a recording's metadata gives it
        (flight.compensation_mode, flight.compensation, flight.plan_adjustments, flight.plan,
         flight.controller) = controller_side(run.scenario, flight.notes)
    true = Odometry(stamp_ns, t, run.position, run.state[:, 6:10], rotation, run.velocity, run.angular_velocity)
    flight.odom = true
    if run.odometry_measured is not None:  # odom is the measurement: the true state is odom_truth (its numbers,
        # read as a recording's are)
        flight.odom = measured_odometry(stamp_ns, t, run.odometry_measured)
        flight.odom_truth = measured_odometry(stamp_ns, t, run.odometry_true)
    # the metrics read the attitudes as rotation matrices: the quaternions are not made (None)
    flight.reference = Reference(stamp_ns, t, run.reference_position, None, run.reference_rotation,  # type: ignore[arg-type]
                                 run.reference_velocity, run.reference_acceleration,
                                 run.reference_angular_velocity_world)
    flight.attitude_cmd = Attitude(stamp_ns, t, None, run.rotation_commanded)  # type: ignore[arg-type]
    flight.wrench_truth = Wrench(stamp_ns, t, run.external_force_body, run.external_torque_body)
    flight.wrench_cmd = Wrench(stamp_ns, t, run.force_cmd, run.torque_cmd)
    flight.wrench_desired = Wrench(stamp_ns, t, run.force_desired, run.torque_desired)
    flight.wrench_shortfall = Wrench(stamp_ns, t, run.wrench_shortfall[:, :3], run.wrench_shortfall[:, 3:])
    if run.rotor_speeds is not None:
        flight.rotor_cmd = RotorCommand(stamp_ns, t, run.rotor_speeds, run.tilt_angles)
        if run.actuator_dynamics:
            flight.rotor_state = RotorCommand(stamp_ns, t, run.actual_rotor_speeds, run.actual_tilt_angles)
    if run.imu_specific_force_measured is not None:
        flight.imu = Imu(stamp_ns, t, run.imu_angular_velocity_measured, run.imu_specific_force_measured)
    if run.estimate_force_body is not None:
        flight.wrench_estimate = Wrench(stamp_ns, t, run.estimate_force_body, run.estimate_torque_body)
        flight.mass_estimate = Scalar(stamp_ns, t, run.mass_estimate)
    for topic in LOADERS:  # what a recording of it holds: a message per state on each topic flown
        name = resolve(topic.name, "/")
        present = getattr(flight, topic.name) is not None
        flight.message_counts[name] = len(t) if present else 0
        if not present:
            flight.notes.append(f"no messages on {name}")
    return flight
