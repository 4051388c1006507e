"""Geometric (SE(3)) controller for fixed-rotor multirotors (Lee et al.; report exercise 4, SPEC §3.6).

World NED, body FRD, ``e3 = [0, 0, 1]`` (down), ``g = 9.81``:

    e_p = p - p_d,   e_v = v - v_d                                   (world)
    a   = -K_p e_p - K_v e_v - m g e3 + m p_ddot_d                   [N]
    u_T = -a^T R_b e3,   z_bd = -a / |a|                             (thrust [N] along -z_b)
    y_bd = (z_bd x x_c) / |z_bd x x_c|,  x_bd = y_bd x z_bd,  x_c = [cos psi_d, sin psi_d, 0]
    e_R = vee(R_d^T R_b - R_b^T R_d) / 2,   e_w = w_b - R_b^T R_d w_d
    tau_b = -K_R e_R - K_w e_w + S(w_b) I_b w_b - I_b (S(w_b) R_b^T R_d w_d - R_b^T R_d w_dot_d)   [N m]

``w_d`` and ``w_dot_d`` are the exact rates of this ``R_d`` (:mod:`fsr_control.planning.flatness`): with
``a_dot = -K_p e_v - K_v e_a + m p_dddot_d`` and ``a_ddot = -K_p e_a - K_v e_j + m p_ddddot_d``, where the
acceleration error ``e_a`` uses the acceleration measured by differencing consecutive velocities (the
model's ``g e3 - u_T R_b e3 / m`` would miss unmodelled forces: with a constant disturbance it predicts
an acceleration that never comes and keeps ``R_d`` turning) and the jerk error ``e_j`` the model's
``p_dddot = -(u_T_dot R_b e3 + u_T R_b S(w_b) e3) / m`` (zero at any equilibrium). Without the
feedback part of these rates (only the reference's) the attitude loop lags the outer loop and, with the
report's gains and the exercise-4 inertia (1.24 kg m^2), the lateral loop is unstable:
``1.49 s^4 + 12 s^3 + 12 s^2 + 200 s + 200`` fails Routh's test. The controller uses the nominal model (mass, inertia).
Report gains: ``K_p = K_v = diag(20, 20, 100)``, ``K_R = K_w = diag(10, 10, 100)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_control.controllers._vec import cross3
from fsr_control.planning.flatness import attitude_from_thrust_vector
from fsr_control.planning.trajectory import Reference
from fsr_sim.model.so3 import attitude_error
from fsr_sim.model.vehicle import GRAVITY, Vehicle

REPORT_GAINS = {
    "k_p": np.diag((20.0, 20.0, 100.0)),
    "k_v": np.diag((20.0, 20.0, 100.0)),
    "k_r": np.diag((10.0, 10.0, 100.0)),
    "k_w": np.diag((10.0, 10.0, 100.0)),
}


@dataclass
class GeometricCommand:
    """Thrust ``u_T`` [N] along ``-z_b``, body torque [N m], and the desired attitude used."""

    thrust: float
    torque_body: np.ndarray
    rotation_desired: np.ndarray


class GeometricController:
    """``compute(reference, state) -> GeometricCommand`` with the equations of the module docstring."""

    def __init__(self, vehicle: Vehicle, gains: dict[str, np.ndarray]) -> None:
        self.mass = vehicle.mass
        self.inertia = np.array(vehicle.inertia, dtype=float)
        self.k_p, self.k_v = np.asarray(gains["k_p"], float), np.asarray(gains["k_v"], float)
        self.k_r, self.k_w = np.asarray(gains["k_r"], float), np.asarray(gains["k_w"], float)
        self._weight = np.array((0.0, 0.0, self.mass * GRAVITY))
        self._gravity = np.array((0.0, 0.0, GRAVITY))
        self._previous: tuple[float, np.ndarray] | None = None  # (t [s], velocity world [m/s])

    def compute(
        self,
        reference: Reference,
        position: np.ndarray,
        rotation: np.ndarray,
        velocity_world: np.ndarray,
        angular_velocity_body: np.ndarray,
    ) -> GeometricCommand:
        m = self.mass
        e_p = position - reference.position
        e_v = velocity_world - reference.velocity
        a = -(self.k_p @ e_p) - self.k_v @ e_v - self._weight + m * reference.acceleration
        z_b = rotation[:, 2]
        thrust = -float(a @ z_b)
        # R_d and its rates: differentiate a with the model-predicted acceleration and jerk of this thrust.
        w = angular_velocity_body
        wx, wy, _ = w.tolist()
        z_b_dot = rotation @ np.array((wy, -wx, 0.0))  # R S(w) e3
        e_a = self._measured_acceleration(reference.time, velocity_world, thrust, z_b) - reference.acceleration
        a_dot = -(self.k_p @ e_v) - self.k_v @ e_a + m * reference.jerk
        thrust_dot = -float(a_dot @ z_b) - float(a @ z_b_dot)
        e_j = -(thrust_dot * z_b + thrust * z_b_dot) / m - reference.jerk
        a_ddot = -(self.k_p @ e_a) - self.k_v @ e_j + m * reference.snap
        rotation_desired, omega_d, omega_dot_d = attitude_from_thrust_vector(
            -a, -a_dot, -a_ddot, reference.yaw, reference.yaw_rate, reference.yaw_acceleration
        )
        relative = rotation.T @ rotation_desired  # R_b^T R_d
        e_r = attitude_error(rotation, rotation_desired)
        omega_d_body = relative @ omega_d
        e_w = w - omega_d_body
        inertia = self.inertia
        torque = (
            -(self.k_r @ e_r)
            - self.k_w @ e_w
            + cross3(w, inertia @ w)
            - inertia @ (cross3(w, omega_d_body) - relative @ omega_dot_d)
        )
        return GeometricCommand(thrust, torque, rotation_desired)

    def _measured_acceleration(self, t: float, velocity_world: np.ndarray, thrust: float, z_b: np.ndarray
                               ) -> np.ndarray:
        """Acceleration [m/s^2] from consecutive velocities (includes unmodelled forces); the model's
        ``g e3 - u_T z_b / m`` at the first step or when time does not advance."""
        previous = self._previous
        self._previous = (t, velocity_world.copy())
        if previous is not None and t > previous[0]:
            return (velocity_world - previous[1]) / (t - previous[0])
        return self._gravity - (thrust / self.mass) * z_b
