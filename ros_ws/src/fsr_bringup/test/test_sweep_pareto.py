"""fsr-sweep --pareto X,Y: the front is the set of finished flights no other finished flight dominates (checked
against brute force), NaN / inf / unfinished flights are never on it, bad names are refused, the CLI writes the
column, the summary section and the figure."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

from fsr_bringup.sweeps.axes import SweepError
from fsr_bringup.sweeps.metrics import METRIC_COLUMNS
from fsr_bringup.sweeps.pareto import non_dominated, pareto_front, parse_pareto
from fsr_bringup.sweeps.report import summary_markdown, write_figures


def brute_force_front(points: np.ndarray) -> np.ndarray:
    dominated = [any((q <= p).all() and (q < p).any() for q in points) for p in points]
    return ~np.array(dominated, dtype=bool)


@pytest.mark.parametrize("seed", range(20))
def test_the_front_is_what_no_other_point_dominates(seed):
    rng = np.random.default_rng(seed)
    points = rng.integers(0, 6, size=(int(rng.integers(1, 40)), 2)).astype(float)  # ties and duplicates
    np.testing.assert_array_equal(non_dominated(points), brute_force_front(points))


def test_the_front_trades_one_metric_for_the_other():
    points = np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 1.0], [3.0, 3.0], [1.0, 5.0], [4.0, 1.0]])
    assert non_dominated(points).tolist() == [True, True, True, False, True, False]


def sweep_table() -> pd.DataFrame:
    table = pd.DataFrame({
        "estimator.c0": [1.0, 5.0, 10.0, 50.0, 100.0, 25.0],
        "end_reason": ["finished", "finished", "finished", "finished", "diverged", "finished"],
        "end_detail": ["", "", "", "", "position error 12 m > 10 m", ""],
        "estimate_settling_s": [20.0, 5.0, 2.0, math.inf, 0.1, math.nan],
        "estimate_force_rms_N": [0.01, 0.02, 0.05, 0.001, 0.0, 0.0],
    })
    table.index.name = "flight"
    table.attrs.update(scenario="ex3_estimation_noisy", keys=["estimator.c0"], grid=["estimator.c0"], seed=0,
                       flights=6, wall_s=1.0, vehicle_steps=6000, workers=1, startup_s=0.1)
    return table


def test_diverged_nan_and_infinite_flights_are_never_on_the_front():
    front = pareto_front(sweep_table(), "estimate_settling_s", "estimate_force_rms_N")
    assert front.tolist() == [True, True, True, False, False, False]


def test_the_summary_lists_the_front_and_the_figure_is_written(tmp_path):
    table = sweep_table()
    table["pareto"] = pareto_front(table, "estimate_settling_s", "estimate_force_rms_N")
    text = summary_markdown(table, "estimate_force_rms_N", "fsr-sweep ...", ("estimate_settling_s",
                                                                           "estimate_force_rms_N"))
    section = text.split("## Pareto front of estimate_settling_s and estimate_force_rms_N")[1]
    assert "3 of 5 finished flights" in section
    rows = [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("| flight")]
    assert [row.split(" | ")[1] for row in rows] == ["10", "5", "1"]  # by settling time
    paths = write_figures(table, tmp_path, "estimate_force_rms_N", ("estimate_settling_s", "estimate_force_rms_N"))
    assert tmp_path / "pareto.png" in paths and (tmp_path / "pareto.png").stat().st_size > 0


@pytest.mark.parametrize(("text", "message"), [
    ("estimate_settling_s", "expected two metrics X,Y"),
    ("estimate_settling_s,", "expected two metrics X,Y"),
    ("estimate_settling,estimate_force_rms_N", "unknown metric 'estimate_settling'"),
    ("estimate_force_rms_N,estimate_force_rms_N", "must differ"),
])
def test_bad_metric_pairs_are_refused_naming_them(text, message):
    with pytest.raises(SweepError, match=message):
        parse_pareto(text, METRIC_COLUMNS)


def fsr_sweep(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "fsr_bringup.cli.sweep_cli", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=240)


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_the_cli_refuses_an_unknown_metric_before_flying(tmp_path):
    result = fsr_sweep("ex3_estimation", "--grid", "estimator.c0=5,50", "--pareto", "settling,estimate_force_rms_N",
                       "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert result.returncode == 2
    assert "unknown metric 'settling'" in result.stderr and len(result.stderr.strip().splitlines()) <= 3
    assert not (tmp_path / "out").exists()


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_the_cli_marks_the_front(tmp_path):
    out = tmp_path / "sweep"
    result = fsr_sweep("ex3_estimation", "--grid", "estimator.c0=2,10,50", "--grid", "estimator.r=1,2",
                       "--duration", "1.0", "--pareto", "position_error_rms_m,estimate_force_rms_N",
                       "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    table = pd.read_csv(out / "results.csv", index_col="flight")
    expected = pareto_front(table, "position_error_rms_m", "estimate_force_rms_N")
    assert table["pareto"].tolist() == expected.tolist() and table["pareto"].any()
    assert "## Pareto front of position_error_rms_m and estimate_force_rms_N" in (out / "summary.md").read_text()
    assert (out / "pareto.png").stat().st_size > 0
