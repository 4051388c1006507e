"""Analysis of synthetic recordings with known errors: metrics, figures, missing topics, truncation, CLI."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from rclpy.serialization import deserialize_message

from fsr_bringup.analysis.figures import FIGURES, envelope
from fsr_bringup.analysis.load import load_flight, zero_order_hold
from fsr_bringup.analysis.metrics import flight_metrics
from fsr_bringup.analysis.run import analyze_recording
from fsr_bringup.cli.analyze_cli import main as analyze_main
from fsr_sim.contract import SimStatus
from fsr_sim.recording.cdr_columns import decode_columns
from fsr_sim.recording.reader import open_recording
from fsr_sim.recording.writer import RecordingWriter
from fsr_sim.ros.message_schema import message_class


def test_metrics_match_the_constructed_errors(synthetic_recording: Path, expected: dict) -> None:
    EXPECTED, STEPS = expected, expected["steps"]
    m = flight_metrics(synthetic_recording)
    tracking = m["tracking"]
    assert tracking["position_error_m"]["final"] == pytest.approx(EXPECTED["position_final"], abs=1e-9)
    assert tracking["position_error_m"]["peak"] == pytest.approx(EXPECTED["position_peak"], abs=1e-9)
    assert tracking["position_error_m"]["peak_time_s"] == pytest.approx(EXPECTED["position_peak_time"])
    assert tracking["attitude_error_deg"]["final"] == pytest.approx(EXPECTED["attitude_final"], abs=1e-9)
    assert tracking["attitude_error_deg"]["peak"] == pytest.approx(EXPECTED["attitude_peak"], abs=1e-9)
    # Against the commanded attitude (attitude_cmd); the planner's attitude is kept apart.
    assert tracking["attitude_vs"] == "attitude_cmd"
    assert tracking["attitude_vs_reference_deg"]["final"] == pytest.approx(EXPECTED["attitude_reference_final"],
                                                                           abs=1e-9)
    # World-frame velocity error although odometry carries body-frame twist (yawed vehicle).
    assert tracking["velocity_error_m_s"]["final"] == pytest.approx(EXPECTED["velocity_error"], abs=1e-9)
    assert tracking["velocity_error_m_s"]["peak"] == pytest.approx(EXPECTED["velocity_error"], abs=1e-9)
    w_error = tracking["angular_velocity_error_rad_s"]
    assert w_error["final"] == pytest.approx(EXPECTED["angular_velocity_error"], abs=1e-9)
    assert w_error["peak"] == pytest.approx(EXPECTED["angular_velocity_error"], abs=1e-9)
    saturation = m["saturation"]
    assert saturation["rotor_speed"]["steps"] == EXPECTED["saturation_steps"]
    assert saturation["rotor_speed"]["first_time_s"] == pytest.approx(EXPECTED["saturation_first"])
    assert saturation["rotor_speed"]["worst_rotor"] == EXPECTED["worst_rotor"]
    assert saturation["at_max_steps"] == EXPECTED["at_max"] and saturation["at_min_steps"] == EXPECTED["at_min"]
    shortfall = m["wrench_shortfall"]
    assert shortfall["steps"] == STEPS + 1 and shortfall["any_axis_steps"] == 210
    for axis, (steps, largest, when) in EXPECTED["gave_way"].items():
        assert shortfall[axis]["steps"] == steps and shortfall[axis]["max_shortfall"] == pytest.approx(largest)
        assert shortfall[axis]["max_time_s"] == (None if when is None else pytest.approx(when))
    assert all(shortfall[axis]["steps"] == 0 for axis in ("force_x", "force_y", "torque_y"))
    wrench = m["external_wrench"]
    np.testing.assert_allclose(wrench["truth_mean_last_s"], [1, 1, 0, 0, 0, -0.4], atol=1e-12)
    np.testing.assert_allclose(wrench["estimate_mean_last_s"], [1.02, 0.99, 0, 0, 0, -0.395], atol=1e-12)
    np.testing.assert_allclose(wrench["rms_error_vs_external"], [0.02, 0.01, 0, 0, 0, 0.005], atol=1e-12)
    assert wrench["rms_from_s"] == pytest.approx(1.0)  # half the 2 s run (default settling 5 s is longer)
    assert m["mass"]["estimate_final_kg"] == pytest.approx(EXPECTED["mass_final"])
    assert m["mass"]["true_kg"] == EXPECTED["mass_true"] and m["mass"]["nominal_kg"] == EXPECTED["mass_nominal"]
    np.testing.assert_allclose(m["thrust_ratio"]["ground"], EXPECTED["ground_ratio"], rtol=1e-9)
    assert m["thrust_ratio"]["ceiling"] == [1.0, 1.0]
    assert m["commanded_thrust_N"]["peak"] == pytest.approx(12.5)
    assert m["sim_status"] == SimStatus("finished", "duration reached", 2.0, STEPS).as_dict()
    assert m["steps"] == STEPS and m["duration_s"] == pytest.approx(2.0) and m["odom_messages"] == STEPS + 1
    assert m["message_counts"]["/odom"] == STEPS + 1 and m["message_counts"]["/sim_status"] == 2
    assert m["truncated"] is False and m["scenario"] == "synthetic_flight" and m["notes"] == []
    json.dumps(m, allow_nan=False)  # JSON-ready


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_all_figures_and_files_are_written(synthetic_recording: Path, tmp_path: Path) -> None:
    result = analyze_recording(synthetic_recording, tmp_path)
    assert sorted(p.stem for p in result.figures) == sorted(FIGURES)
    for path in result.figures:
        assert path.stat().st_size > 10_000 and path.read_bytes()[:4] == b"\x89PNG"
    saved = json.loads((tmp_path / "metrics.json").read_text())
    assert saved["tracking"]["position_error_m"]["peak"] == pytest.approx(0.5)
    summary = (tmp_path / "summary.md").read_text()
    assert "| position error [m] final / peak (at t) / RMS | 0.300 / 0.500 (at 1.00 s)" in summary
    assert "210 steps, first at 0.500 s, worst rotor 3" in summary
    assert ("| gave way at the rotor limits [N, N m] | force_z 10 steps (max 0.500 at 1.50 s), "
            "torque_z 200 steps (max 0.300 at 0.60 s) |") in summary


def test_missing_topics_and_scenario_are_skipped_with_notes(tmp_path: Path, write_flight) -> None:
    path = write_flight(tmp_path / "odom_only.mcap", topics=("odom",), scenario=False)
    result = analyze_recording(path, tmp_path / "out")
    m = result.metrics
    assert m["tracking"] is None and m["saturation"] is None and m["external_wrench"] is None
    assert m["mass"] is None and m["thrust_ratio"] is None and m["sim_status"] is None and m["wrench_shortfall"] is None
    assert m["duration_s"] == pytest.approx(2.0) and m["scenario"] == "odom_only"
    notes = "\n".join(m["notes"])
    for expected in ("no scenario", "no messages on /reference", "tracking errors skipped", "figure errors left out"):
        assert expected in notes
    assert [p.name for p in result.figures] == ["pose.png"]
    assert "Notes:" in result.summary


def test_truncated_file_is_flagged_and_analysed(synthetic_recording: Path, tmp_path: Path, expected: dict) -> None:
    data = synthetic_recording.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    recording = open_recording(cut)
    assert recording.truncated
    kept = recording.count("odom")
    assert 0 < kept < expected["steps"] + 1
    m = flight_metrics(recording)
    assert m["truncated"] is True
    assert any("truncated" in note for note in m["notes"])
    # What is there is decoded right: odom stamps are the first `kept` steps.
    flight = load_flight(recording)
    np.testing.assert_array_equal(flight.odom.stamp_ns, np.arange(kept) * 1_000_000)


def test_vectorised_decoding_equals_rclpy(synthetic_recording: Path) -> None:
    recording = open_recording(synthetic_recording)
    for topic, path in (("odom", "twist.twist.linear.y"), ("reference", "points.0.transforms.0.rotation.z"),
                        ("rotor_cmd", "velocity"), ("mass_estimate", "data")):
        raw = recording.raw(topic)
        type_name = recording.topics["/" + topic]
        columns = decode_columns([d for _, d in raw], type_name)
        cls = message_class(type_name)
        for index in (0, 777, len(raw) - 1):
            msg = deserialize_message(raw[index][1], cls)
            expected = msg
            for part in path.split("."):
                expected = expected[int(part)] if part.isdigit() else getattr(expected, part)
            np.testing.assert_array_equal(columns.get(path)[index], np.asarray(expected))


def test_zero_order_hold_and_envelope() -> None:
    stamps, values = np.array([10, 20, 30]), np.array([1.0, 2.0, 3.0])
    np.testing.assert_array_equal(zero_order_hold(stamps, values, np.array([5, 10, 25, 40]))[1:], [1, 2, 3])
    assert np.isnan(zero_order_hold(stamps, values, np.array([5]))[0])
    t = np.arange(100_000) * 1e-3
    y = np.zeros_like(t)
    y[51_234] = 7.0  # a one-sample spike must survive decimation
    td, yd = envelope(t, y)
    assert len(td) < 5000 and yd.max() == 7.0 and np.all(np.diff(td) >= 0)


def test_cli_writes_outputs_and_prints_summary(synthetic_recording: Path, tmp_path: Path, capsys) -> None:
    assert analyze_main([str(synthetic_recording), "--out", str(tmp_path), "--no-figures"]) == 0
    out = capsys.readouterr().out
    assert "### Flight `synthetic_flight`" in out and (tmp_path / "metrics.json").is_file()


@pytest.mark.parametrize("kind", ["missing", "text", "empty", "no_messages"])
def test_cli_refuses_bad_input_with_one_line_exit_2(kind: str, tmp_path: Path, capsys) -> None:
    path = tmp_path / "bad.mcap"
    if kind == "text":
        path.write_text("not an mcap file\n")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "no_messages":
        with RecordingWriter(path) as writer:
            writer.add_topic("/odom", "nav_msgs/msg/Odometry")
    assert analyze_main([str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0]
    assert not (tmp_path / "out" / "metrics.json").exists()


def test_a_flight_stopped_by_a_signal_is_summarised_as_interrupted() -> None:
    from fsr_bringup.analysis.metrics import interrupted_at
    from fsr_bringup.analysis.summary import markdown_summary

    stopped = SimStatus("stopped", "received SIGINT", 5.123, 5123)
    assert interrupted_at(stopped) == pytest.approx(5.123)
    for other in (
        SimStatus("finished", "reached the scenario duration 10 s", 10.0, 10000),
        SimStatus("diverged", "crashed into the ceiling", 2.0, 2000),
        SimStatus("stopped", "start-up failed: no rotor_cmd", 0.0, 0),
        None,
    ):
        assert interrupted_at(other) is None
    summary = markdown_summary({"scenario": "x", "sim_status": stopped.as_dict(), "interrupted_at_s": 5.123})
    assert "| end state | **interrupted at t = 5.123 s** (received SIGINT) |" in summary
    finished = SimStatus("finished", "r", 1.0, 1000).as_dict()
    assert "interrupted" not in markdown_summary({"scenario": "x", "sim_status": finished})


def test_a_wrench_actuated_flight_has_no_rotor_saturation_to_report(tmp_path: Path) -> None:
    from fsr_bringup.runner.in_process_flight import fly_in_process
    from fsr_sim.config.scenario import load_scenario

    scenario = load_scenario("ex4_geometric")
    assert scenario.data["actuation"] == "wrench"
    fly_in_process(scenario, recording=tmp_path / "wrench.mcap", max_steps=300)
    result = analyze_recording(tmp_path / "wrench.mcap", tmp_path / "out", figures=False)
    notes = "\n".join(result.metrics["notes"])
    assert "no rotor saturation: wrench actuation applies the commanded wrench as it is" in notes
    assert "saturation skipped" not in notes and "wrench shortfall skipped" not in notes
    assert result.metrics["saturation"] is None and "gave way" not in result.summary


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: the figures are drawn in this process")
def test_the_figures_are_drawn_in_workers_that_were_not_forked_from_this_process(synthetic_recording: Path,
                                                                                 tmp_path: Path, monkeypatch) -> None:
    """Python 3.12+ warns when a process that runs threads forks: the figures' workers come from a fork server."""
    from fsr_bringup.analysis.figure_jobs import Run, make_figures

    def no_fork() -> int:
        raise AssertionError("the analysis forked this process")

    flight = load_flight(synthetic_recording)
    monkeypatch.setattr(os, "fork", no_fork)
    written, _ = make_figures([Run.of(flight, "synthetic")], tmp_path)
    assert {path.stem for path in written} >= {"pose", "rotors"}


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="one core: the figures are drawn in this process")
def test_the_block_of_shared_memory_the_workers_read_is_freed_when_the_figures_are_done_or_dropped(
        synthetic_recording: Path, tmp_path: Path) -> None:
    import gc
    from multiprocessing.shared_memory import SharedMemory

    from fsr_bringup.analysis.figure_jobs import Run, start_figures

    runs = [Run.of(load_flight(synthetic_recording), "synthetic")]
    finished = start_figures(runs, tmp_path / "finished")
    name = finished.shared.memory.name
    SharedMemory(name=name).close()  # there while the workers draw
    written, _ = finished.result()
    assert (tmp_path / "finished" / "pose.png") in written
    dropped = start_figures(runs, tmp_path / "dropped")
    names = [name, dropped.shared.memory.name]
    dropped.pool.terminate()
    del dropped
    gc.collect()
    for name in names:
        with pytest.raises(FileNotFoundError):
            SharedMemory(name=name)


def test_the_workers_draw_every_built_in_figure_in_the_order_slowest_first() -> None:
    """The drawing order names each built-in figure once (a renamed or a new figure would otherwise be drawn
    last, whatever it costs); figures it does not name come after it."""
    from fsr_bringup.analysis.figure_jobs import SLOWEST_FIRST, drawing_rank
    from fsr_bringup.analysis.figures import FIGURES

    assert sorted(SLOWEST_FIRST) == sorted(FIGURES)
    assert sorted(["mass", "mine", "pose"], key=drawing_rank) == ["pose", "mass", "mine"]


def test_run_labels_leave_out_the_time_stamp_of_a_run_name() -> None:
    from fsr_bringup.analysis.run import run_labels

    assert run_labels(["ex4_geometric_20261205-152426"]) == ["ex4_geometric"]
    assert run_labels(["a_20261205-152426", "b_20261205-152430"]) == ["a", "b"]
    same = ["ex4_geometric_20261205-152426", "ex4_geometric_20261205-152430"]
    assert run_labels(same) == same  # the stamp is what tells them apart
