"""fsr-sweep: every row is the flight simulate() flies with those values; divergences are rows; bad keys and
distributions are refused naming the key; a seed gives one table; the CLI writes its files."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from fsr_bringup import simulate, sweep
from fsr_bringup.sweeps.axes import SweepError
from fsr_bringup.sweeps.metrics import METRIC_COLUMNS, flight_row

TEXT_COLUMNS = ("end_reason", "end_detail", "gave_way")


def assert_row_is_simulated(table, number: int, scenario: str, fixed: dict, duration: float) -> None:
    """Row ``number`` equals the metrics of simulate() with the row's swept values (to 1e-9)."""
    values = {key: table.at[number, key] for key in table.attrs["keys"]}
    values = {k: (v.item() if hasattr(v, "item") else v) for k, v in values.items()}
    expected = flight_row(simulate(scenario, set={**fixed, **values}, duration=duration))
    for column in METRIC_COLUMNS:
        got, want = table.at[number, column], expected[column]
        if column in TEXT_COLUMNS:
            assert got == want, (number, column)
        elif math.isnan(want):
            assert math.isnan(got), (number, column, got)
        else:
            assert got == pytest.approx(want, rel=1e-9, abs=1e-12), (number, column)


@pytest.mark.parametrize(("scenario", "fixed", "grid", "sample"), [
    ("ex4_geometric", {"actuation": "rotors"},
     {"controller.gains.k_p": [[7, 7, 40], [12, 12, 55]], "plant.mass": [1.1, 1.3]},
     {"estimator.c0": "loguniform:2:50"}),
    ("ex5_voliro", {"disturbances": [{"kind": "constant", "frame": "world", "force": [0.5, 0.0, 0.0]}]},
     {"plant.mass": [1.9, 2.1]}, {"disturbances.0.force.0": "normal:0.5:0.2"}),
    ("octo_ground_effect", {}, {"estimator.r": [1, 3]}, {"plant.mass": "uniform:2.2:2.8"}),
])
def test_rows_of_a_grid_and_a_sample_equal_simulate(scenario, fixed, grid, sample):
    duration = 1.5
    table = sweep(scenario, grid=grid, sample=sample, n=3, seed=4, duration=duration, set=fixed, workers=2)
    points = math.prod(len(v) for v in grid.values())
    assert len(table) == points * 3 and list(table.columns[:len(table.attrs["keys"])]) == [*grid, *sample]
    assert set(table["end_reason"]) == {"finished"}
    assert table.attrs["vehicle_steps"] == len(table) * int(round(duration / 0.001))
    rng = np.random.default_rng(len(scenario))
    for number in rng.choice(len(table), size=2, replace=False):
        assert_row_is_simulated(table, int(number), scenario, fixed, duration)


def test_a_grid_is_the_product_in_order_and_a_seed_gives_one_table():
    grid = {"plant.mass": [1.1, 1.2, 1.3], "estimator.r": [1, 2]}
    first = sweep("ex4_geometric", grid=grid, sample={"estimator.c0": "uniform:5:20"}, n=2, seed=7, duration=0.3)
    assert list(first["plant.mass"]) == [1.1] * 4 + [1.2] * 4 + [1.3] * 4
    assert list(first["estimator.r"]) == [1, 1, 2, 2] * 3
    assert list(first["estimator.c0"][:2]) == list(first["estimator.c0"][2:4])  # the draws repeat per grid point
    again = sweep("ex4_geometric", grid=grid, sample={"estimator.c0": "uniform:5:20"}, n=2, seed=7, duration=0.3,
                  workers=1)
    assert first.equals(again)
    other = sweep("ex4_geometric", grid=grid, sample={"estimator.c0": "uniform:5:20"}, n=2, seed=8, duration=0.3)
    assert not np.array_equal(first["estimator.c0"], other["estimator.c0"])


def test_a_diverging_or_refused_flight_is_a_row_and_the_sweep_goes_on():
    table = sweep("ex4_geometric", grid={"plant.mass": [1.2, 30.0, -1.0, 1.25]}, set={"actuation": "rotors"},
                  duration=2.0)
    assert list(table["end_reason"]) == ["finished", "diverged", "invalid", "finished"]
    assert "crashed into the ground" in table.at[1, "end_detail"]
    assert "plant.mass" in table.at[2, "end_detail"] and "must be > 0" in table.at[2, "end_detail"]
    assert table.at[1, "saturated_fraction"] > 0.5 and "force_z" in table.at[1, "gave_way"]
    assert math.isnan(table.at[2, "position_error_rms_m"])
    assert_row_is_simulated(table, 1, "ex4_geometric", {"actuation": "rotors"}, 2.0)


