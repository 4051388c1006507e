import json

import numpy as np
import pytest

from fsr_estimation.cli.estimate_cli import main, parse_orders

REPORT_ARGS = ["--mass", "1.5", "--inertia", "1.2416,1.2416,2.4832", "--c0", "10", "--r", "1:5",
               "--truth", "1,1,0,0,0,-0.4"]


def table_rows(text, title):
    """Rows of the Markdown table after the line starting with ``title``, as lists of cells."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(title))
    rows = []
    for line in lines[start + 4:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows


def check_report_tables(text, ref):
    settle = table_rows(text, "Settling time")
    errors = table_rows(text, "Mean absolute error")
    mass = table_rows(text, "Mass estimate")
    assert [row[:2] for row in settle] == [["10", str(r)] for r in range(1, 6)]
    for r in range(1, 6):
        expected = ref.REPORT_TABLE[r]
        assert settle[r - 1][2:] == [f"{v:.3f}" for v in expected[:3]], f"Table 3, r = {r}"
        assert errors[r - 1][2:5] == [f"{v:.4f}" for v in expected[3:]], f"Table 4 MAE, r = {r}"
        assert mass[r - 1][2:] == ["-0.250", "1.250"]


def test_report_tables_from_the_shipped_mcap(ref, capsys):
    code = main([str(ref.EXAMPLE_MCAP), *REPORT_ARGS, "--settling", "report"])
    assert code == 0
    check_report_tables(capsys.readouterr().out, ref)


def test_report_tables_and_max_errors_from_the_mat(ref, report_mat, capsys, tmp_path):
    out = tmp_path / "results.json"
    assert main([str(report_mat), *REPORT_ARGS, "--settling", "report", "--after", "25", "--json", str(out)]) == 0
    check_report_tables(capsys.readouterr().out, ref)
    results = json.loads(out.read_text())
    assert [(item["c0"], item["r"]) for item in results] == [(10.0, r) for r in range(1, 6)]
    for item in results:
        assert set(item) == {"c0", "r", "dm", "m_real", "settling_time", "mae", "max_error"}
        assert item["settling_time"]["fz"] is None and item["settling_time"]["tx"] is None
        fx, fy, tz = ref.REPORT_MAX_ERROR[item["r"]]
        assert item["max_error"]["fx"] == pytest.approx(fx, rel=5e-6)
        assert item["max_error"]["fy"] == pytest.approx(fy, rel=5e-6)
        assert item["max_error"]["tz"] == pytest.approx(tz, rel=1e-12)
        assert item["dm"] == pytest.approx(-0.25, abs=5e-4)


def test_standard_settling_values(ref, capsys):
    args = [str(ref.EXAMPLE_MCAP), "--mass", "1.5", "--inertia", "1.2416,1.2416,2.4832", "--c0", "10", "--r", "1",
            "--truth", "1,1,0,0,0,-0.4"]
    assert main(args) == 0
    settle = table_rows(capsys.readouterr().out, "Settling time")
    assert settle == [["10", "1", "1.750", "1.752", "0.544"]]


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_plots_and_json_without_truth(tmp_path, synthetic, capsys):
    log, _ = synthetic(n=1500)
    header = "time,roll,pitch,yaw,roll_rate,pitch_rate,yaw_rate,vx,vy,vz,fx,fy,fz,tx,ty,tz"
    table = np.column_stack((log.time, log.eta, log.eta_dot, log.velocity_world, log.force_body, log.torque_body))
    np.savetxt(tmp_path / "log.csv", table, delimiter=",", header=header, comments="", fmt="%.17g")
    plots = tmp_path / "figures"
    args = [str(tmp_path / "log.csv"), "--mass", "1.5", "--inertia", "1.2416,1.2416,2.4832", "--c0", "5,20",
            "--r", "1,2", "--truth", "0.3,-0.2,-0.5,0,0,0", "--plots", str(plots)]
    assert main(args) == 0
    names = sorted(p.name for p in plots.iterdir())
    assert names == sorted(["estimates_r1.png", "estimates_r2.png", "estimates_c0_5.png", "estimates_c0_20.png",
                            "error_c0_5.png", "error_c0_20.png", "mae_vs_r.png", "settling_vs_r.png"])
    assert all((plots / n).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" for n in names)
    capsys.readouterr()
    out = tmp_path / "no_truth.json"
    assert main([*args[:9], "--json", str(out)]) == 0
    assert "Settling" not in capsys.readouterr().out
    item = json.loads(out.read_text())[0]
    assert item["mae"] == dict.fromkeys(("fx", "fy", "fz", "tx", "ty", "tz"))


def test_order_lists_and_ranges():
    assert parse_orders("1:5") == [1, 2, 3, 4, 5]
    assert parse_orders("1,3") == [1, 3]
    assert parse_orders("1:3,5,2") == [1, 2, 3, 5]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"--r": "0"}, "--r: filter orders must be integers >= 1"),
        ({"--r": "5:1"}, "--r: bad range"),
        ({"--r": "a"}, "--r: expected integers"),
        ({"--c0": "abc"}, "--c0: expected comma-separated numbers"),
        ({"--c0": "-1"}, "--c0: must be a finite number > 0"),
        ({"--c0": "5000"}, "unstable"),
        ({"--mass": "0"}, "--mass: must be"),
        ({"--inertia": "1,2"}, "--inertia: expected 3 numbers"),
        ({"--inertia": "1,-1,1"}, "--inertia: must be positive definite"),
        ({"--truth": "1,1,0"}, "--truth: expected 6 numbers"),
        ({"LOG": "missing.mcap"}, "missing.mcap: no such file"),
        ({"--settling": "fast"}, "invalid choice"),
        ({"--mass": None}, "required: --mass"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(ref, tmp_path, capsys, change, message):
    options = {"LOG": str(tmp_path / "log.csv"), "--mass": "1.5", "--inertia": "1,1,2", "--c0": "10", "--r": "1"}
    tmp_path.joinpath("log.csv").write_text(
        "time,roll,pitch,yaw,roll_rate,pitch_rate,yaw_rate,vx,vy,vz,thrust,tx,ty,tz\n"
        + "".join(f"{k * 0.001},0,0,0,0,0,0,0,0,0,14.715,0,0,0\n" for k in range(20)))
    options.update(change)
    argv = [options.pop("LOG")]
    for key, value in options.items():
        if value is not None:
            argv += [key, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("fsr-estimate: error: ")
    assert message in err


def cut_in_half(source, tmp_path):
    """The shipped recording cut at half its size, like a copy interrupted or a recorder killed."""
    data = source.read_bytes()
    path = tmp_path / "half.mcap"
    path.write_bytes(data[: len(data) // 2])
    return path


def test_truncated_mcap_is_refused_with_the_time_it_covers(ref, tmp_path, capsys):
    half = cut_in_half(ref.EXAMPLE_MCAP, tmp_path)
    code = main([str(half), *REPORT_ARGS])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1
    assert "truncated" in lines[0] and "--allow-truncated" in lines[0]
    covered = [float(v) for v in lines[0].split("t = ")[1].split(" s")[0].split(" .. ")]
    assert covered[0] == pytest.approx(0.0, abs=0.01)
    assert 1.0 < covered[1] < 20.0  # part of the 30 s flight, not all of it


def test_truncated_mcap_is_used_with_allow_truncated_and_a_warning(ref, tmp_path, capsys):
    half = cut_in_half(ref.EXAMPLE_MCAP, tmp_path)
    code = main([str(half), *REPORT_ARGS, "--allow-truncated", "--json", str(tmp_path / "out.json")])
    captured = capsys.readouterr()
    assert code == 0
    assert captured.err.startswith("fsr-estimate: warning:") and "truncated" in captured.err
    assert len(captured.err.strip().splitlines()) == 1
    assert "Settling time" in captured.out
    end = float(captured.err.split(" .. ")[1].split(" s")[0])
    assert end < 20.0


def test_complete_mcap_prints_no_warning(ref, capsys):
    assert main([str(ref.EXAMPLE_MCAP), *REPORT_ARGS]) == 0
    assert capsys.readouterr().err == ""
