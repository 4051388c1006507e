import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model import Environment, Plant, Surface, disturbances, load_vehicle


def make_plant(vehicle="quadrotor_ex4", actuation="wrench", **values):
    """A plant from plain Python values (no scenario file)."""
    return Plant(load_vehicle(vehicle), **{"dt": 0.001, "actuation": actuation, **values})


def test_model_imports_neither_ros_nor_the_yaml_readers():
    """The model loads no ROS and none of fsr's configuration readers (numba itself imports PyYAML)."""
    code = ("import sys, fsr_sim.model, fsr_sim.model.rotors; "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rosidl_parser') "
            "or m.startswith('fsr_sim.config') or m.endswith(('.msg', '_msgs'))))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_plant_from_python_values_hovers_with_the_weight_as_thrust():
    plant = Plant(load_vehicle("quadrotor_ex4"), dt=0.001, actuation="wrench", position=[0, 0, -1])
    plant.set_wrench(force_body=[0, 0, -11.772], torque_body=[0, 0, 0])
    for _ in range(100):
        plant.step()
    np.testing.assert_allclose(plant.state.position, [0, 0, -1], atol=1e-12)
    np.testing.assert_allclose(plant.state.rotation, np.eye(3), atol=1e-15)
    assert plant.time == pytest.approx(0.1)


@pytest.mark.parametrize(("values", "named"), [
    ({"actuation": "thrust"}, "actuation"), ({"dt": 0.0}, "dt"), ({"position": [0, 0]}, "position"),
    ({"rotation": np.eye(3), "attitude_rpy_deg": [0, 0, 1]}, "rotation"), ({"substeps": 0}, "substeps"),
])
def test_bad_plant_values_are_refused_by_name(values, named):
    with pytest.raises(ValueError, match=named):
        make_plant(**values)


def test_free_fall_from_rest_matches_half_g_t_squared():
    plant = make_plant(position=[0.0, 0.0, -50.0])
    for _ in range(1500):
        plant.step()
    t = plant.time
    assert t == pytest.approx(1.5)
    np.testing.assert_allclose(plant.position, [0.0, 0.0, -50.0 + 0.5 * GRAVITY * t**2], atol=1e-12)
    np.testing.assert_allclose(plant.velocity, [0.0, 0.0, GRAVITY * t], atol=1e-12)


def test_hover_with_thrust_equal_to_weight_stays_put():
    plant = make_plant(position=[1.0, 2.0, -3.0], attitude_rpy_deg=[0, 0, 30])
    plant.set_wrench_command(plant.vehicle.weight, np.zeros(3))
    for _ in range(2000):
        plant.step()
    np.testing.assert_allclose(plant.position, [1.0, 2.0, -3.0], atol=1e-12)
    np.testing.assert_allclose(plant.velocity, 0.0, atol=1e-12)


@pytest.mark.parametrize("vehicle", ["octocopter", "quadrotor_ex4", "tilting_quadrotor_ex5"])
def test_rotor_hover_stays_put_away_from_surfaces(vehicle):
    plant = make_plant(vehicle, "rotors", environment=Environment(ground=Surface(enabled=False)),
                       position=[0.0, 0.0, -5.0])
    v = plant.vehicle
    plant.set_rotor_command(np.full(v.rotor_count, np.sqrt(v.weight / (v.rotor_count * v.c_f))))
    for _ in range(1000):
        plant.step()
    np.testing.assert_allclose(plant.position, [0.0, 0.0, -5.0], atol=1e-9)
    np.testing.assert_allclose(plant.angular_velocity, 0.0, atol=1e-9)


def test_torque_free_spinning_body_conserves_angular_momentum_and_stays_orthonormal():
    inertia = np.diag((0.02, 0.03, 0.05))
    vehicle = load_vehicle("quadrotor_ex4").with_mass_properties(1.0, inertia)
    plant = Plant(vehicle, dt=1e-3, actuation="wrench", environment=Environment(ground=Surface(enabled=False)),
                  angular_velocity=(0.3, 5.0, 0.4))  # near-unstable axis; gravity does not turn the body

    def world_momentum():
        r = plant.rotation
        return r @ inertia @ plant.angular_velocity, r

    momentum0, _ = world_momentum()
    energy0 = 0.5 * plant.angular_velocity @ inertia @ plant.angular_velocity
    for _ in range(100_000):
        plant.step()
    momentum, r = world_momentum()
    np.testing.assert_allclose(momentum, momentum0, rtol=0, atol=1e-9 * np.linalg.norm(momentum0))
    assert 0.5 * plant.angular_velocity @ inertia @ plant.angular_velocity == pytest.approx(energy0, rel=1e-9)
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-14)
    assert np.linalg.norm(plant.quaternion) == pytest.approx(1.0, abs=1e-15)


