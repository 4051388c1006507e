"""The IMU (fsr_sim.core.imu, fsr_sim.core.sensors.measure_imu): the specific force the plant's own forces give,
on the ground, in the air, pushed and tilted; its stage's noise, bias walk, delay and rate exactly as documented."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_sim.core import lockstep
from fsr_sim.core.jit import numba
from fsr_sim.core.odometry import (
    IMU_ANGULAR_VELOCITY,
    IMU_END,
    IMU_LINEAR_ACCELERATION,
    IMU_TRUE_ANGULAR_VELOCITY,
    IMU_TRUE_LINEAR_ACCELERATION,
    PUBLISHED_SIZE,
)
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.core.sensors import measure_imu, new_sensor_memory, reset_sensor_memory
from fsr_sim.model import Environment, Plant, Surface, disturbances, load_vehicle
from fsr_sim.model.checks import InvalidValueError
from fsr_sim.model.sensors import ImuModel, pack_sensors
from fsr_sim.model.so3 import rotation_from_euler_zyx

FREE_SPACE = Environment(ground=Surface(enabled=False))


def imu_plant(**values) -> Plant:
    return Plant(load_vehicle("quadrotor_ex4"), **{"dt": 0.001, "actuation": "wrench", "imu": ImuModel(enabled=True),
                                                   **values})


def published(plant: Plant, advance: bool = False) -> np.ndarray:
    row = np.zeros(PUBLISHED_SIZE)
    (lockstep.advance if advance else lockstep.publish)(plant.params, plant.core_state, row)
    return row


def test_at_rest_on_the_ground_it_reads_minus_g_along_body_z():
    plant = imu_plant(position=[0.0, 0.0, 0.0])  # below the rest height: put on the ground by the first step
    for _ in range(3):
        row = published(plant, advance=True)
        assert plant.in_contact
        np.testing.assert_array_equal(row[IMU_TRUE_LINEAR_ACCELERATION:IMU_TRUE_LINEAR_ACCELERATION + 3],
                                      [0.0, 0.0, -GRAVITY])
        np.testing.assert_array_equal(row[IMU_ANGULAR_VELOCITY:IMU_END],  # ideal
                                      row[IMU_TRUE_ANGULAR_VELOCITY:IMU_TRUE_ANGULAR_VELOCITY + 6])
    plant.set_wrench([0.0, 0.0, -0.5 * plant.vehicle.mass * GRAVITY], [0.0, 0.0, 0.0])  # half its weight: held
    np.testing.assert_array_equal(published(plant)[IMU_LINEAR_ACCELERATION:IMU_END], [0.0, 0.0, -GRAVITY])


def test_resting_tilted_it_reads_gravity_in_the_body_frame():
    rotation = rotation_from_euler_zyx(np.deg2rad([10.0, -5.0, 40.0]))
    plant = imu_plant(position=[0.0, 0.0, 0.0], rotation=rotation)
    np.testing.assert_allclose(plant.specific_force(), -GRAVITY * rotation.T @ [0.0, 0.0, 1.0], atol=1e-15)


def test_taking_off_it_reads_the_thrust_not_the_ground():
    plant = imu_plant(position=[0.0, 0.0, 0.0])
    plant.step()
    thrust = 1.5 * plant.vehicle.mass * GRAVITY
    plant.set_wrench([0.0, 0.0, -thrust], [0.0, 0.0, 0.0])  # pulls it off the ground
    np.testing.assert_allclose(plant.specific_force(), [0.0, 0.0, -thrust / plant.vehicle.mass], rtol=1e-15)


def test_in_free_fall_and_before_the_first_command_it_reads_zero():
    plant = imu_plant(position=[0.0, 0.0, -5.0], angular_velocity=[0.1, -0.2, 0.3], environment=FREE_SPACE)
    row = published(plant)  # t_0: the rotors are still
    np.testing.assert_array_equal(row[IMU_LINEAR_ACCELERATION:IMU_END], 0.0)
    np.testing.assert_array_equal(row[IMU_ANGULAR_VELOCITY:IMU_LINEAR_ACCELERATION], [0.1, -0.2, 0.3])
    row = published(plant, advance=True)
    np.testing.assert_array_equal(row[IMU_LINEAR_ACCELERATION:IMU_END], 0.0)
    np.testing.assert_array_equal(row[IMU_ANGULAR_VELOCITY:IMU_LINEAR_ACCELERATION], plant.angular_velocity)


def test_in_flight_it_reads_every_force_but_gravity_in_the_body_frame():
    # a tilted, spinning vehicle with a body force and a world disturbance: R^T (p_ddot - g e3) = R^T F / m, and
    # p_ddot is what the plant integrates (the RK4 step's velocity change over a short step, to O(dt))
    rotation = rotation_from_euler_zyx(np.deg2rad([20.0, 10.0, -30.0]))
    push = np.array([1.0, -2.0, 0.5])
    plant = imu_plant(position=[0.0, 0.0, -5.0], rotation=rotation, angular_velocity=[0.2, 0.1, -0.1],
                      disturbances=[disturbances.constant(push)], environment=FREE_SPACE, dt=1e-5)
    body_force = np.array([0.3, 0.2, -14.0])
    plant.set_wrench(body_force, [0.0, 0.0, 0.0])
    expected = rotation.T @ (rotation @ body_force + push) / plant.vehicle.mass
    np.testing.assert_allclose(plant.specific_force(), expected, rtol=1e-14)
    velocity = plant.velocity.copy()
    plant.step()
    acceleration = (plant.velocity - velocity) / plant.dt
    np.testing.assert_allclose(plant.specific_force(), plant.rotation.T @ (acceleration - [0.0, 0.0, GRAVITY]),
                               atol=1e-4)


def stage(model: ImuModel, period: float = 0.001):
    sensors = pack_sensors(None, model, period)
    return sensors.imu, new_sensor_memory(sensors)


def test_an_ideal_stage_is_the_truth_delayed_and_held():
    truth = np.arange(60.0).reshape(10, 6)
    delayed, memory = stage(ImuModel(enabled=True, delay_steps=3))
    for k in range(10):
        out = truth[k].copy()
        measure_imu(delayed, memory, k, out)
        np.testing.assert_array_equal(out, truth[max(k - 3, 0)])
    slow, memory = stage(ImuModel(enabled=True, every_steps=4))
    for k in range(10):
        out = truth[k].copy()
        measure_imu(slow, memory, k, out)
        np.testing.assert_array_equal(out, truth[k - k % 4])


def test_the_initial_bias_is_there_from_the_first_sample():
    params, memory = stage(ImuModel(enabled=True, gyro_initial_bias=[0.01, 0.0, -0.02], accelerometer_initial_bias=0.3))
    out = np.zeros(6)
    measure_imu(params, memory, 0, out)
    np.testing.assert_array_equal(out, [0.01, 0.0, -0.02, 0.3, 0.3, 0.3])


def test_the_discrete_noise_and_walk_follow_the_densities():
    model = ImuModel(enabled=True, gyro_noise_density=[1e-4, 2e-4, 3e-4], accelerometer_noise_density=2e-3,
                     gyro_bias_walk=1e-5, accelerometer_bias_walk=[1e-3, 0.0, 2e-3], every_steps=4)
    params = model.pack(0.001)  # samples at 250 Hz, steps of 1 ms
    np.testing.assert_allclose(params.noise_std, np.array([1e-4, 2e-4, 3e-4, 2e-3, 2e-3, 2e-3]) * math.sqrt(250.0),
                               rtol=1e-15)
    np.testing.assert_allclose(params.walk_std, np.array([1e-5, 1e-5, 1e-5, 1e-3, 0.0, 2e-3]) * math.sqrt(0.001),
                               rtol=1e-15)
    assert params.noisy and not ImuModel(enabled=True).pack(0.001).noisy


@numba.njit  # not cached: a test writes nothing next to its source
def _bias_after(params, steps, memory, out):  # noqa: ANN001, ANN202
    reset_sensor_memory(memory)
    for k in range(steps + 1):
        out[:] = 0.0
        measure_imu(params, memory, k, out)


def test_the_bias_spreads_as_walk_sqrt_t():
    """Over 2000 seeds, the bias after T = 1 s (1000 steps of 1 ms) has the standard deviation walk sqrt(T) on
    every axis, and the mean of the initial bias."""
    walks = np.array([1e-4, 2e-4, 4e-4, 1e-3, 2e-3, 4e-3])
    model = ImuModel(enabled=True, gyro_bias_walk=walks[:3], accelerometer_bias_walk=walks[3:],
                     accelerometer_initial_bias=0.5)
    params, memory = stage(model)
    out = np.zeros((2000, 6))
    for seed in range(2000):
        _bias_after(params._replace(seed=seed), 1000, memory, out[seed])
    np.testing.assert_allclose(out.std(axis=0), walks * math.sqrt(1.0), rtol=0.08)  # each axis: 2000 samples
    spread = (out - out.mean(axis=0)) / walks
    assert spread.std() == pytest.approx(1.0, rel=0.03)  # pooled: 12 000 samples
    assert np.all(np.abs(out.mean(axis=0) - [0.0, 0.0, 0.0, 0.5, 0.5, 0.5]) < 4 * walks / math.sqrt(2000))


@pytest.mark.parametrize(("values", "name"), [
    ({"gyro_noise_density": -1e-4}, "gyro_noise_density"), ({"accelerometer_bias_walk": [0, 0]}, "accelerometer"),
    ({"gyro_initial_bias": float("nan")}, "gyro_initial_bias"), ({"seed": 2**32}, "seed"),
    ({"delay_steps": -1}, "delay_steps"), ({"every_steps": 0}, "every_steps"), ({"enabled": 1}, "enabled")])
def test_a_bad_imu_is_refused_naming_the_value(values, name):
    with pytest.raises(InvalidValueError, match=name):
        ImuModel(**values)
