"""The figures a reviewer accepts, checked on the figure objects of short in-process flights (in memory, no
recording): math notation in every label and legend, a zoom on a short start transient, no panel zero by
construction, the commanded attitude in the pose figure, rotor axes scaled to the data with limits only when
near, disturbance windows shaded and legends outside the axes."""

from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.patches import Rectangle

from fsr_bringup.analysis.figure_layout import PANEL_LABEL, ZOOM_LABEL
from fsr_bringup.analysis.figure_rules import (
    disturbance_windows,
    limits_near,
    nice_ceil,
    start_transient,
    zoom_span,
)
from fsr_bringup.analysis.figures import (
    DISTURBANCE_LABEL,
    FIGURES,
    RC,
    FigureOptions,
    Run,
    errors_figure,
    external_wrench_figure,
    pose_figure,
    rotor_groups,
    rotors_figure,
    wrench_command_figure,
)
from fsr_bringup.analysis.in_memory import recorded_flight_of_run
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.api import simulate
from fsr_sim.model import disturbances as profiles
from fsr_sim.model.so3 import euler_zyx_from_rotation

STEP_WINDOW = (1.0, 2.0)  # s, the step disturbance's window in the short flight below
MATH = re.compile(r"\$[^$]*\$")


def _run(label: str, scenario: str, **kwargs: object) -> Run:
    return Run.of(recorded_flight_of_run(simulate(scenario, **kwargs)), label)


def _draw_all(runs: list[Run]) -> dict[str, matplotlib.figure.Figure]:
    with matplotlib.rc_context(RC):
        drawn = {name: draw(runs, FigureOptions()) for name, draw in FIGURES.items()}
        figures = {name: d.figure for name, d in drawn.items() if d.figure is not None}
        for fig in figures.values():
            fig.canvas.draw()
    return figures


@pytest.fixture(scope="module")
def ex3() -> Run:
    """ex3_estimation over its whole 30 s: the estimator settles in ~0.3 s, 1 % of the time axis."""
    return _run("ex3", "ex3_estimation")


@pytest.fixture(scope="module")
def ex3_figures(ex3: Run) -> dict[str, matplotlib.figure.Figure]:
    return _draw_all([ex3])


@pytest.fixture(scope="module")
def ex4() -> Run:
    return _run("ex4", "ex4_geometric", duration=4.0)


@pytest.fixture(scope="module")
def step() -> Run:
    """step_disturbance (rotors, quadrotor) for 3 s with its 2 N step acting from 1 s to 2 s."""
    start, end = STEP_WINDOW
    return _run("step", "step_disturbance", duration=3.0,
                set={"disturbances.0.start": start, "disturbances.0.end": end})


def _panels(fig: matplotlib.figure.Figure) -> list[matplotlib.axes.Axes]:
    """The axes over the whole time axis (not the zooms, not the twins on the right)."""
    return [ax for ax in fig.axes if ax.get_label().startswith(PANEL_LABEL)]


def _zooms(fig: matplotlib.figure.Figure) -> list[matplotlib.axes.Axes]:
    return [ax for ax in fig.axes if ax.get_label().startswith(ZOOM_LABEL)]


def _data_lines(ax: matplotlib.axes.Axes) -> list[matplotlib.lines.Line2D]:
    return [line for line in ax.get_lines() if line.get_transform() == ax.transData and len(line.get_xdata())]


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_labels_and_legends_are_mathtext(ex3_figures: dict) -> None:
    for name, fig in ex3_figures.items():
        labels = [ax.get_ylabel() for ax in fig.axes if ax.get_ylabel()]
        assert labels, name
        for label in labels:
            assert "$" in label, (name, label)
        texts = labels + [ax.get_xlabel() for ax in fig.axes] + [t.get_text() for t in fig.legends[0].get_texts()]
        for text in texts:
            plain = MATH.sub("", text)
            assert "_" not in plain and "|" not in plain and "tau" not in plain, (name, text)  # no p_x, |e_omega|
    pose_labels = " ".join(ax.get_ylabel() for ax in ex3_figures["pose"].axes)
    assert "$p_x$" in pose_labels and r"$\psi$" in pose_labels
    errors = " ".join(ax.get_ylabel() for ax in ex3_figures["errors"].axes)
    assert r"$\|e_\Omega\|$" in errors and r"$\|e_p\|$" in errors
    estimate = " ".join(ax.get_ylabel() for ax in ex3_figures["external_wrench"].axes)
    assert "$f_{e,x}$" in estimate and r"$\tau_{e,z}$" in estimate


