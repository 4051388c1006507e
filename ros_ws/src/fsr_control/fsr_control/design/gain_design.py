"""Loop gains designed from a vehicle's model: its mass, inertia and the authority of its rotors at hover
(:mod:`fsr_control.design.authority`), made robust to a lagging motor and delayed onboard sensors
(docs/control.md, *Gains designed from the vehicle*).

Each loop is designed as the second-order error dynamics ``e'' + 2 zeta w e' + w^2 e = 0`` it would have
alone, ``w`` its bandwidth [rad/s] (the natural frequency), ``zeta`` = :data:`DAMPING`:

* **lag**: a first-order motor ``tau`` and a sensor delay ``d`` cost ``atan(w_c tau) + w_c d`` of phase at the
  crossover ``w_c`` (about ``1.7 w`` for ``zeta = 0.8``, where the loop alone has 70 deg of phase margin).
  Every loop is kept below ``w_lag = 1 / (LAG_FACTOR L)``, ``L = tau + d + 1 / (2 f_s)``: ``tau`` the
  larger of the vehicle's rotor and tilt time constants and :data:`DESIGN_MOTOR_TIME_CONSTANT` (30 ms), ``d``
  :data:`DESIGN_SENSOR_DELAY` (10 ms) and ``1 / (2 f_s)`` the mean age of a sample held at
  :data:`DESIGN_SENSOR_RATE` (100 Hz): 45 ms, ``w_lag = 7.4`` rad/s, which leaves about 38 deg of margin.
  A law that damps with the gyro and flies on the IMU-bridged estimate of the state (the geometric law of the
  flight profile on a vehicle with an IMU) has no odometry delay: ``L = tau + T_imu / 2`` (30.5 ms, ``w_lag
  = 10.9`` rad/s);
* **attitude** (roll and pitch): an attitude error of :data:`ATTITUDE_ERROR` (2 deg) demands at most
  :data:`AUTHORITY_SHARE` (half) of the angular acceleration the rotors give at hover about the weaker axis,
  ``w_R^2 e <= share alpha``: ``w_R = min(w_lag, sqrt(share alpha / e))``; **yaw** likewise with the yaw
  acceleration;
* **position**, vehicles that tilt to move (thrust along ``-z_b``): horizontally :data:`CASCADE_RATIO` (3)
  times slower than the attitude loop, ``w_xy = w_R / 3``, so that the attitude follows the thrust direction
  the position loop asks for (the reference feed-forward's rates assume it does); vertically, where the
  thrust acts at once, a position error of :data:`POSITION_ERROR` (0.25 m) demands at most half the vertical
  acceleration the thrust range gives (the smaller of up and down), ``w_z = min(w_lag, sqrt(share a_z / e))``;
* **position**, fully actuated vehicles (the force needs no tilt): horizontally as vertically, with the
  lateral acceleration the force set gives at level hover (the smallest of the four body directions);
* **integral**: ``K_i = (w / INTEGRAL_RATIO) K_p`` per axis, an integral 5 times slower than the loop it
  trims (``s^3 + 2 zeta w s^2 + w^2 s + w^3 / 5`` is stable for ``1 / 5 < 2 zeta``), its force bounded by
  :data:`INTEGRAL_LIMIT_SHARE` of the weight (anti-windup).

The gains in a law's units (:meth:`GainDesign.wrench_gains`, :meth:`GainDesign.acceleration_gains`) follow
from these bandwidths, the mass ``m`` and the inertia ``I``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.design.authority import Authority, ForceSet
from fsr_sim.model.vehicle import Vehicle

DAMPING = 0.8  # zeta of every loop
DESIGN_MOTOR_TIME_CONSTANT = 0.03  # s: the slowest motor the gains are designed for (a real vehicle's)
DESIGN_SENSOR_DELAY = 0.01  # s: onboard odometry's delay
DESIGN_IMU_PERIOD = 0.001  # s: the IMU's sample, at the scenarios' 1 kHz control rate
DESIGN_SENSOR_RATE = 100.0  # Hz: onboard odometry's rate (a sample is held half a period on average)
LAG_FACTOR = 3.0  # every bandwidth <= 1 / (LAG_FACTOR * total lag)
AUTHORITY_SHARE = 0.5  # of the angular / linear acceleration at hover a reference error may demand
ATTITUDE_ERROR = 0.035  # rad (2 deg): the attitude (and yaw) error that may demand AUTHORITY_SHARE
POSITION_ERROR = 0.25  # m: the position error that may demand AUTHORITY_SHARE
CASCADE_RATIO = 3.0  # attitude bandwidth / horizontal position bandwidth (vehicles that tilt to move)
INTEGRAL_RATIO = 5.0  # a loop's bandwidth / its integral's rate
INTEGRAL_LIMIT_SHARE = 0.25  # the integral's force bound, a share of the nominal weight m g


@dataclass(frozen=True)
class GainDesign:
    """The loop bandwidths designed for one vehicle (module docstring) and the gains they give.

    Attributes
    ----------
    mass : float
        Nominal mass [kg].
    inertia : numpy.ndarray, shape (3, 3)
        Nominal inertia [kg m^2] (body FRD).
    lag : float
        The total lag designed for [s] (motor, sensor delay, sample hold).
    lag_bandwidth : float
        ``1 / (LAG_FACTOR lag)`` [rad/s], the cap on every loop.
    attitude, yaw, horizontal, vertical : float
        Bandwidths [rad/s] of the roll/pitch, yaw, horizontal and vertical position loops.
    limits : dict
        What set each bandwidth: ``"lag"``, ``"authority"`` or ``"cascade"`` (the attitude loop's pace).
    damping : float
        ``zeta`` of every loop.
    integral_limit : float
        Bound [N] on the integral term's force.
    """

    mass: float
    inertia: np.ndarray
    lag: float
    lag_bandwidth: float
    attitude: float
    yaw: float
    horizontal: float
    vertical: float
    limits: dict[str, str]
    damping: float = DAMPING
    integral_limit: float = 0.0

    @property
    def position_bandwidths(self) -> np.ndarray:
        """``[w_xy, w_xy, w_z]`` [rad/s] (world NED axes)."""
        return np.array((self.horizontal, self.horizontal, self.vertical))

    @property
    def attitude_bandwidths(self) -> np.ndarray:
        """``[w_R, w_R, w_yaw]`` [rad/s] (body FRD axes)."""
        return np.array((self.attitude, self.attitude, self.yaw))

    def wrench_gains(self) -> dict[str, np.ndarray]:
        """Force and torque gains (the geometric law's units), (3, 3) each: ``k_p = m W^2`` [N/m], ``k_v =
        2 zeta m W`` [N s/m], ``k_i = k_p W / INTEGRAL_RATIO`` [N/(m s)] with ``W = diag(w_xy, w_xy, w_z)``;
        ``k_r = S I S`` [N m/rad], ``k_w = zeta (S I + I S)`` [N m s/rad] with ``S = diag(w_R, w_R, w_yaw)``
        (``I w^2`` and ``2 zeta I w`` per axis for a diagonal inertia)."""
        position, attitude = np.diag(self.position_bandwidths), np.diag(self.attitude_bandwidths)
        k_p = self.mass * position @ position
        return {"k_p": k_p, "k_v": 2.0 * self.damping * self.mass * position,
                "k_i": k_p @ position / INTEGRAL_RATIO,
                "k_r": attitude @ self.inertia @ attitude,
                "k_w": self.damping * (attitude @ self.inertia + self.inertia @ attitude)}

    def acceleration_gains(self) -> dict[str, np.ndarray]:
        """Acceleration gains (the Voliro law's units), (3, 3) each: ``k_p = W^2`` [1/s^2], ``k_d = 2 zeta W``
        [1/s], ``k_r = S^2`` [1/s^2], ``k_w = 2 zeta S`` [1/s] (``W``, ``S`` of :meth:`wrench_gains`)."""
        position, attitude = np.diag(self.position_bandwidths), np.diag(self.attitude_bandwidths)
        return {"k_p": position @ position, "k_d": 2.0 * self.damping * position,
                "k_r": attitude @ attitude, "k_w": 2.0 * self.damping * attitude}

    def as_dict(self) -> dict:
        """Bandwidths, limits and both gain sets as plain Python data (JSON)."""
        return {"lag_s": self.lag, "lag_bandwidth": self.lag_bandwidth, "attitude": self.attitude, "yaw": self.yaw,
                "horizontal": self.horizontal, "vertical": self.vertical, "damping": self.damping,
                "limits": dict(self.limits), "integral_limit": self.integral_limit,
                "wrench_gains": {name: value.tolist() for name, value in self.wrench_gains().items()},
                "acceleration_gains": {name: value.tolist() for name, value in self.acceleration_gains().items()}}


def design_lag(vehicle: Vehicle, imu: bool = False) -> float:
    """The lag [s] the gains are designed for: the slower of the vehicle's motor (or servo) and
    :data:`DESIGN_MOTOR_TIME_CONSTANT`, plus the onboard sensor delay and half a sample period; with ``imu`` (the
    law damps with the gyro and flies on the IMU-bridged estimate of the state: no odometry delay) half an IMU
    sample (:data:`DESIGN_IMU_PERIOD`) instead."""
    motor = max(vehicle.rotor_time_constant, vehicle.tilt_time_constant, DESIGN_MOTOR_TIME_CONSTANT)
    if imu:
        return motor + 0.5 * DESIGN_IMU_PERIOD
    return motor + DESIGN_SENSOR_DELAY + 0.5 / DESIGN_SENSOR_RATE


def _bounded(cap: float, acceleration: float, error: float) -> tuple[float, str]:
    """``min(cap, sqrt(AUTHORITY_SHARE acceleration / error))`` and which of the two it is."""
    by_authority = math.sqrt(AUTHORITY_SHARE * max(acceleration, 0.0) / error)
    return (by_authority, "authority") if by_authority < cap else (cap, "lag")


def lateral_acceleration(vehicle: Vehicle, force_set: ForceSet) -> float:
    """The smallest of the largest body forces along ``+-x``, ``+-y`` a fully actuated vehicle adds to its level
    hover force with zero torque (its force set, :class:`~fsr_control.design.authority.ForceSet`), over its mass
    [m/s^2]."""
    reach = []
    for direction in np.vstack((np.eye(3)[:2], -np.eye(3)[:2])):
        along = force_set.normals @ direction
        room = force_set.offsets - force_set.normals @ force_set.hover
        reach.append(min((room[k] / along[k] for k in range(len(along)) if along[k] > 1e-12), default=np.inf))
    return max(min(reach), 0.0) / vehicle.mass


def design_gains(vehicle: Vehicle, authority: Authority | None = None, force_set: ForceSet | None = None,
                 lag: float | None = None, imu: bool = False) -> GainDesign:
    """The bandwidths and gains of the module docstring for ``vehicle`` (its nominal mass and inertia).

    Parameters
    ----------
    vehicle : Vehicle
        The nominal model.
    authority : Authority, optional
        Its authority at margin 1 (default: :func:`fsr_control.design.authority_cache.model_authority`).
    force_set : ForceSet, optional
        A fully actuated vehicle's force set (default: the cached one); unused otherwise.
    lag : float, optional
        The total lag [s] to design for (default: :func:`design_lag` of ``vehicle`` and ``imu``, the geometric
        law's).
    imu : bool, optional
        Whether the law flies on the IMU (``controller.use_imu``): the default lag's (:func:`design_lag`).

    Returns
    -------
    GainDesign
    """
    from fsr_control.design.authority_cache import model_authority, model_force_set

    authority = model_authority(vehicle) if authority is None else authority
    lag = design_lag(vehicle, imu) if lag is None else float(lag)
    cap = 1.0 / (LAG_FACTOR * lag)
    alpha = min(authority.roll_acceleration, authority.pitch_acceleration)
    attitude, attitude_limit = _bounded(cap, alpha, ATTITUDE_ERROR)
    yaw, yaw_limit = _bounded(cap, authority.yaw_acceleration, ATTITUDE_ERROR)
    weight = authority.hover_thrust
    vertical_acceleration = min(authority.thrust_max - weight, weight - authority.thrust_min) / vehicle.mass
    vertical, vertical_limit = _bounded(cap, vertical_acceleration, POSITION_ERROR)
    if vehicle.fully_actuated:
        force_set = model_force_set(vehicle) if force_set is None else force_set
        horizontal, horizontal_limit = _bounded(cap, lateral_acceleration(vehicle, force_set), POSITION_ERROR)
    else:
        horizontal, horizontal_limit = attitude / CASCADE_RATIO, "cascade"
    limits = {"attitude": attitude_limit, "yaw": yaw_limit, "horizontal": horizontal_limit,
              "vertical": vertical_limit}
    return GainDesign(float(vehicle.mass), np.array(vehicle.inertia, dtype=float), lag, cap, attitude, yaw,
                      horizontal, vertical, limits, DAMPING, INTEGRAL_LIMIT_SHARE * float(vehicle.weight))
