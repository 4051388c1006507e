"""Command-line mistakes give one line naming the argument (exit 2), not argparse's usage or a traceback."""

from __future__ import annotations

import pytest

from fsr_bringup.cli import analyze_cli, fly_cli
from fsr_bringup.recording.recorder_node import open_writer, parse_args
from fsr_sim.config.scenario import load_scenario
from fsr_sim.recording.reader import open_recording


def one_line(text: str) -> str:
    lines = text.strip().splitlines()
    assert len(lines) == 1, f"expected one line, got {len(lines)}:\n{text}"
    return lines[0]


@pytest.mark.parametrize(
    "argv, named",
    [
        (["ex4_geometric", "--duration", "abc"], "argument --duration: invalid float value: 'abc'"),
        (["ex4_geometric", "--domain-id", "x"], "argument --domain-id"),
        (["ex4_geometric", "--bogus"], "unrecognized arguments: --bogus"),
        ([], "the following arguments are required: scenario"),
    ],
)
def test_fly_argument_errors_are_one_line(capsys, argv, named):
    with pytest.raises(SystemExit) as exit_info:
        fly_cli.main(argv)
    assert exit_info.value.code == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith("fsr-fly: error: ") and named in line


def test_malformed_set_yaml_is_one_line(capsys, tmp_path):
    code = fly_cli.main(["ex4_geometric", "--set", "controller.gains.k_p=[10,10", "--out", str(tmp_path / "a.mcap")])
    assert code == 2
    line = one_line(capsys.readouterr().err)
    assert "controller.gains.k_p" in line and "--set value '[10,10' is not valid YAML at column" in line
    assert not (tmp_path / "a").exists()  # refused before anything was written


def test_malformed_set_yaml_error_from_the_loader():
    with pytest.raises(ValueError) as error:
        load_scenario("ex4_geometric", ["duration={a: 1"])
    assert "\n" not in str(error.value) and "duration: --set value '{a: 1' is not valid YAML" in str(error.value)


def test_analyze_a_directory_says_it_is_a_directory(capsys, tmp_path):
    assert analyze_cli.main([str(tmp_path)]) == 2
    line = one_line(capsys.readouterr().err)
    assert f"{tmp_path}: is a directory; expected an MCAP recording file" in line


def test_analyze_argument_error_is_one_line(capsys):
    with pytest.raises(SystemExit) as exit_info:
        analyze_cli.main(["x.mcap", "--settle", "soon"])
    assert exit_info.value.code == 2
    assert "argument --settle: invalid float value: 'soon'" in one_line(capsys.readouterr().err)


def test_record_argument_error_is_one_line(capsys):
    with pytest.raises(SystemExit) as exit_info:
        parse_args(["--scenario", "ex4_geometric"])
    assert exit_info.value.code == 2
    assert "the following arguments are required: --out" in one_line(capsys.readouterr().err)


def test_record_scenario_accepts_a_built_in_name(tmp_path):
    writer = open_writer(tmp_path / "manual.mcap", "ex4_geometric")
    writer.close()
    stored = open_recording(tmp_path / "manual.mcap").scenario_yaml
    assert stored == load_scenario("ex4_geometric").dump()


def test_record_scenario_file_is_stored_as_written(tmp_path):
    path = tmp_path / "fleet.yaml"
    path.write_text("fleet: []\n", encoding="utf-8")  # the runner's fleet file is not a scenario
    writer = open_writer(tmp_path / "run.mcap", str(path))
    writer.close()
    assert open_recording(tmp_path / "run.mcap").scenario_yaml == "fleet: []\n"


def test_record_unknown_scenario_is_refused(tmp_path):
    with pytest.raises(ValueError, match="--scenario: unknown scenario 'ex9'"):
        open_writer(tmp_path / "run.mcap", "ex9")