def test_start_transient_rule() -> None:
    t = np.linspace(0.0, 30.0, 30001)
    settling = 1.0 - np.exp(-t / 0.1)  # tau = 0.1 s: half-way after ln 2 tau
    assert start_transient([(t, settling)]) == pytest.approx(0.1 * math.log(2.0), abs=2e-3)
    assert zoom_span([start_transient([(t, settling)])], 30.0) == 0.5  # max(2 x 0.069, 1 % of 30 s) -> 0.5 s
    ramp = np.minimum(t / 10.0, 1.0)
    assert start_transient([(t, ramp)]) == pytest.approx(5.0, abs=1e-2) and zoom_span([5.0], 30.0) is None
    assert start_transient([(t, 1e-6 * settling)], floor=1e-3) is None  # rounding noise has no transient
    # A late excursion of one series keeps the panel's height to the end: no start transient.
    late = np.where((t > 20.0) & (t < 20.1), 0.0, 500.0)
    assert start_transient([(t, late), (t, np.full_like(t, 500.0))]) == pytest.approx(20.1, abs=2e-3)
    assert [nice_ceil(v) for v in (0.0139, 0.3, 0.71, 1.0, 1.07)] == pytest.approx([0.02, 0.5, 1.0, 1.0, 2.0])


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_a_short_estimator_transient_gets_a_zoom(ex3_figures: dict, ex4: Run) -> None:
    fig = ex3_figures["external_wrench"]
    zooms = _zooms(fig)
    assert len(zooms) == 6 and [ax.get_title() for ax in zooms if ax.get_title()] == ["first 1 s"] * 2
    for zoom in zooms:
        assert zoom.get_xlim() == pytest.approx((0.0, 1.0))
        panel = next(ax for ax in _panels(fig) if zoom.get_shared_y_axes().joined(zoom, ax))
        assert panel.get_xlim()[1] > 29.0 and panel.get_ylim() == zoom.get_ylim()
        assert zoom.get_ylabel() and not panel.get_ylabel()  # the zoom's y labels stand for both
        estimate = _data_lines(zoom)[0]
        assert estimate.get_xdata().max() <= 1.01 and len(estimate.get_xdata()) > 500  # every sample, not decimated
    with matplotlib.rc_context(RC):  # ex4 flies smoothly from rest: no transient to zoom on
        for name, draw in FIGURES.items():
            drawn = draw([ex4], FigureOptions())
            if drawn.figure is not None:
                assert not _zooms(drawn.figure), name


def test_no_panel_is_zero_by_construction(ex4: Run) -> None:
    assert not ex4.flight.config.vehicle.fully_actuated
    assert np.all(ex4.flight.wrench_cmd.force[:, :2] == 0.0)  # thrust along -z_b only
    figures = _draw_all([ex4])
    for name, fig in figures.items():
        for ax in _panels(fig):
            values = np.concatenate([np.asarray(line.get_ydata(), dtype=float) for line in _data_lines(ax)])
            assert np.any(values != 0.0), (name, ax.get_ylabel())
    labels = [ax.get_ylabel().splitlines()[0] for ax in figures["wrench_cmd"].axes if ax.get_ylabel()]
    assert labels == ["$f_z$ [N]", r"$\tau_x$ [N m]", r"$\tau_y$ [N m]", r"$\tau_z$ [N m]"]
    ex5 = _run("ex5", "ex5_voliro", duration=0.5)  # fully actuated: every force component is commanded
    with matplotlib.rc_context(RC):
        assert len(wrench_command_figure([ex5], FigureOptions()).figure.axes) == 6


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_pose_draws_the_commanded_attitude(ex3: Run, ex3_figures: dict) -> None:
    fig = ex3_figures["pose"]
    roll = next(ax for ax in fig.axes if "roll" in ax.get_ylabel())
    by_label = {line.get_label(): line for line in _data_lines(roll)}
    assert set(by_label) == {"ex3: $p$, $R$", "ex3: commanded $R_c$", "reference $p_d$, $R_d$"}
    commanded = by_label["ex3: commanded $R_c$"]
    expected = np.degrees(euler_zyx_from_rotation(ex3.flight.attitude_cmd.rotation)[:, 0])
    np.testing.assert_allclose(np.interp(commanded.get_xdata(), ex3.flight.attitude_cmd.t, expected),
                               commanded.get_ydata(), atol=1e-9)
    assert np.abs(commanded.get_ydata()).max() > 5.0  # ex3 tilts against its 1 N push, the planner's R_d does not
    assert np.abs(by_label["reference $p_d$, $R_d$"].get_ydata()).max() < 1e-6
    assert "ex3: commanded $R_c$" in [t.get_text() for t in fig.legends[0].get_texts()]