def test_ground_stops_the_vehicle():
    plant = make_plant(position=[0.0, 0.0, -0.5])
    for _ in range(1000):
        plant.step()
    assert plant.in_contact
    assert plant.position[2] == pytest.approx(-plant.vehicle.contact_height)
    np.testing.assert_allclose(plant.velocity, 0.0)
    assert plant.max_impact_speed == pytest.approx(np.sqrt(2 * GRAVITY * 0.4), rel=1e-2)
    assert plant.divergence() is None


def test_hard_landing_is_reported_as_a_crash():
    plant = make_plant(position=[0.0, 0.0, -3.0])
    for _ in range(1000):
        plant.step()
    assert "crashed into the ground" in plant.divergence()


def test_constant_world_force_and_body_force_disturbances():
    plant = make_plant(
        position=[0.0, 0.0, -20.0], attitude_rpy_deg=[0.0, 0.0, 90.0],
        disturbances=[
            disturbances.constant(force=[1.2, 0.0, 0.0]),
            disturbances.step(0.5, force=[2.4, 0.0, 0.0], torque=[0, 0, 0.1], frame="body"),
        ],
    )
    plant.set_wrench_command(plant.vehicle.weight, np.zeros(3))
    for _ in range(1000):
        plant.step()
    m = plant.vehicle.mass
    # World x: 1.2 N for 1 s. Body x (yaw 90 deg = world y): 2.4 N from 0.5 s on.
    np.testing.assert_allclose(plant.position[:2], [0.5 * 1.2 / m, 0.5 * 2.4 / m * 0.25], atol=1e-3)
    force, torque = plant.external_wrench()
    np.testing.assert_allclose(torque, [0, 0, 0.1])
    assert force[1] == pytest.approx(2.4, abs=1e-2)


def test_ground_effect_raises_thrust_near_the_ground():
    plant = make_plant("octocopter", "rotors", position=[0.0, 0.0, -0.3])
    ratios = plant.thrust_ratios()
    distance = 0.3
    np.testing.assert_allclose(ratios, 1.0 / (1.0 - (0.127 / (4 * distance)) ** 2), rtol=1e-12)


def test_saturated_rotor_command_is_clamped_and_recorded():
    plant = make_plant(actuation="rotors")
    assert plant.set_rotor_command(np.array((500.0, 1500.0, 500.0, 500.0)))
    assert plant.rotor_speeds[1] == 1000.0
    assert plant.saturation.worst_rotor == 2


CEILING = Environment(ceiling=Surface(enabled=True, height=-3.0, effect=True))


def test_ceiling_stops_the_vehicle_at_its_top():
    # Thrust 1.5 x weight from 0.5 m below the ceiling: the top (top_height above the centre) touches it
    # at ~2.2 m/s (below the crash speed) and the vehicle is held there.
    plant = make_plant(position=[0.0, 0.0, -2.4], environment=CEILING)
    assert plant.vehicle.top_height == plant.vehicle.contact_height  # default: symmetric about the CoM
    plant.set_wrench_command(1.5 * plant.vehicle.weight, np.zeros(3))
    for _ in range(1000):
        plant.step()
        assert plant.position[2] >= -3.0 + plant.vehicle.top_height - 1e-12
    assert plant.at_ceiling
    assert plant.position[2] == pytest.approx(-3.0 + plant.vehicle.top_height)
    np.testing.assert_allclose(plant.velocity, 0.0)
    assert 0.0 < plant.max_ceiling_impact_speed < plant.crash_speed
    assert plant.divergence() is None
    plant.set_wrench_command(0.5 * plant.vehicle.weight, np.zeros(3))  # less than the weight: it drops away
    for _ in range(100):
        plant.step()
    assert not plant.at_ceiling and plant.position[2] > -3.0 + plant.vehicle.top_height