def test_sampled_integer_keys_are_rounded():
    table = sweep("ex3_estimation", sample={"estimator.r": "uniform:1:3"}, n=4, duration=0.2, workers=1)
    assert all(isinstance(v, int) and 1 <= v <= 3 for v in table["estimator.r"])


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"grid": {"controller.type": [1, 2]}}, "controller.type: not a numeric leaf"),
    ({"sample": {"trajectory.waypoints.0.position": "uniform:1:2"}, "n": 2}, "a list of 3"),
    ({"grid": {"plant.mas": [1.0]}}, "did you mean 'mass'"),
    ({"grid": {"trajectory.waypoints.7.duration": [1.0]}}, "out of range"),
    ({"sample": {"plant.mass": "uniform:2:1"}, "n": 2}, "LO > HI"),
    ({"sample": {"plant.mass": "gamma:1:2"}, "n": 2}, "unknown distribution 'gamma'"),
    ({"sample": {"plant.mass": "uniform:1:2"}}, "needs n >= 1"),
    ({"grid": {"plant.mass": ["heavy"]}}, "not a number"),
    ({}, "nothing to sweep"),
])
def test_bad_keys_and_distributions_are_refused_naming_them(kwargs, message):
    with pytest.raises(SweepError, match=message.replace("(", r"\(")):
        sweep("ex4_geometric", duration=0.1, **kwargs)


def fsr_sweep(*args: str, cwd) -> subprocess.CompletedProcess:
    command = [sys.executable, "-m", "fsr_bringup.cli.sweep_cli", *args]
    return subprocess.run(command, capture_output=True, text=True, cwd=cwd, timeout=240)


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.parametrize(("args", "message"), [
    (["--grid", "plant.mas=1,2"], "did you mean 'mass'"),
    (["--sample", "plant.mass=uniform:1.5:1.0", "--n", "3"], "LO > HI"),
    (["--grid", "controller.type=1,2"], "controller.type: not a numeric leaf"),
    (["--grid", "plant.mass"], "expected KEY=V1,V2"),
])
def test_the_cli_exits_2_with_one_line_naming_the_key(tmp_path, args, message):
    result = fsr_sweep("ex4_geometric", "--duration", "0.1", "--out", str(tmp_path / "out"), *args, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.parametrize("out", ["/proc/fsr_sweep_out", "/dev/null/sweep"])
def test_an_unwritable_output_folder_is_refused_before_any_flight(tmp_path, out):
    result = fsr_sweep("ex4_geometric", "--duration", "60", "--sample", "plant.mass=uniform:1:2", "--n", "1000",
                       "--out", out, cwd=tmp_path)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"fsr-sweep: --out: cannot write to '{out}'"), result.stderr


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_the_cli_writes_the_table_summary_figures_and_recordings(tmp_path):
    import pandas as pd

    out = tmp_path / "sweep"
    result = fsr_sweep("ex3_estimation", "--grid", "estimator.c0=5,50", "--grid", "estimator.r=1,2",
                       "--sample", "plant.mass=uniform:1.2:1.3", "--n", "3", "--duration", "0.5",
                       "--record-best", "1", "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out / "results.csv", index_col="flight")
    assert len(table) == 12 and list(table.columns[:3]) == ["estimator.c0", "estimator.r", "plant.mass"]
    summary = (out / "summary.md").read_text()
    assert "12 finished" in summary and "## Best" in summary and "vehicle-steps/s" in summary
    for name in ("heatmap.png", "estimator.c0.png", "plant.mass.png", "ecdf.png", "best_1.mcap", "worst_1.mcap"):
        assert (out / name).stat().st_size > 0, name
    best = table.sort_values("position_error_rms_m").iloc[0]
    from fsr_bringup.analysis.metrics import flight_metrics

    recorded = flight_metrics(out / "best_1.mcap")
    assert recorded["tracking"]["position_error_m"]["rms"] == pytest.approx(best["position_error_rms_m"], rel=1e-6)