def _limit_lines(ax: matplotlib.axes.Axes) -> list[float]:
    return sorted(line.get_ydata()[0] for line in ax.get_lines() if "limits" in line.get_label())


def test_rotor_axes_follow_the_data_and_limits_only_when_near(step: Run, synthetic_recording: Path) -> None:
    hover = _run("wind", "wind_rejection", duration=3.0)  # the octocopter's rotors at 500-512 rad/s (0-900)
    with matplotlib.rc_context(RC):
        for run, expected in ((hover, []), (step, [0.0]), (Run.of(load_flight(synthetic_recording)), [0.0, 1000.0])):
            ax = rotors_figure([run], FigureOptions()).figure.axes[0]
            speeds = run.flight.rotor_cmd.speeds[:, rotor_groups(run.flight.rotor_cmd.speeds.shape[1])[0]]
            low, high = speeds.min(), speeds.max()
            assert _limit_lines(ax) == expected, run.label
            shown = sorted([low, high, *expected])  # the axis spans the data and the limits drawn, no more
            margin = 0.1 * (shown[-1] - shown[0])
            bottom, top = ax.get_ylim()
            assert shown[0] - margin <= bottom <= shown[0] and shown[-1] <= top <= shown[-1] + margin, run.label
    # step_disturbance's 2 N step drives a rotor to 0 rad/s (its minimum); its maximum (1000) stays far off.
    assert step.flight.rotor_cmd.speeds.max() < 700.0
    assert limits_near(440.0, 545.0, (0.0, 1000.0)) == []
    assert limits_near(440.0, 990.0, (0.0, 1000.0)) == [1000.0]


def test_an_octocopters_rotors_get_a_panel_per_pair_with_what_they_did_beside_the_command() -> None:
    lagging = _run("octo", "octo_ground_effect", duration=0.2, set={"plant.rotor_time_constant": 0.03})
    assert rotor_groups(8) == [[0, 1], [2, 3], [4, 5], [6, 7]] and rotor_groups(4) == [[0, 1, 2, 3]]
    with matplotlib.rc_context(RC):
        figure = rotors_figure([lagging], FigureOptions()).figure
    panels = [ax for ax in figure.axes if ax.get_label().startswith(PANEL_LABEL)]
    assert len(panels) == 4
    state = lagging.flight.rotor_state.speeds
    for rotors, ax in zip(rotor_groups(8), panels, strict=True):
        lines = [line for line in ax.get_lines() if len(line.get_xdata()) == len(state)]
        commanded = [line for line in lines if line.get_linestyle() == "-"]
        measured = [line for line in lines if line.get_linestyle() != "-"]
        assert len(commanded) == len(measured) == 2
        for i, line in zip(rotors, measured, strict=True):
            np.testing.assert_array_equal(line.get_ydata(), state[:, i])
    legend = [text.get_text() for text in figure.legends[0].get_texts()]
    assert "rotor_state (measured)" in legend


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_disturbance_windows_are_shaded(step: Run, ex3_figures: dict) -> None:
    figures = _draw_all([step])
    for name in ("errors", "external_wrench", "pose", "wrench_cmd", "rotors"):
        fig = figures[name]
        for ax in _panels(fig):
            spans = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_label() == DISTURBANCE_LABEL]
            assert len(spans) == 1, (name, ax.get_ylabel())
            x0, x1 = spans[0].get_x(), spans[0].get_x() + spans[0].get_width()
            assert (x0, x1) == pytest.approx(STEP_WINDOW)
        assert DISTURBANCE_LABEL in [t.get_text() for t in fig.legends[0].get_texts()]
    for fig in ex3_figures.values():  # ex3's wrench is constant: it acts all the time, nothing to shade
        assert not any(p.get_label() == DISTURBANCE_LABEL for ax in fig.axes for p in ax.patches)


