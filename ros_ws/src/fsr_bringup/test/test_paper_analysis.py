"""Analysis a paper can use, on real (short, in-process) flights: the effective truth of the wrench observer,
the attitude error against the commanded attitude, the estimator metrics of fsr-estimate in fsr-fly's
summary, journal figures (sizes, fonts, vector formats, no noise drawn as signal) and overlays of runs."""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from fsr_bringup.analysis.effective import effective_wrench
from fsr_bringup.analysis.figure_jobs import make_figures
from fsr_bringup.analysis.figures import (
    FLOORS,
    FONT_PT,
    ONE_COLUMN_IN,
    RC,
    TWO_COLUMN_IN,
    FigureOptions,
    Run,
    errors_figure,
    mass_figure,
)
from fsr_bringup.analysis.load import load_flight, zero_order_hold
from fsr_bringup.analysis.metrics import flight_metrics, tracking_errors
from fsr_bringup.cli.analyze_cli import main as analyze_main
from fsr_bringup.cli.fly_cli import parse_args as fly_args
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_estimation.estimator.metrics import max_error_after, mean_absolute_error, settling_time
from fsr_sim.config.scenario import load_scenario
from fsr_sim.core.rigid_body import GRAVITY

EX3_YAW_GAIN = 100.0  # k_R,z of ex3's geometric controller (report gains)
EX3_YAW_TORQUE = 0.4  # N m, the unopposed external yaw torque


def _fly(name: str, path: Path, *overrides: str) -> Path:
    result = fly_in_process(load_scenario(name, list(overrides)), recording=path)
    assert result.end_reason == "finished", result.reason
    return path


