"""Tracking errors are taken on the true state: with a sensor stage on, the recording holds the true state on
``odom_truth`` beside the measured ``odom``, and the summary, ``fsr-sweep`` and ``simulate()`` report the same
metrics of one flight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_bringup import simulate
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.analysis.metrics import flight_metrics
from fsr_bringup.analysis.summary import markdown_summary
from fsr_bringup.sweeps.metrics import flight_row
from fsr_sim.contract import ODOM, ODOM_TRUTH
from fsr_sim.recording.reader import open_recording

NOISY = {"sensors.odometry": {"position_std": 0.01, "seed": 1}}


def _close(a, b, path="") -> None:
    """Nested metrics equal, numbers to 1e-12 (relative)."""
    if isinstance(a, dict):
        assert set(a) == set(b), path
        for key in a:
            _close(a[key], b[key], f"{path}.{key}")
    elif isinstance(a, list):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert b == pytest.approx(a, rel=1e-12, abs=1e-15), path
    else:
        assert a == b, path


def test_a_noisy_flight_is_measured_on_its_true_state_alike_in_summary_sweep_and_simulate(tmp_path):
    path = tmp_path / "noisy.mcap"
    run = simulate("ex4_geometric", set=NOISY, duration=1.0, record=path)
    recording = open_recording(path)
    assert recording.count("/" + ODOM_TRUTH.name) == recording.count("/" + ODOM.name) == len(run.time)
    true_rms = float(np.sqrt(np.mean(np.sum((run.position - run.reference_position) ** 2, axis=1))))

    recorded = flight_metrics(load_flight(path))
    in_memory = run.metrics()
    row = flight_row(run)
    tracking = recorded["tracking"]
    assert tracking["measured_on"] == ODOM_TRUTH.name
    assert tracking["position_error_m"]["rms"] == pytest.approx(true_rms, rel=1e-12)
    assert row["position_error_rms_m"] == pytest.approx(true_rms, rel=1e-12)
    assert row["attitude_error_peak_deg"] == pytest.approx(tracking["attitude_error_deg"]["peak"], rel=1e-12)
    # every metric of the flight, from its recording and in memory (the recording's own path and counts apart)
    for key in set(recorded) - {"recording", "message_counts", "notes"}:
        _close(recorded[key], in_memory[key], key)
    # the measurement's own error is the configured noise (0.01 m per axis), far above the tracking error
    measured = recorded["odometry_error"]["position_m"]["rms"]
    assert measured == pytest.approx(0.01 * math.sqrt(3), rel=0.1) and true_rms < 0.2 * measured
    text = markdown_summary(recorded)
    assert f"true state (`{ODOM_TRUTH.name}`" in text and "odom (measured) vs true state" in text


def test_an_ideal_flight_records_no_odom_truth_and_says_odom_is_the_true_state(tmp_path):
    path = tmp_path / "ideal.mcap"
    run = simulate("ex4_geometric", duration=0.2, record=path)
    assert open_recording(path).count("/" + ODOM_TRUTH.name) == 0
    metrics = flight_metrics(load_flight(path))
    assert metrics["tracking"]["measured_on"] == ODOM.name and metrics["odometry_error"] is None
    assert f"true state (`{ODOM.name}`: no sensor stage)" in markdown_summary(metrics)
    assert run.metrics()["tracking"]["position_error_m"] == metrics["tracking"]["position_error_m"]


def test_a_noisy_recording_without_odom_truth_says_its_errors_are_on_the_measurement(tmp_path):
    path = tmp_path / "odom_only.mcap"
    simulate("ex4_geometric", set=NOISY, duration=0.2, record=path, record_topics="odom,reference,attitude_cmd")
    metrics = flight_metrics(load_flight(path))
    assert metrics["tracking"]["measured_on"] == ODOM.name and not metrics["tracking"]["odom_is_true_state"]
    assert "**measured `odom`**" in markdown_summary(metrics)
    assert any("odom_truth is not recorded" in note for note in metrics["notes"])
