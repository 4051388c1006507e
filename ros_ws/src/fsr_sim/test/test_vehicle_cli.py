import json

from fsr_sim.cli.vehicle_cli import main


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
