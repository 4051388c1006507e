"""Sensor models between the true plant and what the simulator publishes (docs/model.md §3.9): ``odom``'s
(:class:`OdometryNoise`) and the IMU's (:class:`ImuModel`), checked, packed into the compiled core's
:class:`fsr_sim.core.sensors.SensorParams` once, at start-up (:func:`pack_sensors`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_sim.core.sensors import ImuParams, OdometryParams, SensorParams
from fsr_sim.model.checks import InvalidValueError, finite_array

WALKS = ("position_bias_walk", "attitude_bias_walk", "velocity_bias_walk", "angular_velocity_bias_walk")


@dataclass(frozen=True)
class OdometryNoise:
    """What ``odom`` measures of the state (all zero, the default: the true state): white Gaussian noise per
    published state, a bias that walks randomly, a delay and a lower rate
    (:func:`fsr_sim.core.sensors.measure_odometry`).

    Parameters
    ----------
    position_std : float
        [m], each world NED axis.
    attitude_std : float
        [rad], each component of a body rotation vector (``R_meas = R Exp(n)``).
    velocity_std : float
        [m/s], each body axis of the linear velocity (``odom``'s twist).
    angular_velocity_std : float
        [rad/s], each body axis.
    seed : int
        ``0 .. 2^32 - 1``: the same seed gives the same noise, in the node graph and in one process.
    position_bias_walk, attitude_bias_walk, velocity_bias_walk, angular_velocity_bias_walk : float
        Random-walk densities of a bias per channel, [m/sqrt(s)], [rad/sqrt(s)], [m/s/sqrt(s)],
        [rad/s/sqrt(s)]: after ``t`` seconds the bias has a standard deviation of ``walk sqrt(t)``.
    delay_steps : int
        ``>= 0``: ``odom`` at step ``k`` carries the measurement of step ``k - delay_steps`` (stamped ``t_k``:
        the lockstep answers every state).
    every_steps : int
        ``>= 1``: a new measurement every this many steps (``odom`` at ``1 / (every_steps T)`` Hz), held in
        between.
    """

    position_std: float = 0.0
    attitude_std: float = 0.0
    velocity_std: float = 0.0
    angular_velocity_std: float = 0.0
    seed: int = 0
    position_bias_walk: float = 0.0
    attitude_bias_walk: float = 0.0
    velocity_bias_walk: float = 0.0
    angular_velocity_bias_walk: float = 0.0
    delay_steps: int = 0
    every_steps: int = 1

    def __post_init__(self) -> None:
        for name in ("position_std", "attitude_std", "velocity_std", "angular_velocity_std", *WALKS):
            value = float(getattr(self, name))
            if not (value >= 0.0 and math.isfinite(value)):
                raise InvalidValueError(name, f"must be a finite standard deviation >= 0, got {value}")
            object.__setattr__(self, name, value)
        _check_seed_delay_and_rate(self)

    @property
    def enabled(self) -> bool:
        """Whether any noise or bias acts (a delay or a rate alone keeps the true values)."""
        return any((self.position_std, self.attitude_std, self.velocity_std, self.angular_velocity_std,
                    *(getattr(self, name) for name in WALKS)))

    def pack(self, period: float) -> OdometryParams:
        """The core's parameters for published states ``period`` [s] apart."""
        return OdometryParams(self.enabled, self.seed, self.position_std, self.attitude_std, self.velocity_std,
                              self.angular_velocity_std, tuple(float(getattr(self, name)) for name in WALKS),
                              float(period), self.delay_steps, self.every_steps)


IMU_DENSITIES = ("gyro_noise_density", "accelerometer_noise_density", "gyro_bias_walk", "accelerometer_bias_walk")
IMU_BIASES = ("gyro_initial_bias", "accelerometer_initial_bias")


@dataclass(frozen=True)
class ImuModel:
    """An IMU at the centre of mass, axes ``base_link_frd`` (:mod:`fsr_sim.core.imu`): what ``imu`` measures of
    the true angular velocity and specific force - white Gaussian noise, a bias per axis that starts at its
    initial value and walks randomly, a delay and a rate (:func:`fsr_sim.core.sensors.measure_imu`). All zero
    (the default): an ideal IMU, the true values. Densities, walks and biases are 3 numbers (x y z) or one for
    every axis.

    Parameters
    ----------
    enabled : bool
        The simulator computes and publishes ``imu`` (default: no IMU).
    gyro_noise_density : float or (3,)
        [rad/s/sqrt(Hz)]: white noise of standard deviation ``density sqrt(rate)`` per sample.
    accelerometer_noise_density : float or (3,)
        [m/s^2/sqrt(Hz)], the same way.
    gyro_bias_walk : float or (3,)
        [rad/s^2/sqrt(Hz)]: the bias's random walk, standard deviation ``walk sqrt(t)`` after ``t`` seconds.
    accelerometer_bias_walk : float or (3,)
        [m/s^3/sqrt(Hz)], the same way.
    gyro_initial_bias, accelerometer_initial_bias : float or (3,)
        The biases at ``t_0`` [rad/s], [m/s^2].
    seed : int
        ``0 .. 2^32 - 1``: the same seed gives the same noise, in the node graph and in one process.
    delay_steps : int
        ``>= 0``: ``imu`` at step ``k`` carries the sample of step ``k - delay_steps`` (stamped ``t_k``).
    every_steps : int
        ``>= 1``: a new sample every this many steps (``imu`` at ``1 / (every_steps T)`` Hz), held in between.
    """

    enabled: bool = False
    gyro_noise_density: object = 0.0
    accelerometer_noise_density: object = 0.0
    gyro_bias_walk: object = 0.0
    accelerometer_bias_walk: object = 0.0
    gyro_initial_bias: object = 0.0
    accelerometer_initial_bias: object = 0.0
    seed: int = 0
    delay_steps: int = 0
    every_steps: int = 1

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise InvalidValueError("enabled", f"must be true or false, got {self.enabled!r}")
        for name in (*IMU_DENSITIES, *IMU_BIASES):
            value = getattr(self, name)
            values = finite_array(np.broadcast_to(value, (3,)) if np.ndim(value) == 0 else value, (3,), name)
            if name in IMU_DENSITIES and np.any(values < 0.0):
                raise InvalidValueError(name, f"must be >= 0, got {values.tolist()}")
            object.__setattr__(self, name, tuple(float(v) for v in values))
        _check_seed_delay_and_rate(self)

    @property
    def noisy(self) -> bool:
        """Whether any noise, bias walk or initial bias acts (a delay or a rate alone keeps the true values)."""
        return any(v != 0.0 for name in (*IMU_DENSITIES, *IMU_BIASES) for v in getattr(self, name))

    def pack(self, period: float) -> ImuParams:
        """The core's parameters for published states ``period`` [s] apart."""
        rate = 1.0 / (self.every_steps * period)
        return ImuParams(
            self.enabled, self.noisy, self.seed,
            tuple(d * math.sqrt(rate) for d in (*self.gyro_noise_density, *self.accelerometer_noise_density)),
            tuple(w * math.sqrt(period) for w in (*self.gyro_bias_walk, *self.accelerometer_bias_walk)),
            (*self.gyro_initial_bias, *self.accelerometer_initial_bias), self.delay_steps, self.every_steps)


def pack_sensors(odometry: OdometryNoise | None, imu: ImuModel | None, period: float) -> SensorParams:
    """Both sensor stages for published states ``period`` [s] apart (None: off, and no IMU)."""
    return SensorParams((odometry or OdometryNoise()).pack(period), (imu or ImuModel()).pack(period))


def _check_seed_delay_and_rate(model: OdometryNoise | ImuModel) -> None:
    if isinstance(model.seed, bool) or int(model.seed) != model.seed or not 0 <= model.seed < 2**32:
        raise InvalidValueError("seed", f"must be an integer in 0 .. 2^32 - 1, got {model.seed}")
    object.__setattr__(model, "seed", int(model.seed))
    for name, low in (("delay_steps", 0), ("every_steps", 1)):
        value = getattr(model, name)
        if isinstance(value, bool) or int(value) != value or value < low:
            raise InvalidValueError(name, f"must be an integer >= {low}, got {value}")
        object.__setattr__(model, name, int(value))
