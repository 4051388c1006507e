"""The summary says which part of a flight uses which mass: ex3's plant weighs 1.25 kg, its controller's model
(the vehicle file) 1.2 kg and its estimator's model 1.5 kg."""

from __future__ import annotations

from fsr_bringup import simulate
from fsr_bringup.analysis.metrics import flight_metrics
from fsr_bringup.analysis.summary import summary_rows


def test_ex3s_three_masses_are_named(tmp_path):
    simulate("ex3_estimation", duration=0.1, record=tmp_path / "ex3.mcap")
    metrics = flight_metrics(tmp_path / "ex3.mcap")
    assert metrics["masses"] == {"plant_kg": 1.25, "controller_model_kg": 1.2, "vehicle": "quadrotor_ex4",
                                 "estimator_model_kg": 1.5}
    rows = dict(summary_rows(metrics))
    assert rows["masses [kg]"] == ("plant (true) 1.250, controller's model 1.200 (quadrotor_ex4), "
                                   "estimator's model 1.500")


def test_without_the_estimator_two_masses_are_named(tmp_path):
    simulate("ex4_geometric", set={"estimator.enabled": False}, duration=0.1, record=tmp_path / "ex4.mcap")
    rows = dict(summary_rows(flight_metrics(tmp_path / "ex4.mcap")))
    assert rows["masses [kg]"] == "plant (true) 1.200, controller's model 1.200 (quadrotor_ex4)"
