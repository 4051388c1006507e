"""The ``sensors`` section: ``sensors.imu`` and ``sensors.preset`` set the documented values, any key overridable,
every bad value refused in one line naming the file, the key and the reason (the preset when it set it)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError


def sensors(*overrides: str):
    """(odometry, imu) of ex4 (1 kHz control) with ``--set`` overrides."""
    config = simulation_config(load_scenario("ex4_geometric", list(overrides)))
    return config.odometry_noise, config.imu


def test_without_a_sensors_section_odom_is_true_and_there_is_no_imu():
    odometry, imu = sensors()
    assert not odometry.enabled and odometry.delay_steps == 0 and odometry.every_steps == 1
    assert not imu.enabled and not imu.noisy


def test_an_imu_section_gives_an_imu_ideal_by_default_and_enabled_false_removes_it():
    _, imu = sensors("sensors.imu={}")
    assert imu.enabled and not imu.noisy and imu.every_steps == 1 and imu.delay_steps == 0
    _, imu = sensors("sensors.imu.gyro_noise_density=0.0001")
    assert imu.enabled and imu.gyro_noise_density == (1e-4, 1e-4, 1e-4)
    _, imu = sensors("sensors.preset=onboard", "sensors.imu.enabled=false")
    assert not imu.enabled


def test_imu_keys_per_axis_and_in_si_units():
    _, imu = sensors("sensors.imu.accelerometer_noise_density=[0.001, 0.002, 0.003]", "sensors.imu.rate_hz=250",
                     "sensors.imu.delay_s=0.004", "sensors.imu.seed=7", "sensors.imu.gyro_initial_bias=[0.01, 0, 0]",
                     "sensors.imu.accelerometer_bias_walk=0.002", "sensors.imu.gyro_bias_walk=[0, 0.00001, 0]")
    assert imu.accelerometer_noise_density == (1e-3, 2e-3, 3e-3)
    assert (imu.every_steps, imu.delay_steps, imu.seed) == (4, 4, 7)
    assert imu.gyro_initial_bias == (0.01, 0.0, 0.0) and imu.accelerometer_initial_bias == (0.0, 0.0, 0.0)
    assert imu.accelerometer_bias_walk == (0.002,) * 3 and imu.gyro_bias_walk == (0.0, 1e-5, 0.0)


def test_the_ideal_preset_is_true_odometry_and_an_ideal_imu():
    odometry, imu = sensors("sensors.preset=ideal")
    assert not odometry.enabled and odometry.every_steps == 1 and odometry.delay_steps == 0
    assert imu.enabled and not imu.noisy and imu.every_steps == 1 and imu.delay_steps == 0


def test_the_mocap_preset():
    odometry, imu = sensors("sensors.preset=mocap")
    assert (odometry.every_steps, odometry.delay_steps) == (5, 5)  # 200 Hz, 5 ms at 1 kHz
    assert odometry.position_std == 0.0005 and odometry.attitude_std == pytest.approx(math.radians(0.1), rel=1e-15)
    # the twist is the least-squares slope through 20 poses at 200 Hz: sigma sqrt(12 / (N (N^2 - 1))) / T_s
    gain = math.sqrt(12.0 / (20 * 399)) * 200.0
    assert odometry.velocity_std == pytest.approx(gain * 0.0005, rel=1e-15)  # 3.9 mm/s
    assert odometry.angular_velocity_std == pytest.approx(gain * math.radians(0.1), rel=1e-15)  # 0.78 deg/s
    assert not any(getattr(odometry, name) for name in ("position_bias_walk", "attitude_bias_walk"))
    assert not imu.enabled


def test_the_onboard_preset():
    odometry, imu = sensors("sensors.preset=onboard")
    assert (odometry.every_steps, odometry.delay_steps) == (10, 10)  # 100 Hz, 10 ms at 1 kHz
    assert (odometry.position_std, odometry.velocity_std) == (0.01, 0.02)
    assert odometry.attitude_std == pytest.approx(math.radians(0.5), rel=1e-15)
    gyro = math.radians(0.014)  # BMI088: 0.014 deg/s/sqrt(Hz); odom's rates: the gyro's over 10 ms
    assert odometry.angular_velocity_std == pytest.approx(gyro * math.sqrt(100.0), rel=1e-15)
    assert imu.enabled and imu.every_steps == 1 and imu.delay_steps == 0
    assert imu.gyro_noise_density == pytest.approx((gyro,) * 3, rel=1e-15)
    assert imu.accelerometer_noise_density == pytest.approx((175e-6 * 9.80665,) * 3, rel=1e-15)
    assert imu.gyro_bias_walk == (2.2e-5,) * 3 and imu.accelerometer_bias_walk == (8.6e-4,) * 3
    assert imu.gyro_initial_bias == imu.accelerometer_initial_bias == (0.0, 0.0, 0.0)
    np.testing.assert_allclose(imu.pack(0.001).noise_std[:3], gyro * math.sqrt(1000.0), rtol=1e-15)


def test_any_preset_key_is_overridden_by_the_scenario():
    odometry, imu = sensors("sensors.preset=onboard", "sensors.odometry.position_std=0.002",
                            "sensors.odometry.delay_steps=3", "sensors.imu.rate_hz=500",
                            "sensors.imu.gyro_noise_density=[0, 0, 0.001]")
    assert odometry.position_std == 0.002 and odometry.delay_steps == 3 and odometry.velocity_std == 0.02
    assert imu.every_steps == 2 and imu.gyro_noise_density == (0.0, 0.0, 1e-3)
    assert imu.accelerometer_noise_density == pytest.approx((175e-6 * 9.80665,) * 3, rel=1e-15)


@pytest.mark.parametrize(("overrides", "message"), [
    (["sensors.preset=lab"], r"sensors\.preset: must be one of ideal, mocap, onboard; got 'lab'"),
    (["sensors.imu=3"], r"sensors\.imu: expected a mapping, got int"),
    (["sensors.imu.enabled=1"], r"sensors\.imu\.enabled: must be true or false"),
    (["sensors.imu.gyro_noise_density=-0.0001"], r"sensors\.imu\.gyro_noise_density: must be >= 0"),
    (["sensors.imu.accelerometer_noise_density=[1, 2]"], r"sensors\.imu\.accelerometer_noise_density: expected shape"),
    (["sensors.imu.gyro_bias_walk=[0, -1, 0]"], r"sensors\.imu\.gyro_bias_walk: must be >= 0"),
    (["sensors.imu.accelerometer_bias_walk=fast"], r"sensors\.imu\.accelerometer_bias_walk: must be a number"),
    (["sensors.imu.gyro_initial_bias=.nan"], r"sensors\.imu\.gyro_initial_bias: must be finite"),
    (["sensors.imu.accelerometer_initial_bias=[0, 0, .inf]"], r"sensors\.imu\.accelerometer_initial_bias: must be"),
    (["sensors.imu.seed=-1"], r"sensors\.imu\.seed: must be >= 0"),
    (["sensors.imu.seed=4294967296"], r"sensors\.imu\.seed: must be <= 4294967295"),
    (["sensors.imu.rate_hz=300"], r"sensors\.imu\.rate_hz: must divide the control rate 1000 Hz by a whole number"),
    (["sensors.imu.rate_hz=2000"], r"sensors\.imu\.rate_hz: must divide the control rate"),
    (["sensors.imu.rate_hz=0"], r"sensors\.imu\.rate_hz: must be > 0"),
    (["sensors.imu.delay_s=0.0015"], r"sensors\.imu\.delay_s: must be a whole number of control periods \(0\.001 s\)"),
    (["sensors.imu.delay_s=-0.001"], r"sensors\.imu\.delay_s: must be >= 0"),
    (["sensors.imu.delay_steps=-1"], r"sensors\.imu\.delay_steps: must be >= 0"),
    (["sensors.imu.delay_s=0.002", "sensors.imu.delay_steps=2"], r"sensors\.imu\.delay_s: give delay_s or delay_st"),
    (["sensors.imu.gyro_noise=0.0001"], r"sensors\.imu\.gyro_noise: unknown key \(did you mean 'gyro_noise_density'"),
    (["sensors.odometry.delay_s=0.0005"], r"sensors\.odometry\.delay_s: must be a whole number of control periods"),
    (["sensors.odometry.delay_s=0.002", "sensors.odometry.delay_steps=1"], r"sensors\.odometry\.delay_s: give"),
    (["sensors.camera={}"], r"sensors\.camera: unknown key"),
])
def test_bad_sensor_values_are_refused_in_one_line(overrides, message):
    with pytest.raises(ConfigError, match=message) as error:
        sensors(*overrides)
    assert "\n" not in str(error.value) and "ex4_geometric" in error.value.source


def test_a_preset_value_refused_at_this_control_rate_names_the_preset():
    # at 500 Hz control the onboard IMU's 1 kHz cannot be: refused, saying the preset set it
    with pytest.raises(ConfigError, match=r"sensors\.imu\.rate_hz: must divide the control rate 500 Hz .* got "
                                          r"1000 \(set by sensors\.preset: onboard\)"):
        sensors("physics_dt=0.002", "sensors.preset=onboard")
    with pytest.raises(ConfigError, match=r"sensors\.odometry\.delay_s: .* got 0.005 \(set by sensors\.preset: mocap"):
        sensors("physics_dt=0.002", "sensors.preset=mocap")  # 5 ms is 2.5 periods of 2 ms
    odometry, imu = sensors("physics_dt=0.002", "sensors.preset=onboard", "sensors.imu.rate_hz=500")
    assert imu.every_steps == 1 and odometry.every_steps == 5 and odometry.delay_steps == 5
