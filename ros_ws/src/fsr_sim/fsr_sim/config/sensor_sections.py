"""The ``sensors`` section of a scenario: a ``preset``, then ``odometry`` (what ``odom`` measures) and ``imu``
(an IMU on ``imu``), docs/scenarios.md and docs/model.md §3.9.

A preset (:data:`PRESETS`) is a set of values of the ``odometry`` and ``imu`` keys, put under the scenario's
own: any key the scenario (or ``--set``) gives wins; ``delay_steps`` replaces a preset's ``delay_s``. A value
refused because of the preset says so (``... (set by sensors.preset: onboard)``). An ``imu`` section (the
scenario's or a preset's) gives the vehicle an IMU: ``enabled`` defaults to true there, false without one.

Rates are in Hz and must divide the control rate ``1 / T`` (a new sample every whole number of steps); delays
are ``delay_s`` [s], a whole number of control periods, or ``delay_steps``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from fsr_sim.config.validation import ConfigError, Section
from fsr_sim.contract import IMU
from fsr_sim.model.sensors import ImuModel, OdometryNoise

ODOMETRY_SECTION, IMU_SECTION = "odometry", IMU.name  # sensors.imu: the sensor of the topic imu
STANDARD_GRAVITY = 9.80665  # m/s^2: a datasheet's g (the plant's gravity is fsr_sim.core.rigid_body.GRAVITY)

# Motion capture (Vicon/OptiTrack class): poses at 200 Hz, 5 ms late, 0.5 mm and 0.1 deg per sample. The twist
# such a system streams is a derivative of its poses: the least-squares slope through the last
# MOCAP_DERIVATIVE_POSES poses, whose noise is the pose noise times sqrt(12 / (N (N^2 - 1))) / T_s.
MOCAP_RATE_HZ = 200.0
MOCAP_POSITION_STD = 0.0005  # m
MOCAP_ATTITUDE_STD_DEG = 0.1
MOCAP_DERIVATIVE_POSES = 20  # 0.1 s at 200 Hz
MOCAP_DERIVATIVE_GAIN = math.sqrt(12.0 / (MOCAP_DERIVATIVE_POSES * (MOCAP_DERIVATIVE_POSES**2 - 1))) * MOCAP_RATE_HZ

# Bosch BMI088 (datasheet BST-BMI088-DS001): gyroscope 0.014 deg/s/sqrt(Hz), accelerometer 175 ug/sqrt(Hz)
# (docs/model.md §3.9 says which axes and why); bias random walks from the Allan-deviation calibration of a
# Bosch BMI160 in the TUM VI benchmark (Schubert et al., IROS 2018), the datasheet giving none.
BMI088_GYRO_NOISE_DENSITY = math.radians(0.014)  # rad/s/sqrt(Hz)
BMI088_ACCELEROMETER_NOISE_DENSITY = 175e-6 * STANDARD_GRAVITY  # m/s^2/sqrt(Hz)
BMI160_GYRO_BIAS_WALK = 2.2e-5  # rad/s^2/sqrt(Hz)
BMI160_ACCELEROMETER_BIAS_WALK = 8.6e-4  # m/s^3/sqrt(Hz)
ONBOARD_ODOMETRY_RATE_HZ = 100.0

PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    # the true state on odom, and an ideal IMU
    "ideal": {IMU_SECTION: {"enabled": True}},
    "mocap": {ODOMETRY_SECTION: {
        "rate_hz": MOCAP_RATE_HZ, "delay_s": 0.005, "position_std": MOCAP_POSITION_STD,
        "attitude_std_deg": MOCAP_ATTITUDE_STD_DEG, "velocity_std": MOCAP_DERIVATIVE_GAIN * MOCAP_POSITION_STD,
        "angular_velocity_std": MOCAP_DERIVATIVE_GAIN * math.radians(MOCAP_ATTITUDE_STD_DEG),
    }},
    # an onboard state estimate (100 Hz, 10 ms late; its body rates the gyro's, averaged over its period) and
    # the BMI088 at 1 kHz
    "onboard": {
        ODOMETRY_SECTION: {
            "rate_hz": ONBOARD_ODOMETRY_RATE_HZ, "delay_s": 0.010, "position_std": 0.01, "attitude_std_deg": 0.5,
            "velocity_std": 0.02,
            "angular_velocity_std": BMI088_GYRO_NOISE_DENSITY * math.sqrt(ONBOARD_ODOMETRY_RATE_HZ),
        },
        IMU_SECTION: {
            "enabled": True, "rate_hz": 1000.0, "gyro_noise_density": BMI088_GYRO_NOISE_DENSITY,
            "accelerometer_noise_density": BMI088_ACCELEROMETER_NOISE_DENSITY,
            "gyro_bias_walk": BMI160_GYRO_BIAS_WALK, "accelerometer_bias_walk": BMI160_ACCELEROMETER_BIAS_WALK,
        },
    },
}


def sensors_from_section(sensors: Section, period: float) -> tuple[OdometryNoise, ImuModel]:
    """Parse ``sensors`` (module docstring) for published states ``period`` [s] apart: (what ``odom``
    measures, the IMU). Unknown keys are refused."""
    preset_name = sensors.string("preset", choices=tuple(PRESETS)) if sensors.has("preset") else None
    preset = PRESETS.get(preset_name, {})
    parsed = []
    for name, parse in ((ODOMETRY_SECTION, _odometry), (IMU_SECTION, _imu)):
        given = sensors.raw(name, {})
        if not isinstance(given, dict):
            raise sensors.error(name, f"expected a mapping, got {type(given).__name__}")
        from_preset = dict(preset.get(name, {}))
        if "delay_steps" in given:
            from_preset.pop("delay_s", None)
        section = Section({**from_preset, **given}, sensors.key(name), sensors.source)
        try:
            parsed.append(parse(section, period, name in preset or sensors.data.get(name) is not None))
        except ConfigError as error:
            key = error.key.rpartition(".")[2]
            if error.key == section.key(key) and key in from_preset and key not in given:
                raise ConfigError(error.key, f"{error.reason} (set by sensors.preset: {preset_name})",
                                  error.source) from None
            raise
    sensors.reject_unknown()
    return parsed[0], parsed[1]


def _odometry(odometry: Section, period: float, _present: bool) -> OdometryNoise:
    """``sensors.odometry`` (:class:`fsr_sim.model.sensors.OdometryNoise`; angles in degrees here)."""
    noise = OdometryNoise(
        position_std=odometry.number("position_std", 0.0, minimum=0.0),
        attitude_std=np.deg2rad(odometry.number("attitude_std_deg", 0.0, minimum=0.0)),
        velocity_std=odometry.number("velocity_std", 0.0, minimum=0.0),
        angular_velocity_std=odometry.number("angular_velocity_std", 0.0, minimum=0.0),
        seed=odometry.integer("seed", 0, minimum=0, maximum=2**32 - 1),
        position_bias_walk=odometry.number("position_bias_walk", 0.0, minimum=0.0),
        attitude_bias_walk=np.deg2rad(odometry.number("attitude_bias_walk_deg", 0.0, minimum=0.0)),
        velocity_bias_walk=odometry.number("velocity_bias_walk", 0.0, minimum=0.0),
        angular_velocity_bias_walk=odometry.number("angular_velocity_bias_walk", 0.0, minimum=0.0),
        delay_steps=_delay_steps(odometry, period),
        every_steps=_every_steps(odometry, period),
    )
    odometry.reject_unknown()
    return noise


def _imu(imu: Section, period: float, present: bool) -> ImuModel:
    """``sensors.imu`` (:class:`fsr_sim.model.sensors.ImuModel`, SI units): on by default where it is given."""
    model = ImuModel(
        enabled=imu.boolean("enabled", present),
        gyro_noise_density=_per_axis(imu, "gyro_noise_density", minimum=0.0),
        accelerometer_noise_density=_per_axis(imu, "accelerometer_noise_density", minimum=0.0),
        gyro_bias_walk=_per_axis(imu, "gyro_bias_walk", minimum=0.0),
        accelerometer_bias_walk=_per_axis(imu, "accelerometer_bias_walk", minimum=0.0),
        gyro_initial_bias=_per_axis(imu, "gyro_initial_bias"),
        accelerometer_initial_bias=_per_axis(imu, "accelerometer_initial_bias"),
        seed=imu.integer("seed", 0, minimum=0, maximum=2**32 - 1),
        delay_steps=_delay_steps(imu, period),
        every_steps=_every_steps(imu, period),
    )
    imu.reject_unknown()
    return model


def _per_axis(section: Section, name: str, minimum: float | None = None) -> tuple[float, float, float]:
    """One number for every axis or three (x y z), each ``>= minimum``; 0 when absent."""
    value = section.raw(name, 0.0)
    if isinstance(value, list):
        values = section.vector(name, 3)
    else:
        values = np.full(3, section.number(name, 0.0))
    if minimum is not None and np.any(values < minimum):
        raise section.error(name, f"must be >= {minimum}, got {value}")
    return tuple(float(v) for v in values)


def _every_steps(section: Section, period: float) -> int:
    """``rate_hz`` as the steps between two samples: a whole divisor of the control rate (default: every step)."""
    if not section.has("rate_hz"):
        return 1
    rate = section.number("rate_hz", strictly_positive=True)
    every = round(1.0 / (period * rate))
    if every < 1 or abs(every * period * rate - 1.0) > 1e-9:
        raise section.error("rate_hz", f"must divide the control rate {1.0 / period:g} Hz by a whole number, "
                                       f"got {rate:g}")
    return every


def _delay_steps(section: Section, period: float) -> int:
    """``delay_s`` (a whole number of control periods) or ``delay_steps``, in steps (default 0)."""
    if section.has("delay_s") and section.has("delay_steps"):
        raise section.error("delay_s", "give delay_s or delay_steps, not both")
    if not section.has("delay_s"):
        return section.integer("delay_steps", 0, minimum=0)
    delay = section.number("delay_s", minimum=0.0)
    steps = round(delay / period)
    if abs(delay / period - steps) > 1e-6:
        raise section.error("delay_s", f"must be a whole number of control periods ({period:g} s), got {delay:g}")
    return steps
