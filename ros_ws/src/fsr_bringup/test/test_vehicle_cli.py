import json

from fsr_bringup.cli.vehicle_cli import main


def test_json_has_the_documented_fields(capsys):
    assert main(["tilting_quadrotor_ex5", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("mass", "inertia", "c_f", "c_m", "arm_length", "rotors", "allocation", "allocation_static"):
        assert key in data
    assert len(data["allocation"]) == 6 and len(data["allocation"][0]) == 4
    assert len(data["allocation_static"][0]) == 8
    assert set(data["rotors"][0]) >= {"position", "spin", "tilt_axis"}


def test_markdown_prints_gq_for_the_octocopter(capsys):
    assert main(["octocopter"]) == 0
    out = capsys.readouterr().out
    assert "G_q (rows f_z, tau_x, tau_y, tau_z)" in out and "| u_w8 |" in out


def test_unknown_vehicle_exits_2_with_a_message(capsys):
    assert main(["hexacopter"]) == 2
    assert "unknown vehicle 'hexacopter'" in capsys.readouterr().err


def test_json_and_markdown_include_the_contact_height(capsys):
    assert main(["octocopter", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    from fsr_sim.model.vehicle import load_vehicle

    assert data["contact_height"] == load_vehicle("octocopter").contact_height
    assert main(["quadrotor_ex4"]) == 0
    assert "| contact height" in capsys.readouterr().out


def test_bad_argument_is_one_line_exit_2(capsys):
    import pytest

    with pytest.raises(SystemExit) as exit_info:
        main(["octocopter", "--jsn"])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--jsn" in err and err.startswith("fsr-vehicle: error:")


def test_json_and_markdown_print_the_authority_at_margin_1(capsys):
    import pytest

    from fsr_control.design.authority import authority
    from fsr_sim.model.vehicle import load_vehicle

    for name in ("quadrotor_ex4", "octocopter", "tilting_quadrotor_ex5"):
        assert main([name, "--json"]) == 0
        data = json.loads(capsys.readouterr().out)["authority"]
        expected = authority(load_vehicle(name)).as_dict()
        assert data.keys() == expected.keys()
        for key, value in expected.items():
            assert data[key] == (None if value is None else pytest.approx(value, rel=1e-12)), key
        assert data["margin"] == 1.0
        assert set(data) >= {"thrust_min", "thrust_max", "roll_torque", "pitch_torque", "yaw_torque",
                             "roll_acceleration", "pitch_acceleration", "yaw_acceleration", "tilt_max"}
        assert (data["tilt_max"] is None) == (name != "tilting_quadrotor_ex5")
    assert main(["quadrotor_ex4"]) == 0
    out = capsys.readouterr().out
    assert "Authority at hover (margin 1: the model's limits" in out
    assert "| yaw torque (+-) | 0.1547 N m" in out and "| roll torque (+-) | 2.649 N m" in out


def test_a_vehicle_that_cannot_hover_is_still_printed_with_the_reason(tmp_path, capsys):
    import yaml

    from fsr_sim.config.validation import builtin_config_dir

    data = yaml.safe_load((builtin_config_dir("vehicles") / "quadrotor_ex4.yaml").read_text())
    path = tmp_path / "heavy.yaml"
    path.write_text(yaml.safe_dump({**data, "name": "heavy", "mass": 20.0}))
    assert main([str(path), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["authority"] is None and "vehicle 'heavy' cannot hover" in data["authority_error"]
    assert main([str(path)]) == 0
    assert "Authority at hover: none (vehicle 'heavy' cannot hover" in capsys.readouterr().out


def test_the_rotorpy_vehicles_print_their_authority_lag_and_aerodynamics(capsys):
    assert main(["hummingbird", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["rotor_time_constant"] == 0.005 and data["drag_coefficients"] == [0.005, 0.005, 0.01]
    assert data["rotor_drag_coefficient"] == 1.19e-4 and data["translational_lift_coefficient"] == 3.39e-3
    authority = data["authority"]
    assert authority["thrust_max"] == __import__("pytest").approx(4 * 5.57e-6 * 1500.0**2)
    assert authority["roll_torque"] > 0.5 and authority["yaw_torque"] > 0.1  # 0.590 and 0.120 N m
    assert main(["crazyflie"]) == 0
    out = capsys.readouterr().out
    assert "| roll torque (+-) |" in out and "| rotor time constant | 0.072 s |" in out
    assert "| hover rotor speed | 1788.6 rad/s |" in out


def test_the_gains_the_geometric_law_flies_on_the_imu_are_printed_too(capsys):
    """The flight profile's law on the IMU (``controller.use_imu``) is designed for less lag: the octocopter's
    attitude loop, set by the lag, is faster there; the catalog flies exactly these gains; a fully actuated vehicle
    has none, and where no loop is set by the lag the markdown says the gains are the same."""
    import numpy as np

    from fsr_control.controllers.catalog import LAWS
    from fsr_sim.model.vehicle import load_vehicle

    assert main(["octocopter", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    odometry, imu = data["designed_gains"], data["designed_gains_imu"]
    assert odometry["lag_s"] == 0.045 and imu["lag_s"] == 0.0305
    assert imu["attitude"] > odometry["attitude"] and imu["limits"]["attitude"] == "lag"
    flown = LAWS["geometric"].designed_gains(load_vehicle("octocopter"), True)
    for name, value in imu["wrench_gains"].items():
        np.testing.assert_array_equal(flown[name], value)
    assert main(["octocopter"]) == 0
    assert "for 30.5 ms of lag (motor and half an IMU sample" in capsys.readouterr().out
    assert main(["quadrotor_ex4"]) == 0
    assert "the same gains: no loop is set by the lag" in capsys.readouterr().out
    assert main(["tilting_quadrotor_ex5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["designed_gains_imu"] is None
