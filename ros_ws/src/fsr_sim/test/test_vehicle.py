import numpy as np
import pytest
import yaml

from fsr_sim.config.validation import ConfigError, builtin_names, resolve_config_path
from fsr_sim.model.vehicle import load_vehicle


def test_builtin_vehicles_load():
    names = builtin_names("vehicles")
    assert {"octocopter", "quadrotor_ex4", "tilting_quadrotor_ex5"} <= set(names)
    assert all(load_vehicle(name).name == name for name in names)  # every shipped file loads, named as its file
    octo = load_vehicle("octocopter")
    assert octo.rotor_count == 8 and not octo.has_servos
    np.testing.assert_array_equal(octo.spins, [-1, 1, -1, 1, -1, 1, -1, 1])
    ex5 = load_vehicle("tilting_quadrotor_ex5")
    assert ex5.has_servos and ex5.mass == 1.32
    np.testing.assert_allclose(ex5.tilt_axes, ex5.positions / 0.45, atol=1e-15)
    np.testing.assert_allclose(load_vehicle("quadrotor_ex4").inertia, np.diag((1.2416, 1.2416, 2.4832)))


def write_vehicle(tmp_path, **changes):
    data = yaml.safe_load(open(resolve_config_path("quadrotor_ex4", "vehicles")))
    data.update(changes)
    path = tmp_path / "v.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"mass": -1.0}, "mass: must be > 0"),
        ({"mass": float("nan")}, "mass: must be finite"),
        ({"inertia": [[1, 0.1, 0], [0, 1, 0], [0, 0, 1]]}, "inertia: must be symmetric"),
        ({"inertia": [1.0, -1.0, 1.0]}, "inertia: must be positive definite"),
        ({"rotor_speed_max": 10.0, "rotor_speed_min": 20.0}, "rotor_speed_max: must be > rotor_speed_min"),
        ({"c_ff": 1.0}, "c_ff: unknown key"),
        ({"layout": {"count": 4, "arm_lenght": 0.2}}, "arm_length: is required .*'arm_lenght'"),
        ({"layout": {"count": 4, "arm_length": 0.2, "tilt": True}}, "layout.tilt: unknown key"),
        ({"rotor_time_constant": -0.005}, "rotor_time_constant: must be >= 0"),
        ({"drag_coefficients": [0.01, -0.01, 0.02]}, "drag_coefficients: must be >= 0"),
        ({"drag_coefficients": [0.01, 0.02]}, "drag_coefficients: expected shape"),
        ({"rotor_drag_coefficient": -1e-4}, "rotor_drag_coefficient: must be >= 0"),
        ({"induced_inflow_coefficient": "small"}, "induced_inflow_coefficient: must be a number"),
        ({"translational_lift_coefficient": float("inf")}, "translational_lift_coefficient: must be finite"),
        ({"flapping_coefficient": -1e-6}, "flapping_coefficient: must be >= 0"),
        ({"rotor_drag_coeficient": 1e-4}, "rotor_drag_coeficient: unknown key .*rotor_drag_coefficient"),
    ],
)
def test_invalid_vehicle_is_refused_with_file_and_key(tmp_path, changes, message):
    path = write_vehicle(tmp_path, **changes)
    with pytest.raises(ConfigError, match=message) as error:
        load_vehicle(path)
    assert str(path) in str(error.value) and "\n" not in str(error.value)


def test_unknown_vehicle_lists_the_builtin_ones():
    with pytest.raises(ConfigError, match="unknown vehicle 'no_such_vehicle'.*octocopter"):
        load_vehicle("no_such_vehicle")


def test_the_rotorpy_vehicles_are_rotorpys_parameters_in_fsrs_frames():
    # rotorpy 3.0.0, hummingbird_params.py / crazyflie_params.py: rotor i at d (+-0.70710678118, ...) in its FLU
    # body, rotor_directions [1, -1, 1, -1] (+1: a reaction torque about +z up, a clockwise rotor)
    flu = np.array(((1.0, 1.0, 0.0), (1.0, -1.0, 0.0), (-1.0, -1.0, 0.0), (-1.0, 1.0, 0.0))) * 0.70710678118
    directions = np.array((1, -1, 1, -1))
    for name, arm, mass, inertia, c_f, c_m, speed_max, tau, drag, rotor in (
            ("hummingbird", 0.17, 0.5, (3.65e-3, 3.68e-3, 7.03e-3), 5.57e-6, 1.36e-7, 1500.0, 0.005,
             (0.5e-2, 0.5e-2, 1e-2), (1.19e-4, 2.32e-4, 3.39e-3, 0.0)),
            ("crazyflie", 0.043, 0.03, (1.43e-5, 1.43e-5, 2.89e-5), 2.3e-8, 7.8e-10, 2500.0, 0.072,
             (0.0, 0.0, 0.0), (10.2506e-07, 7.553e-07, 0.0, 0.0))):
        vehicle = load_vehicle(name)
        np.testing.assert_array_equal(vehicle.positions, arm * flu * (1.0, -1.0, -1.0))  # FLU -> FRD
        np.testing.assert_array_equal(vehicle.spins, -directions)
        np.testing.assert_array_equal(vehicle.inertia, np.diag(inertia))
        assert (vehicle.mass, vehicle.c_f, vehicle.c_m, vehicle.rotor_speed_min, vehicle.rotor_speed_max) == (
            mass, c_f, c_m, 0.0, speed_max)
        assert vehicle.rotor_time_constant == tau
        np.testing.assert_array_equal(vehicle.drag_coefficients, drag)
        assert (vehicle.rotor_drag_coefficient, vehicle.induced_inflow_coefficient,
                vehicle.translational_lift_coefficient, vehicle.flapping_coefficient) == rotor
    assert load_vehicle("hummingbird").rotor_radius == 0.10
    for name in ("octocopter", "quadrotor_ex4", "tilting_quadrotor_ex5"):  # the report's: no lag, no aerodynamics
        vehicle = load_vehicle(name)
        assert vehicle.rotor_time_constant == 0.0 and not vehicle.has_aerodynamics


def test_a_folder_named_like_a_builtin_does_not_shadow_it(tmp_path, monkeypatch):
    # a sweep's --out folder named after its scenario, then the same command again from that folder's parent
    monkeypatch.chdir(tmp_path)
    (tmp_path / "quadrotor_ex4").mkdir()
    (tmp_path / "elsewhere").mkdir()
    assert load_vehicle("quadrotor_ex4").name == "quadrotor_ex4"
    with pytest.raises(ConfigError, match="elsewhere: is a folder, not a vehicle file"):
        load_vehicle("elsewhere")
