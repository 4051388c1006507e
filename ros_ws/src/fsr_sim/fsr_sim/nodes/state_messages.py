"""The simulator's outgoing messages as rclpy objects, allocated once and refilled from the plant at every step
(the reference for :class:`fsr_sim.nodes.state_packets.StatePackets`, whose packed CDR bytes the node publishes).

* ``odom`` (nav_msgs/Odometry): pose in ``world_ned``, twist in ``base_link_frd`` (linear ``R^T v_world``
  [m/s], angular ``omega_b`` [rad/s]); orientation is the plant's unit quaternion ``[x, y, z, w]`` with
  ``w >= 0`` (the same rotation as ``-q``; the sign is fixed so consecutive messages are comparable).
* ``wrench_truth`` (geometry_msgs/WrenchStamped): the true external wrench in ``base_link_frd``,
  force ``R^T f_ext,world`` [N] and torque ``tau_ext,body`` [N m].
* ``/clock`` (rosgraph_msgs/Clock): the simulated time of the state.

Every stamp is the physics time ``t_k`` of the state, in exact integer nanoseconds (``Plant.stamp_ns``). The
numbers are the core's published row (:func:`fsr_sim.model.odometry.published_row`).
"""

from __future__ import annotations

import numpy as np
from geometry_msgs.msg import WrenchStamped
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock

from fsr_sim.contract import ODOM, WRENCH_TRUTH
from fsr_sim.core.odometry import WRENCH_TRUTH_END
from fsr_sim.model.odometry import published_row
from fsr_sim.model.plant import Plant

NS_PER_S = 1_000_000_000


class StateMessages:
    """Preallocated ``Odometry``, ``WrenchStamped`` and ``Clock`` filled by :meth:`fill`."""

    def __init__(self, plant: Plant | None = None) -> None:
        self.plant = plant
        self.odom = Odometry()
        self.odom.header.frame_id = ODOM.frame
        self.odom.child_frame_id = ODOM.child_frame
        self.wrench = WrenchStamped()
        self.wrench.header.frame_id = WRENCH_TRUTH.frame
        self.clock = Clock()
        self.has_disturbances = plant is not None and bool(plant.disturbances)
        self.stamp_ns = -1

    def fill(self) -> None:
        """Refill all three messages with the plant's current state and time."""
        plant = self.plant
        external = plant.external_wrench() if self.has_disturbances else None
        self.fill_from(plant.stamp_ns, plant.state_vector, external)

    def fill_from(self, stamp_ns: int, state_vector: np.ndarray,
                  external: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Refill the messages from a state vector (13,) and the true external wrench (force world [N], torque
        body [N m]; None: zero) at ``stamp_ns``: the simulator's conversion, also used to record a flight."""
        sec, nanosec = divmod(stamp_ns, NS_PER_S)
        x, y, z, qx, qy, qz, qw, vbx, vby, vbz, wx, wy, wz, fx, fy, fz, tx, ty, tz = published_row(
            state_vector, external)[:WRENCH_TRUTH_END].tolist()

        odom = self.odom
        odom.header.stamp.sec = sec
        odom.header.stamp.nanosec = nanosec
        position = odom.pose.pose.position
        position.x, position.y, position.z = x, y, z
        orientation = odom.pose.pose.orientation
        orientation.x, orientation.y, orientation.z, orientation.w = qx, qy, qz, qw
        twist = odom.twist.twist
        twist.linear.x, twist.linear.y, twist.linear.z = vbx, vby, vbz
        twist.angular.x, twist.angular.y, twist.angular.z = wx, wy, wz

        wrench = self.wrench
        wrench.header.stamp.sec = sec
        wrench.header.stamp.nanosec = nanosec
        w = wrench.wrench
        w.force.x, w.force.y, w.force.z = fx, fy, fz
        w.torque.x, w.torque.y, w.torque.z = tx, ty, tz

        self.clock.clock.sec = sec
        self.clock.clock.nanosec = nanosec
        self.stamp_ns = stamp_ns

    def is_finite(self) -> bool:
        """False when the plant state holds NaN/inf (such a state is never published)."""
        return bool(np.isfinite(self.plant.state_vector).all())
