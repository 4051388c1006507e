"""Sensor models between the true state and ``odom`` (docs/model.md §3.8): the checked parameters, packed into
the compiled core's :class:`fsr_sim.core.sensors.SensorParams` once, at start-up."""

from __future__ import annotations

import math
from dataclasses import dataclass

from fsr_sim.core.sensors import SensorParams
from fsr_sim.model.checks import InvalidValueError


@dataclass(frozen=True)
class OdometryNoise:
    """White Gaussian noise on ``odom``, per published state (all zero: ``odom`` is the true state).

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
    """

    position_std: float = 0.0
    attitude_std: float = 0.0
    velocity_std: float = 0.0
    angular_velocity_std: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("position_std", "attitude_std", "velocity_std", "angular_velocity_std"):
            value = float(getattr(self, name))
            if not (value >= 0.0 and math.isfinite(value)):
                raise InvalidValueError(name, f"must be a finite standard deviation >= 0, got {value}")
            object.__setattr__(self, name, value)
        if int(self.seed) != self.seed or not 0 <= self.seed < 2**32:
            raise InvalidValueError("seed", f"must be an integer in 0 .. 2^32 - 1, got {self.seed}")
        object.__setattr__(self, "seed", int(self.seed))

    @property
    def enabled(self) -> bool:
        return any((self.position_std, self.attitude_std, self.velocity_std, self.angular_velocity_std))

    def pack(self) -> SensorParams:
        """The core's parameters."""
        return SensorParams(self.enabled, self.seed, self.position_std, self.attitude_std, self.velocity_std,
                            self.angular_velocity_std)
