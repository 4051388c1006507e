"""Disturbance frames: ``frame`` applies to the force and to the torque (world torque -> body via R^T)."""

import numpy as np
import pytest
import yaml

from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.model import Plant, disturbances, load_vehicle
from fsr_sim.model.disturbances import total_external_wrench
from fsr_sim.model.so3 import rotation_from_euler_zyx


def profiles(tmp_path, disturbances, attitude_rpy_deg=(0.0, 0.0, 0.0)):
    scenario = {
        "vehicle": "quadrotor_ex4", "duration": 1.0, "actuation": "wrench", "disturbances": disturbances,
        "initial_state": {"position": [0.0, 0.0, -20.0], "attitude_rpy_deg": list(attitude_rpy_deg)},
    }
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(scenario))
    return simulation_config(load_scenario(path))


# Yaw 90 deg: body x = world y (east), body y = world -x (south); R = [[0,-1,0],[1,0,0],[0,0,1]].
YAW_90 = rotation_from_euler_zyx([0.0, 0.0, np.pi / 2])


def test_world_torque_is_rotated_into_the_body_frame(tmp_path):
    config = profiles(tmp_path, [{"kind": "constant", "frame": "world", "torque": [1.0, 0.0, 0.0]}])
    force_world, torque_body = total_external_wrench(config.disturbances, 0.0, YAW_90)
    # A torque about world north is a torque about body -y when the body x axis points east.
    np.testing.assert_allclose(torque_body, [0.0, -1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(force_world, 0.0)


def test_body_torque_turns_with_the_vehicle(tmp_path):
    config = profiles(tmp_path, [{"kind": "constant", "frame": "body", "force": [2.0, 0.0, 0.0],
                                  "torque": [1.0, 0.0, 0.0]}])
    force_world, torque_body = total_external_wrench(config.disturbances, 0.0, YAW_90)
    np.testing.assert_allclose(torque_body, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(force_world, [0.0, 2.0, 0.0], atol=1e-15)


def test_world_and_body_entries_add_up_for_a_general_rotation(tmp_path):
    rotation = rotation_from_euler_zyx(np.deg2rad([20.0, -35.0, 110.0]))
    tau_world, tau_body = np.array([0.3, -0.2, 0.5]), np.array([-0.1, 0.4, 0.05])
    config = profiles(tmp_path, [
        {"kind": "constant", "frame": "world", "torque": tau_world.tolist()},
        {"kind": "constant", "frame": "body", "torque": tau_body.tolist()},
    ])
    _, torque = total_external_wrench(config.disturbances, 0.0, rotation)
    np.testing.assert_allclose(torque, rotation.T @ tau_world + tau_body, atol=1e-15)


def test_plant_applies_a_world_torque_about_the_world_axis():
    """Rolled 90 deg (the body y axis points down), a world-down torque spins the
    vehicle about world down, i.e. about body y, and the truth reports it in the body frame."""
    plant = Plant(load_vehicle("quadrotor_ex4"), actuation="wrench", position=[0.0, 0.0, -20.0],
                  attitude_rpy_deg=[90.0, 0.0, 0.0],
                  disturbances=[disturbances.constant(torque=[0.0, 0.0, 0.12], frame="world")])
    plant.set_wrench_command(0.0, np.zeros(3))
    plant.step()
    _, torque_body = plant.external_wrench()
    np.testing.assert_allclose(torque_body, plant.rotation.T @ [0.0, 0.0, 0.12], atol=1e-9)
    assert torque_body[1] == pytest.approx(0.12, abs=1e-6)
    omega = plant.angular_velocity
    assert omega[1] == pytest.approx(0.12 / plant.vehicle.inertia[1, 1] * plant.time, rel=1e-6)
    assert abs(omega[2]) < 1e-9
