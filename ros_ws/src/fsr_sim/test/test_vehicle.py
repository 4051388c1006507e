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
    ],
)
def test_invalid_vehicle_is_refused_with_file_and_key(tmp_path, changes, message):
    path = write_vehicle(tmp_path, **changes)
    with pytest.raises(ConfigError, match=message) as error:
        load_vehicle(path)
    assert str(path) in str(error.value)


def test_unknown_vehicle_lists_the_builtin_ones():
    with pytest.raises(ConfigError, match="unknown vehicle 'no_such_vehicle'.*octocopter"):
        load_vehicle("no_such_vehicle")
