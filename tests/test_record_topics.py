"""fsr-fly --record-topics: a smaller recording for a long flight, the same selection in one process and in
the node graph (same bytes), sim_status always kept, an unknown name refused with a suggestion."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fsr_bringup.analysis.run import analyze_recording
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.contract import recording_selection
from fsr_sim.recording.reader import open_recording

FLY = str(Path(sys.executable).parent / "fsr-fly")


def test_only_the_selected_topics_are_recorded_and_the_analysis_says_what_is_missing(tmp_path):
    scenario = load_scenario("ex4_geometric")
    fly_in_process(scenario, recording=tmp_path / "all.mcap", max_steps=2000)
    fly_in_process(scenario, recording=tmp_path / "some.mcap", max_steps=2000,
                   record_topics=recording_selection("odom,reference"))
    every, some = open_recording(tmp_path / "all.mcap"), open_recording(tmp_path / "some.mcap")
    assert set(some.topics) == {"/odom", "/reference", "/sim_status"}
    for topic in some.topics:
        assert some.raw(topic) == every.raw(topic), topic
    assert (tmp_path / "some.mcap").stat().st_size < 0.6 * (tmp_path / "all.mcap").stat().st_size  # 48 %
    notes = "\n".join(analyze_recording(tmp_path / "some.mcap", tmp_path / "out", figures=True).metrics["notes"])
    assert "no wrench_estimate (estimator off, or not recorded)" in notes


def test_an_unknown_topic_is_refused_naming_the_closest():
    run = subprocess.run([FLY, "ex4_geometric", "--record-topics", "odom,refrence"], capture_output=True, text=True,
                         timeout=60, stdin=subprocess.DEVNULL)
    assert run.returncode == 2
    assert "argument --record-topics: unknown recorded topic 'refrence' (did you mean 'reference'?)" in run.stderr


@pytest.mark.graph
def test_the_node_graph_records_the_same_selection(tmp_path):
    for out, extra in ((tmp_path / "graph.mcap", []), (tmp_path / "local.mcap", ["--in-process"])):
        run = subprocess.run([FLY, "ex4_geometric", "--duration", "0.5", "--record-topics", "odom,wrench_cmd",
                              "--no-analysis", "--out", str(out), *extra], capture_output=True, text=True,
                             timeout=180, stdin=subprocess.DEVNULL, cwd=tmp_path)
        assert run.returncode == 0, run.stdout + run.stderr
    graph, local = open_recording(tmp_path / "graph.mcap"), open_recording(tmp_path / "local.mcap")
    assert set(graph.topics) == set(local.topics) == {"/odom", "/wrench_cmd", "/sim_status"}
    for topic in ("/odom", "/wrench_cmd"):
        assert graph.count(topic) == 501 and graph.raw(topic) == local.raw(topic), topic