def test_hard_ceiling_impact_is_reported_as_a_crash():
    plant = make_plant(position=[0.0, 0.0, -2.0], velocity=[0.0, 0.0, -6.0], environment=CEILING)
    plant.set_wrench_command(plant.vehicle.weight, np.zeros(3))
    for _ in range(300):
        plant.step()
    assert plant.position[2] >= -2.9 - 1e-12
    assert "crashed into the ceiling at 6.00 m/s" in plant.divergence()


def test_top_height_is_a_vehicle_key(tmp_path):
    vehicle = yaml.safe_load((Path(__file__).parents[1] / "fsr_sim/config/vehicles/quadrotor_ex4.yaml").read_text())
    vehicle["top_height"] = 0.04
    path = tmp_path / "flat_top.yaml"
    path.write_text(yaml.safe_dump(vehicle))
    plant = make_plant(str(path), position=[0.0, 0.0, -2.5], environment=CEILING)
    plant.set_wrench_command(1.3 * plant.vehicle.weight, np.zeros(3))
    for _ in range(1500):
        plant.step()
    assert plant.position[2] == pytest.approx(-2.96)


def test_steps_at_the_surface_effect_cap_are_counted_per_surface():
    # Rotor plane 0.1 m below the ceiling: ratio ~1.12 > max_ratio 1.1, so the ceiling ratio is at its cap;
    # the ground (2.9 m below) is far from its cap.
    environment = Environment(ceiling=Surface(enabled=True, height=-3.0, effect=True, max_ratio=1.1))
    plant = make_plant(actuation="rotors", position=[0.0, 0.0, -2.9], environment=environment)
    plant.set_rotor_command(np.full(4, 400.0))
    for _ in range(20):
        plant.step()
    assert plant.ceiling_cap_steps == 20 and plant.ground_cap_steps == 0
    np.testing.assert_allclose(plant.thrust_ratios(), 1.1, rtol=1e-3)  # x the ground ratio ~1.0001
    far = make_plant(actuation="rotors", position=[0.0, 0.0, -1.5], environment=environment)
    far.set_rotor_command(np.full(4, 400.0))
    for _ in range(20):
        far.step()
    assert far.ceiling_cap_steps == 0 and far.ground_cap_steps == 0


@pytest.mark.parametrize(("command", "named"), [
    ({"speeds": [400.0, 400.0, 400.0]}, "speeds: expected shape (4,), got (3,)"),
    ({"speeds": [400.0] * 5}, "speeds: expected shape (4,), got (5,)"),
    ({"speeds": [400.0, float("nan"), 400.0, 400.0]}, "speeds: must be finite"),
    ({"speeds": [400.0] * 4, "tilts": [0.0, 0.0]}, "tilts: expected shape (4,), got (2,)"),
    ({"speeds": [400.0] * 4, "tilts": [0.0, float("inf"), 0.0, 0.0]}, "tilts: must be finite"),
])
def test_a_rotor_command_of_the_wrong_length_or_not_finite_is_refused(command, named):
    plant = Plant(load_vehicle("tilting_quadrotor_ex5"), position=[0, 0, -2])
    before = plant.state_vector.copy()
    with pytest.raises(ValueError, match=named.replace("(", r"\(").replace(")", r"\)")):
        plant.set_rotor_command(**command)
    plant.step()
    assert np.all(np.isfinite(plant.state_vector)) and plant.state_vector[2] >= before[2]  # nothing was applied


def test_a_wrench_command_not_finite_is_refused():
    plant = Plant(load_vehicle("quadrotor_ex4"), actuation="wrench", position=[0, 0, -2])
    with pytest.raises(ValueError, match="torque_body: must be finite"):
        plant.set_wrench([0, 0, -11.0], [0, float("nan"), 0])
    with pytest.raises(ValueError, match="force_body: expected shape"):
        plant.set_wrench([0, -11.0], [0, 0, 0])
