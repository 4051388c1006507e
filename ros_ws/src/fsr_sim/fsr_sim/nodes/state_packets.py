"""The simulator's per-step messages as packed CDR bytes (what the simulator node publishes and an in-process
recording writes): ``odom``, ``wrench_truth``, ``/clock``, (with actuator dynamics) ``rotor_state`` and (with an
IMU) ``imu`` of one state; :func:`joint_state_template` and :func:`joint_values` lay out ``rotor_state`` and
``rotor_cmd`` alike.

The values are the published row of the compiled core (:mod:`fsr_sim.core.odometry`: ``odom``, then
``wrench_truth`` force ``R^T f_ext,world`` and torque, then ``imu``'s angular velocity and specific force), the
same as :class:`fsr_sim.nodes.state_messages.StateMessages`; the bytes are :mod:`fsr_sim.ros.cdr_pack`'s (no
rclpy needed).
"""

from __future__ import annotations

import numpy as np

from fsr_sim.contract import IMU, ODOM, ODOM_TRUTH, ROTOR_STATE, WRENCH_TRUTH, joint_names
from fsr_sim.core.odometry import IMU_ANGULAR_VELOCITY, IMU_END, ODOM_SIZE, TRUE_ODOM, WRENCH_TRUTH_END
from fsr_sim.core.sensors import ImuParams
from fsr_sim.model.odometry import published_row
from fsr_sim.ros import cdr_pack


def joint_state_template(frame_id: str, rotor_count: int, tilting: bool) -> cdr_pack.StampedDoubles:
    """The ``sensor_msgs/JointState`` of the rotors (:func:`fsr_sim.contract.joint_names`): a position and a
    velocity per joint."""
    names = joint_names(rotor_count, tilting)
    return cdr_pack.joint_state(frame_id, names, len(names), len(names))


def imu_template(params: ImuParams) -> cdr_pack.StampedDoubles:
    """The ``sensor_msgs/Imu`` of an IMU stage: covariances the variances of its white noise per sample."""
    variances = [std * std for std in params.noise_std]
    return cdr_pack.imu(IMU.frame, variances[:3], variances[3:])


def joint_values(speeds: np.ndarray, tilts: np.ndarray | None) -> np.ndarray:
    """The numbers of :func:`joint_state_template` for rotor speeds (..., n) [rad/s] and tilts (..., n) [rad]
    (None: fixed rotors): positions (0 for a rotor, the tilt for a tilt joint), then velocities (the speed for
    a rotor, 0 for a tilt joint)."""
    zeros = np.zeros_like(speeds)
    if tilts is None:
        return np.concatenate((zeros, speeds), axis=-1)
    return np.concatenate((zeros, tilts, speeds, zeros), axis=-1)


class StatePackets:
    """Packs the state stamped ``stamp_ns``: after :meth:`fill_from_row`, ``odom``, ``wrench``, ``clock``,
    (with an IMU) ``imu`` and (``odom_truth``) ``truth`` hold the CDR payloads of ``odom``, ``wrench_truth``,
    ``/clock``, ``imu`` and ``odom_truth``. ``rotor_count`` > 0: ``rotor_state`` too (:meth:`rotor_state`);
    ``imu``: the IMU stage (None or disabled: no ``imu``); ``odom_truth``: ``odom`` is measured (a sensor stage
    on), the true state is published beside it."""

    def __init__(self, rotor_count: int = 0, tilting: bool = False, imu: ImuParams | None = None,
                 odom_truth: bool = False) -> None:
        self._odom = cdr_pack.odometry(ODOM.frame, ODOM.child_frame)
        self._wrench = cdr_pack.wrench_stamped(WRENCH_TRUTH.frame)
        self._clock = cdr_pack.clock()
        self.templates = {ODOM.name: self._odom, WRENCH_TRUTH.name: self._wrench}  # topic (relative) -> template
        self.tilting = tilting
        if rotor_count:
            self.templates[ROTOR_STATE.name] = joint_state_template(ROTOR_STATE.frame, rotor_count, tilting)
        self._imu = imu_template(imu) if imu is not None and imu.enabled else None
        if self._imu is not None:
            self.templates[IMU.name] = self._imu
        self._truth = cdr_pack.odometry(ODOM_TRUTH.frame, ODOM_TRUTH.child_frame) if odom_truth else None
        if self._truth is not None:
            self.templates[ODOM_TRUTH.name] = self._truth
        self.odom = self.wrench = self.clock = self.imu = self.truth = b""
        self.stamp_ns = -1

    def fill_from(self, stamp_ns: int, state_vector: np.ndarray,
                  external: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Pack the messages of a state vector (13,) and the true external wrench (force world [N], torque
        body [N m]; None: zero) at ``stamp_ns`` [ns]."""
        self.fill_from_row(stamp_ns, published_row(state_vector, external))

    def fill_from_row(self, stamp_ns: int, row: np.ndarray) -> None:
        """Pack a published row of :mod:`fsr_sim.core.odometry` at ``stamp_ns`` [ns]."""
        values = row.tolist()
        self.odom = self._odom.pack(stamp_ns, values[:ODOM_SIZE])
        self.wrench = self._wrench.pack(stamp_ns, values[ODOM_SIZE:WRENCH_TRUTH_END])
        if self._imu is not None:
            self.imu = self._imu.pack(stamp_ns, values[IMU_ANGULAR_VELOCITY:IMU_END])
        if self._truth is not None:
            self.truth = self._truth.pack(stamp_ns, values[TRUE_ODOM:TRUE_ODOM + ODOM_SIZE])
        self.clock = self._clock.pack(stamp_ns, ())
        self.stamp_ns = stamp_ns

    def rotor_state(self, stamp_ns: int, speeds: np.ndarray, tilts: np.ndarray) -> bytes:
        """The ``rotor_state`` payload of the rotors' actual speeds (n,) [rad/s] and tilts (n,) [rad]."""
        values = joint_values(speeds, tilts if self.tilting else None)
        return self.templates[ROTOR_STATE.name].pack(stamp_ns, values.tolist())
