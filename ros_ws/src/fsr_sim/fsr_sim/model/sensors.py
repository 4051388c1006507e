"""Sensor models between the true state and ``odom`` (docs/model.md §3.8): the checked parameters, packed into
the compiled core's :class:`fsr_sim.core.sensors.SensorParams` once, at start-up."""

from __future__ import annotations

import math
from dataclasses import dataclass

from fsr_sim.core.sensors import SensorParams
from fsr_sim.model.checks import InvalidValueError

WALKS = ("position_bias_walk", "attitude_bias_walk", "velocity_bias_walk", "angular_velocity_bias_walk")


@dataclass(frozen=True)
class OdometryNoise:
    """What ``odom`` measures of the state (all zero, the default: the true state): white Gaussian noise per
    published state, a bias that walks randomly, a delay and a lower rate (:func:`fsr_sim.core.sensors.measure`).

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
        if int(self.seed) != self.seed or not 0 <= self.seed < 2**32:
            raise InvalidValueError("seed", f"must be an integer in 0 .. 2^32 - 1, got {self.seed}")
        object.__setattr__(self, "seed", int(self.seed))
        for name, low in (("delay_steps", 0), ("every_steps", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or int(value) != value or value < low:
                raise InvalidValueError(name, f"must be an integer >= {low}, got {value}")
            object.__setattr__(self, name, int(value))

    @property
    def enabled(self) -> bool:
        """Whether any noise or bias acts (a delay or a rate alone keeps the true values)."""
        return any((self.position_std, self.attitude_std, self.velocity_std, self.angular_velocity_std,
                    *(getattr(self, name) for name in WALKS)))

    def pack(self, period: float) -> SensorParams:
        """The core's parameters for published states ``period`` [s] apart."""
        return SensorParams(self.enabled, self.seed, self.position_std, self.attitude_std, self.velocity_std,
                            self.angular_velocity_std, tuple(float(getattr(self, name)) for name in WALKS),
                            float(period), self.delay_steps, self.every_steps)
