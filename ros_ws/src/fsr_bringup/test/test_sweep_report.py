"""What fsr-sweep writes from its table: every swept key has a figure (list-valued gains as categories), the
best and worst flights are listed once each, the quantiles say how many flights had no finite value, axes carry
units, and ``sweep(pareto=...)`` marks the front as ``--pareto`` does."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from fsr_bringup.sweeps.axes import key_label
from fsr_bringup.sweeps.pareto import pareto_front
from fsr_bringup.sweeps.report import key_figure, summary_markdown, write_figures


def table_of(count: int, keys: dict[str, list]) -> pd.DataFrame:
    table = pd.DataFrame({**keys, "end_reason": ["finished"] * count, "end_detail": [""] * count,
                          "position_error_rms_m": np.arange(count, dtype=float) / 100.0,
                          "position_error_peak_m": np.arange(count, dtype=float) / 10.0,
                          "settling_time_s": [math.inf if i % 3 == 0 else (math.nan if i % 3 == 1 else float(i))
                                              for i in range(count)]})
    table.index.name = "flight"
    table.attrs.update(scenario="ex4_geometric", keys=list(keys), grid=list(keys), seed=0, flights=count, wall_s=1.0,
                       vehicle_steps=count * 1000, workers=1, startup_s=0.1)
    return table


def listed(section: str) -> list[int]:
    return [int(line.split(" | ")[0].strip("| ")) for line in section.strip().splitlines()[2:]
            if line.startswith("| ") and not line.startswith("| flight")]


def test_nine_flights_are_listed_once_best_first():
    text = summary_markdown(table_of(9, {"plant.mass": list(np.linspace(1.0, 1.8, 9))}), "position_error_rms_m")
    assert "## Worst" not in text and "## Best" not in text
    assert listed(text.split("## All 9 finished flights, best first")[1]) == list(range(9))


def test_best_and_worst_never_share_a_flight():
    text = summary_markdown(table_of(15, {"plant.mass": list(np.linspace(1.0, 2.4, 15))}), "position_error_rms_m")
    best = listed(text.split("## Best 10")[1].split("## Worst")[0])
    worst = listed(text.split("## Worst 5")[1])
    assert best == list(range(10)) and worst == [14, 13, 12, 11, 10]


def test_the_quantiles_count_the_flights_that_never_settled_and_those_without_a_value():
    text = summary_markdown(table_of(9, {"plant.mass": list(np.linspace(1.0, 1.8, 9))}), "position_error_rms_m")
    row = next(line for line in text.splitlines() if line.startswith("| settling_time_s |"))
    cells = [cell.strip() for cell in row.strip("|").split("|")]
    assert cells[1:6] == ["2", "2.3", "5", "7.7", "8"] and cells[6:] == ["3", "3"]  # finite: 2, 5, 8


def test_a_list_valued_gain_gets_its_figure_with_the_values_as_categories(tmp_path):
    gains = [[7, 7, 40], [12, 12, 55], [20, 20, 100]]
    table = table_of(6, {"controller.gains.k_p": [gains[i % 3] for i in range(6)]})
    paths = write_figures(table, tmp_path, "position_error_rms_m")
    assert tmp_path / "controller.gains.k_p.png" in paths
    fig = key_figure(table, "controller.gains.k_p", "position_error_rms_m")
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["[7,7,40]", "[12,12,55]", "[20,20,100]"]
    assert ax.get_xlabel() == "controller.gains.k_p [N/m]"
    np.testing.assert_array_equal(ax.lines[0].get_xdata(), [0, 1, 2, 0, 1, 2])


@pytest.mark.parametrize(("key", "label"), [
    ("plant.mass", "plant.mass [kg]"), ("estimator.c0", "estimator.c0 [rad/s]"),
    ("controller.gains.k_p.2", "controller.gains.k_p.2 [N/m]"), ("disturbances.0.force", "disturbances.0.force [N]"),
    ("plant.rotor_time_constant", "plant.rotor_time_constant [s]"), ("something.unknown", "something.unknown"),
])
def test_axis_labels_carry_the_keys_unit(key, label):
    assert key_label(key) == label


@pytest.mark.slow
def test_sweep_marks_the_pareto_front_as_the_command_does():
    from fsr_bringup import sweep

    table = sweep("ex3_estimation", grid={"estimator.c0": [2, 50]}, duration=0.5, workers=1,
                  pareto="position_error_rms_m,estimate_force_rms_N")
    expected = pareto_front(table, "position_error_rms_m", "estimate_force_rms_N")
    assert table["pareto"].tolist() == expected.tolist() and table["pareto"].any()


def test_the_settling_time_counts_from_the_references_arrival():
    from fsr_bringup.sweeps.metrics import settled_after_arrival

    def time(k: int) -> float:  # 11 samples, 0.1 s apart
        return 0.1 * k if k < 11 else math.inf

    # the reference at rest from sample 4 (0.4 s), the error within the band from sample 7 (0.7 s)
    assert settled_after_arrival(1.0, 4, 7, time) == pytest.approx(0.3)
    assert settled_after_arrival(1.0, 4, 0, time) == 0.0  # within the band on arrival
    assert settled_after_arrival(1.0, 4, 11, time) == math.inf  # ends outside
    assert math.isnan(settled_after_arrival(1.0, 11, 7, time))  # the reference still moves
    assert settled_after_arrival(1.0, 0, 7, time) == pytest.approx(0.7)  # at rest from the start


@pytest.mark.slow
def test_a_flight_ended_before_its_leg_has_no_settling_time_and_one_after_it_has():
    from fsr_bringup import sweep

    table = sweep("ex4_geometric", grid={"duration": [5.0, 25.0]}, workers=1)
    assert math.isnan(table.loc[0, "settling_time_s"])  # the 20 s leg is still flown at 5 s
    assert 0.0 <= table.loc[1, "settling_time_s"] < 5.0
