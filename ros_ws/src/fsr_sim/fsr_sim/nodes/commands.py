"""Decoding and checking the commands the simulator receives (per step, so kept lean).

* ``rotor_cmd`` (sensor_msgs/JointState): ``rotor_i`` velocity [rad/s], ``tilt_i`` position [rad].
* ``wrench_cmd`` (geometry_msgs/WrenchStamped, body FRD): the wrench-actuated plant applies the body force
  [N] and torque [N m] as they are (docs/model.md §3.1), as the in-process loop does with the controller's
  wrench; a thrust-only controller sends ``force = [0, 0, -u_T]``.

A command holding NaN/inf (or missing a rotor) raises ``ValueError``; the node drops it with a warning so
it never reaches the plant. The simulator reads the commands from their CDR bytes (:meth:`RotorCommandReader.
read_raw`, :func:`wrench_command_raw`): the same numbers as from the message objects, without building them.
"""

from __future__ import annotations

import math

import numpy as np

from fsr_sim.contract import WRENCH_CMD, joint_names
from fsr_sim.ros import cdr_read
from fsr_sim.ros.conversions import finite_rotor_command, rotor_command_arrays


class RotorCommandReader:
    """``JointState`` -> (speeds [rad/s], tilts [rad] or None); fast when the names are in the usual order."""

    def __init__(self, rotor_count: int, tilting: bool) -> None:
        self.rotor_count = rotor_count
        self._plain_names = joint_names(rotor_count, tilting=False)
        self._tilt_names = joint_names(rotor_count, tilting=True) if tilting else None
        self._plain_reader = cdr_read.JointStateReader(self._plain_names)
        self._tilt_reader = cdr_read.JointStateReader(self._tilt_names) if tilting else None

    def read_raw(self, data: bytes) -> tuple[np.ndarray, np.ndarray | None]:
        """:meth:`read` of a message's CDR bytes (names in the usual order: read in place; else decoded)."""
        n = self.rotor_count
        speeds = tilts = None
        plain = self._plain_reader.read(data)
        if plain is not None and len(plain[2]) >= n:
            speeds = np.array(plain[2][:n], dtype=float)
        elif self._tilt_reader is not None:
            tilted = self._tilt_reader.read(data)
            if tilted is not None and len(tilted[2]) >= n and len(tilted[1]) >= 2 * n:
                speeds = np.array(tilted[2][:n], dtype=float)
                tilts = np.array(tilted[1][n : 2 * n], dtype=float)
        if speeds is None:
            from rclpy.serialization import deserialize_message
            from sensor_msgs.msg import JointState

            return self.read(deserialize_message(data, JointState))
        return finite_rotor_command(speeds, tilts)

    def read_stamped(self, data: bytes) -> tuple[int, np.ndarray, np.ndarray | None]:
        """:meth:`read_raw` with the header's stamp [ns] (``rotor_state`` as the controller and estimator take it)."""
        return (cdr_read.stamp(data), *self.read_raw(data))

    def read(self, msg: object) -> tuple[np.ndarray, np.ndarray | None]:
        n = self.rotor_count
        names = msg.name
        if names == self._plain_names and len(msg.velocity) >= n:
            speeds, tilts = np.array(msg.velocity[:n], dtype=float), None
        elif names == self._tilt_names and len(msg.velocity) >= n and len(msg.position) >= 2 * n:
            speeds = np.array(msg.velocity[:n], dtype=float)
            tilts = np.array(msg.position[n : 2 * n], dtype=float)
        else:
            return rotor_command_arrays(msg, n)  # any order; raises ValueError naming what is missing
        return finite_rotor_command(speeds, tilts)


def wrench_command(msg: object) -> np.ndarray:
    """``WrenchStamped`` (body FRD) -> body wrench (6,): force [N], torque [N m]; ValueError if not finite."""
    f, t = msg.wrench.force, msg.wrench.torque
    return _finite_wrench((f.x, f.y, f.z, t.x, t.y, t.z))


def wrench_command_raw(data: bytes) -> np.ndarray:
    """:func:`wrench_command` of a message's CDR bytes."""
    return _finite_wrench(cdr_read.wrench_stamped(data)[1])


def _finite_wrench(wrench: tuple[float, ...]) -> np.ndarray:
    """(force xyz, torque xyz) as an array; ValueError if any value is NaN or inf."""
    if not all(map(math.isfinite, wrench)):
        raise ValueError(f"{WRENCH_CMD.name} holds NaN or inf")
    return np.array(wrench[:6], dtype=float)
