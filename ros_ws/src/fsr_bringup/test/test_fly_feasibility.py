"""fsr-fly checks every leg against the vehicle's authority before take-off: one line per infeasible leg with
the numbers, ``refuse`` exits 2 before anything is written, ``stretch`` flies the lengthened leg and the
summary says so."""

from __future__ import annotations

import json

import pytest

from fsr_bringup.cli import fly_cli

LEG = "trajectory.waypoints.0={position: [2, 3, -6], attitude_rpy_deg: [0, 0, 0], duration: 2.5}"


def test_refuse_exits_2_before_take_off_with_the_numbers(capsys, tmp_path):
    code = fly_cli.main(["ex4_geometric", "--in-process", "--set", "actuation=rotors", "--set", LEG, "--set",
                         "trajectory.feasibility=refuse", "--out", str(tmp_path / "refused.mcap")])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "trajectory.waypoints.0: leg 1 (2.5 s) needs 11.6 N m of roll torque, the rotors give 2.65 N m at hover" \
        in err and "it needs at least 4.43 s; refused (trajectory.feasibility: refuse)" in err
    assert not (tmp_path / "refused").exists() and not (tmp_path / "refused.mcap").exists()


@pytest.mark.slow
def test_stretch_prints_the_leg_flies_it_and_the_summary_lists_it(capsys, tmp_path):
    out = tmp_path / "stretched.mcap"
    code = fly_cli.main(["ex4_geometric", "--in-process", "--quiet", "--set", "actuation=rotors", "--set", LEG,
                         "--duration", "6", "--out", str(out)])
    assert code == 0
    stdout = capsys.readouterr().out
    line = next(line for line in stdout.splitlines() if "leg 1 (2.5 s)" in line)
    assert line.startswith("fsr-fly: ex4_geometric: leg 1 (2.5 s) needs ") and line.endswith("stretched to 4.43 s")
    metrics = json.loads((tmp_path / "stretched" / "metrics.json").read_text())
    (adjustment,) = metrics["plan_adjustments"]
    assert adjustment["action"] == "stretched" and adjustment["position_duration_s"] == 4.43
    summary = (tmp_path / "stretched" / "summary.md").read_text()
    assert "| legs and paths beyond the authority | leg 1 (2.5 s)" in summary
    assert metrics["tracking"]["position_error_m"]["final"] <= 1e-3