@pytest.fixture(scope="module")
def ex3(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ex3_estimation to 16 s: the trajectory ends at 10 s, so t > 15 s is steady flight."""
    return _fly("ex3_estimation", tmp_path_factory.mktemp("ex3") / "ex3.mcap", "duration=16.0")


@pytest.fixture(scope="module")
def ex3_slow_observer(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _fly("ex3_estimation", tmp_path_factory.mktemp("ex3c5") / "ex3_c5.mcap", "duration=4.0",
                "estimator.c0=5.0")


@pytest.fixture(scope="module")
def ex5(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _fly("ex5_voliro", tmp_path_factory.mktemp("ex5") / "ex5.mcap", "duration=3.0")


def _estimate_and_truth(path: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t, online estimate body (n, 6), effective truth body (n, 6), external wrench only (n, 6))."""
    flight = load_flight(path)
    effective = effective_wrench(flight)
    est = flight.wrench_estimate
    truth = flight.wrench_truth
    estimate = np.hstack((est.force, est.torque))
    return (est.t, estimate, zero_order_hold(effective.stamp_ns, effective.wrench_body, est.stamp_ns),
            zero_order_hold(truth.stamp_ns, np.hstack((truth.force, truth.torque)), est.stamp_ns))


def test_ex3_estimate_converges_to_the_effective_truth(ex3: Path) -> None:
    t, estimate, effective, external = _estimate_and_truth(ex3)
    late = (t > 15.0) & np.all(np.isfinite(effective), axis=1)
    rms = np.sqrt(np.mean((estimate[late] - effective[late]) ** 2, axis=0))
    assert np.all(rms[:3] < 1e-6), rms  # forces [N]
    assert np.all(rms[3:] < 1e-6), rms  # torques [N m]
    # Against the external wrench alone the "error" is the model mismatch: (m_e - m) g = 0.25 * 9.81 N in f_z.
    rms_external = np.sqrt(np.mean((estimate[late] - external[late]) ** 2, axis=0))
    assert rms_external[2] > 2.0
    # While it moves (1-10 s) the estimate trails the effective truth by the observer's lag only (c0 = 10).
    moving = (t > 1.0) & (t < 10.0)
    lag = np.abs(estimate[moving] - effective[moving]).max(axis=0)
    assert np.all(lag[:3] < 0.02) and np.all(lag[:3] < 0.01 * np.abs(effective[moving, :3]).max(axis=0) + 0.01)


def test_ex3_effective_truth_is_external_plus_mass_mismatch_in_steady_flight(ex3: Path) -> None:
    flight = load_flight(ex3)
    effective = effective_wrench(flight)
    scenario = load_scenario("ex3_estimation")
    m_model, m_true = scenario.data["estimator"]["mass"], scenario.data["plant"]["mass"]
    expected = np.array([1.0, 1.0, 0.0]) + (m_model - m_true) * np.array([0.0, 0.0, -GRAVITY])  # world NED
    steady = effective.t > 15.0
    force = effective.force_world[steady][:-1]
    np.testing.assert_allclose(force, np.broadcast_to(expected, force.shape), atol=1e-4)
    np.testing.assert_allclose(effective.torque_body[steady][:-1, 2], -EX3_YAW_TORQUE, atol=1e-9)
    assert not effective.in_contact.any() and np.all(effective.contact_force_world == 0.0)


def test_attitude_error_is_against_the_commanded_attitude(ex3: Path, tmp_path: Path) -> None:
    errors = tracking_errors(load_flight(ex3))
    assert errors.attitude_commanded
    yaw_offset = math.degrees(EX3_YAW_TORQUE / EX3_YAW_GAIN)  # 0.229 deg: K_R,z e_R = tau_ext,z
    late = errors.t > 10.0
    np.testing.assert_allclose(errors.attitude_deg[late], yaw_offset, atol=2e-3)
    assert errors.attitude_reference_deg[late].min() > 5.0  # the commanded tilt is no error
    ex4 = load_flight(_fly("ex4_geometric", tmp_path / "ex4.mcap", "duration=4.0"))
    assert np.nanmax(tracking_errors(ex4).attitude_deg) < 0.01


def test_effective_truth_holds_through_a_landing(tmp_path: Path) -> None:
    """Rotors with ground effect, a lighter model (1.2 kg) than the plant (1.3 kg), landing at ~1.1 s."""
    scenario = tmp_path / "landing.yaml"
    scenario.write_text(
        "name: landing\nvehicle: quadrotor_ex4\nduration: 3.0\nactuation: rotors\n"
        "initial_state: {position: [0.0, 0.0, -0.4]}\nplant: {mass: 1.3}\n"
        "environment: {ground: {enabled: true, height: 0.0, effect: true, model: single}}\n"
        "trajectory: {waypoints: [{position: [0.0, 0.0, 0.05], duration: 2.0}]}\n"
        "controller: {type: geometric, profile: report}\nestimator: {enabled: true, mass: 1.2, c0: 10.0, r: 1}\n",
        encoding="utf-8",
    )
    path = _fly(str(scenario), tmp_path / "landing.mcap")
    flight = load_flight(path)
    effective = effective_wrench(flight)
    assert effective.in_contact.any()
    touchdown = effective.t[np.argmax(effective.in_contact)]
    assert 0.5 < touchdown < 2.0
    assert np.any(effective.thrust_change_world[effective.t < touchdown, 2] < -0.1)  # ground effect: more lift
    t, estimate, truth, external = _estimate_and_truth(path)
    landed = (t > touchdown + 1.5) & np.all(np.isfinite(truth), axis=1)
    assert landed.sum() > 100
    assert np.abs(estimate[landed] - truth[landed]).max() < 1e-4
    assert np.abs(estimate[landed] - external[landed]).max() > 5.0  # the contact force is no external wrench


def test_fly_summary_gives_the_estimator_metrics_of_fsr_estimate(ex3: Path, tmp_path: Path) -> None:
    metrics = flight_metrics(ex3, after=15.0)["external_wrench"]
    t, estimate, effective, _ = _estimate_and_truth(ex3)
    defined = np.all(np.isfinite(effective), axis=1)
    t, estimate, effective = t[defined], estimate[defined], effective[defined]
    channels = ["fx", "fy", "fz", "tx", "ty", "tz"]
    same = {
        "settling_time_s": settling_time(t, estimate, effective, "standard"),
        "mae": mean_absolute_error(estimate, effective),
        "max_error_after": max_error_after(t, estimate, effective, 15.0),
    }
    for key, values in same.items():
        got = [np.nan if metrics[key][c] is None else metrics[key][c] for c in channels]
        np.testing.assert_allclose(got, values, rtol=1e-12, atol=0.0, equal_nan=True)
    assert 0.0 < metrics["settling_time_s"]["fx"] < 1.0 and metrics["settling_time_s"]["tx"] is None
    assert all(metrics["max_error_after"][c] < 1e-6 for c in ("fx", "fy", "fz", "tz"))
    report = flight_metrics(ex3, settling="report")["external_wrench"]
    expected_report = settling_time(t, estimate, effective, "report")  # the report's definition (docs/model.md §5)
    assert report["settling"] == "report"
    np.testing.assert_allclose([np.nan if report["settling_time_s"][c] is None else report["settling_time_s"][c]
                                for c in channels], expected_report, rtol=1e-12, equal_nan=True)
    args = fly_args(["ex3_estimation", "--in-process", "--settling", "report", "--after", "12", "--format", "png,pdf"])
    assert args.settling == "report" and args.after == 12.0 and args.format == "png,pdf"
    assert analyze_main([str(ex3), "--out", str(tmp_path), "--no-figures", "--settling", "report"]) == 0
    summary = (tmp_path / "summary.md").read_text()
    assert "settling time [s] (report, 3 % band)" in summary and "MAE over the flight" in summary
    assert "attitude error vs R_c, commanded [deg]" in summary


def _texts(fig: matplotlib.figure.Figure) -> list[matplotlib.text.Text]:
    return [t for t in fig.findobj(matplotlib.text.Text) if t.get_visible() and t.get_text().strip()]


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_figures_for_a_journal(ex5: Path, tmp_path: Path) -> None:
    flight = load_flight(ex5)
    runs = [Run.of(flight)]
    options = FigureOptions(formats=("png", "pdf", "svg"))
    with matplotlib.rc_context(RC):
        errors = errors_figure(runs, options).figure
        errors.canvas.draw()
        # The attitude error of ex5 is ~1e-6 deg: a flat line on a fixed axis, with a note, not a noise block.
        attitude = errors.axes[2]
        assert np.nanmax(tracking_errors(flight).attitude_deg) < 0.1 * FLOORS["deg"]
        assert attitude.get_ylim() == pytest.approx((0.0, 2 * FLOORS["deg"]))
        assert any("range < 0.001 deg" in t.get_text() for t in attitude.texts)
        mass = mass_figure(runs, options).figure
        mass.canvas.draw()
        assert mass.axes[0].yaxis.get_offset_text().get_text() == ""  # no "1e-9 + 1.3199999" offset
        for fig in (errors, mass):
            assert fig.get_figwidth() in (ONE_COLUMN_IN, TWO_COLUMN_IN)
            assert fig._suptitle is None  # no title inside the figure by default
            sizes = {t.get_fontsize() for t in _texts(fig)}
            assert sizes and min(sizes) >= 8.0 and max(sizes) <= 9.0, sizes
            for ax in fig.axes:
                label = ax.get_ylabel()
                assert "[" in label and "]" in label, label  # unit in every axis label
            legend = fig.legends[0]
            assert legend.get_window_extent().y0 >= max(ax.get_window_extent().y1 for ax in fig.axes) - 1.0
    written, notes = make_figures(runs, tmp_path, options)
    assert any(note.startswith("figure thrust_ratio left out") for note in notes)
    assert not any(p.stem == "thrust_ratio" for p in written)
    for path in written:
        data = path.read_bytes()
        if path.suffix == ".pdf":
            assert data.startswith(b"%PDF") and b"ex5_voliro" in data
        elif path.suffix == ".svg":
            root = ET.fromstring(data)
            assert root.tag.endswith("svg")
        else:
            image = matplotlib.image.imread(path)
            width_in = image.shape[1] / 300.0
            assert min(abs(width_in - ONE_COLUMN_IN), abs(width_in - TWO_COLUMN_IN)) < 0.05
    assert {p.suffix for p in written} == {".png", ".pdf", ".svg"}
    assert FONT_PT == 8.0


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_overlay_of_two_runs(ex3: Path, ex3_slow_observer: Path, tmp_path: Path) -> None:
    out = tmp_path / "cmp"
    assert analyze_main([str(ex3), str(ex3_slow_observer), "--labels", "c0=10,c0=5", "--out", str(out)]) == 0
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert "external_wrench.png" in pngs and "pose.png" in pngs and len(pngs) == len(set(pngs))
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["labels"] == ["c0=10", "c0=5"] and set(metrics["runs"]) == {"c0=10", "c0=5"}
    slow, fast = metrics["runs"]["c0=5"]["external_wrench"], metrics["runs"]["c0=10"]["external_wrench"]
    assert slow["settling_time_s"]["fx"] > fast["settling_time_s"]["fx"]  # the slower filter settles later
    summary = (out / "summary.md").read_text()
    assert "| quantity | c0=10 | c0=5 |" in summary
    row = next(line for line in summary.splitlines() if line.startswith("| settling time [s]"))
    assert row.count("|") == 4  # quantity + two run columns
    # Both runs are in the same figure.
    flight_a, flight_b = load_flight(ex3), load_flight(ex3_slow_observer)
    with matplotlib.rc_context(RC):
        fig = errors_figure([Run.of(flight_a, "c0=10"), Run.of(flight_b, "c0=5")], FigureOptions()).figure
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels == ["c0=10", "c0=5"]
    assert analyze_main([str(ex3), str(ex3_slow_observer), "--labels", "one", "--out", str(out)]) == 2