def test_disturbance_acting_intervals() -> None:
    assert profiles.constant([1.0, 0.0, 0.0]).acting_interval() == (0.0, math.inf)
    assert profiles.step(5.0, [2.0, 0.0, 0.0], end=10.0).acting_interval() == (5.0, 10.0)
    assert profiles.sinusoid(0.5, [0.0, 2.0, 0.0], start=8.5).acting_interval() == (8.5, math.inf)
    ramp = profiles.table([2.0, 2.5, 7.0, 7.5], [[0, 0, 0], [3, 0, 0], [3, 0, 0], [0, 0, 0]])
    assert ramp.acting_interval() == (2.0, 7.5)
    assert profiles.table([1.0, 2.0], [[1, 0, 0], [0, 0, 0]]).acting_interval() == (-math.inf, 2.0)
    assert profiles.step(1.0).acting_interval() is None  # no force, no torque
    windows = disturbance_windows([ramp, profiles.constant(torque=[0, 0, -0.4]), profiles.step(7.2, [1, 0, 0]),
                                   profiles.sinusoid(0.5, [0, 2, 0], start=8.5)], 0.0, 12.0)
    assert windows == [(2.0, 12.0)]  # the constant torque covers the axis: left out; the rest merged
    assert disturbance_windows([ramp], 0.0, 5.0) == [(2.0, 5.0)]


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
def test_legends_are_outside_the_axes(ex3_figures: dict, synthetic_recording: Path) -> None:
    figures = dict(ex3_figures)
    figures.update({f"synthetic {name}": fig for name, fig in
                    _draw_all([Run.of(load_flight(synthetic_recording))]).items()})
    for name, fig in figures.items():
        assert len(fig.legends) == 1 and all(ax.get_legend() is None for ax in fig.axes), name
        legend = fig.legends[0].get_window_extent()
        boxes = [ax.get_window_extent() for ax in fig.axes]
        above = legend.y0 >= max(box.y1 for box in boxes)
        right = legend.x0 >= max(box.x1 for box in boxes)
        assert above or right, name
        assert not any(legend.overlaps(box) for box in boxes), name
        width, height = fig.get_size_inches() * fig.dpi
        assert legend.x0 >= 0.0 and legend.x1 <= width and legend.y1 <= height, name  # inside the figure


def test_an_overlay_shares_one_zoom_and_one_legend(ex3: Run) -> None:
    slow = _run("c0=5", "ex3_estimation", duration=10.0, set={"estimator.c0": 5.0})
    with matplotlib.rc_context(RC):
        fig = external_wrench_figure([ex3, slow], FigureOptions()).figure
        errors = errors_figure([ex3, slow], FigureOptions()).figure
        pose = pose_figure([ex3, slow], FigureOptions()).figure
    titles = [ax.get_title() for ax in _zooms(fig) if ax.get_title()]
    assert len(titles) == 2 and titles[0] == titles[1] and titles[0].startswith("first")
    assert [t.get_text() for t in errors.legends[0].get_texts()] == ["ex3", "c0=5"]
    commanded = [t.get_text() for t in pose.legends[0].get_texts() if "R_c" in t.get_text()]
    assert commanded == ["ex3: commanded $R_c$", "c0=5: commanded $R_c$"]
