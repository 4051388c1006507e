r"""Figures of one or several flights for a paper (matplotlib, Agg, no pyplot state).

Each ``*_figure`` function draws one figure from a list of :class:`Run` (one run, or several overlaid: two
estimator settings, two controllers) and returns it, or a reason why it has nothing to show (topics
missing, no surface effect, no rotors); :func:`draw_and_save` saves one in every requested format and turns
the reason into a note (:mod:`fsr_bringup.analysis.figure_jobs` draws them all, in worker processes).
Conventions, the same in every figure:

* size: one journal column (3.5 in) or two (7.16 in) wide, 8 pt text (:data:`RC`), no title inside the
  figure unless asked for; the scenario and the runs go into the file's metadata (PNG text chunks, PDF info,
  SVG ``<metadata>``) and into ``summary.md``;
* every axis label names its quantity in math notation (mathtext: ``$p_x$``, ``$\tau_x$``,
  ``$\|e_\Omega\|$``, ``$f_{e,x}$``), its frame (world NED, body FRD, ZYX Euler) and unit; time is the
  simulated time ``$t$`` [s];
* colours from the Okabe-Ito palette (colour-blind safe), one meaning per colour in a figure: a run per
  colour (:data:`RUN_COLOURS`), black dashed the reference / the truth the estimate must reach, a run's
  colour dashed its commanded attitude ``R_c``, grey what is only shown for comparison (the external wrench
  alone, model values, limits); in rotor figures a rotor per colour; light grey bands the time a windowed
  disturbance acts;
* a panel whose data spans less than its :data:`FLOORS` value is drawn on a fixed axis of that height with
  a note (no autoscaled rounding noise), tick labels without offset notation;
* the rules of :mod:`fsr_bringup.analysis.figure_rules`: a zoom on the first seconds beside the panels of a
  figure with a start transient shorter than 2 % of its time axis, limits drawn only near the data, no
  panel that is zero by construction, disturbance windows shaded;
* one legend above the panels, never over the data; panels placed by
  :mod:`fsr_bringup.analysis.figure_layout` (one measurement, no layout engine);
* long series are decimated for drawing only (:func:`envelope`: per-bucket min and max, so peaks survive);
  metrics always use every sample.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.legend import Legend
from matplotlib.ticker import MaxNLocator

from fsr_bringup.analysis.effective import thrust_ratio_series
from fsr_bringup.analysis.figure_jobs import Run
from fsr_bringup.analysis.figure_layout import PNG_DPI, Panel, Panels, add_zoom, arrange, envelope, panel_grid
from fsr_bringup.analysis.figure_options import FigureOptions
from fsr_bringup.analysis.figure_rules import disturbance_windows, limits_near, start_transient, zoom_span
from fsr_bringup.analysis.metrics import tracking_errors
from fsr_bringup.visualization.frames import NED_TO_ENU
from fsr_sim.contract import ODOM, REFERENCE, ROTOR_STATE, WRENCH_CMD
from fsr_sim.model.so3 import euler_zyx_from_rotation

ONE_COLUMN_IN = 3.5  # in, one journal column
TWO_COLUMN_IN = 7.16  # in, full page width (two columns)
FONT_PT = 8.0
AXES = ("x", "y", "z")
EULER = (r"roll $\phi$", r"pitch $\theta$", r"yaw $\psi$")
TIME_LABEL = r"time $t$ [s]"
ZOOM_TIME_LABEL = r"$t$ [s]"

# Okabe & Ito (2008), colour-universal design.
OKABE_ITO = {
    "black": "#000000", "orange": "#E69F00", "sky_blue": "#56B4E9", "bluish_green": "#009E73",
    "yellow": "#F0E442", "blue": "#0072B2", "vermillion": "#D55E00", "reddish_purple": "#CC79A7",
}
RUN_COLOURS = tuple(OKABE_ITO[k] for k in ("blue", "vermillion", "bluish_green", "reddish_purple", "orange",
                                           "sky_blue"))
ROTOR_COLOURS = tuple(OKABE_ITO[k] for k in ("blue", "vermillion", "bluish_green", "reddish_purple", "orange",
                                             "sky_blue", "yellow", "black"))
TRUTH = {"color": OKABE_ITO["black"], "ls": "--", "lw": 1.0}
COMMANDED = {"ls": (0, (5.0, 1.5)), "lw": 0.9}  # in the run's colour: what its controller commanded (R_c)
ASIDE = {"color": "0.55", "ls": ":", "lw": 1.0}  # grey: shown for comparison only (not a target)
LIMIT = {"color": "0.55", "ls": "-.", "lw": 0.8}
DISTURBANCE = {"facecolor": "0.9", "edgecolor": "none", "zorder": 0.0}  # behind the grid and the data
DISTURBANCE_LABEL = "disturbance acting"

# Smallest axis height per unit: a channel spanning less is drawn flat on this fixed axis, with a note.
FLOORS = {"m": 1e-3, "m/s": 1e-3, r"m/s$^2$": 1e-3, "deg": 1e-3, "rad/s": 1e-3, "N": 1e-3, "N m": 1e-4, "kg": 1e-4,
          "-": 1e-4, "rotor rad/s": 1e-2}
PATH_POINTS = 3000  # a path is drawn through at most this many samples
PNG_COMPRESS_LEVEL = 1  # zlib's fastest: a figure's file about a fifth larger, 10-15 % less CPU to draw and save
PATH_FIGURE_HEIGHT_IN = 3.2
PATH_FLAT_SHARE = 0.25  # the 3D box is at least this share of its widest half-extent along each axis
PATH_3D_ZOOM = 0.85  # the 3D box within its axes (room for the tick and axis labels)

RC = {
    "font.size": FONT_PT, "axes.labelsize": FONT_PT, "axes.titlesize": FONT_PT, "xtick.labelsize": FONT_PT,
    "ytick.labelsize": FONT_PT, "legend.fontsize": FONT_PT, "figure.titlesize": FONT_PT + 1,
    "axes.formatter.useoffset": False, "axes.formatter.limits": (-4, 5), "lines.linewidth": 1.0,
    "axes.linewidth": 0.6, "grid.linewidth": 0.4, "grid.alpha": 0.4, "legend.frameon": False,
    "svg.fonttype": "none", "pdf.fonttype": 42, "savefig.dpi": PNG_DPI, "font.family": "DejaVu Sans",
    "mathtext.fontset": "dejavusans",
}


@dataclass
class Drawn:
    """A drawn figure, or why there is none (``figure`` None and ``reason``)."""

    figure: Figure | None
    reason: str = ""
    notes: list[str] = field(default_factory=list)


def _apply_floor(panel: Panel) -> str | None:
    """Fixed axis for a panel whose data spans less than its floor; returns the note drawn on it."""
    floor = FLOORS.get(panel.unit) if panel.unit else None
    extent = panel.data_range() if floor is not None else None
    if extent is None:
        return None
    low, high = extent
    if high - low >= floor:
        return None
    centre = round(0.5 * (low + high) / floor) * floor
    bottom = 0.0 if low >= 0.0 and centre - floor < 0.0 else centre - floor  # a norm stays on [0, 2 floor]
    panel.ax.set_ylim(bottom, bottom + 2.0 * floor)
    note = f"range < {floor:g} {panel.unit.removeprefix('rotor ')}"
    panel.ax.text(0.99, 0.04, note, transform=panel.ax.transAxes, ha="right", va="bottom", color="0.35")
    return note


def _time_range(panels: Panels) -> tuple[float, float] | None:
    times = [t for panel in panels.flat for t, _, _ in panel.series if len(t)]
    if not times:
        return None
    return min(float(t[0]) for t in times), max(float(t[-1]) for t in times)


def _windows(runs: Iterable[Run], t_range: tuple[float, float]) -> list[tuple[float, float]]:
    """The disturbance windows of the runs' scenarios (:func:`.figure_rules.disturbance_windows`)."""
    profiles = [p for run in runs if run.flight.config is not None for p in run.flight.config.disturbances]
    return disturbance_windows(profiles, *t_range)


def _shade(panels: Panels, windows: list[tuple[float, float]]) -> None:
    for panel in panels.flat:
        for start, end in windows:
            panel.ax.axvspan(start, end, label=DISTURBANCE_LABEL, **DISTURBANCE)
            if panel.zoom is not None:
                low, high = panel.zoom.get_xlim()
                if start < high and end > low:
                    panel.zoom.axvspan(max(start, low), min(end, high), **DISTURBANCE)


def finish_panels(panels: Panels, runs: list[Run], title: str, options: FigureOptions, legend_cols: int = 4,
                  zoom: bool = True) -> None:
    """What every figure does once its data are drawn (:func:`~fsr_bringup.analysis.figure_layout.panel_grid`,
    :meth:`~fsr_bringup.analysis.figure_layout.Panel.plot`): floors, the zoom on a short start transient
    (``zoom``), the runs' disturbance windows, grid, time labels, one legend above the panels (no duplicates;
    at most ``legend_cols`` columns), the ``title`` if the options ask for titles, then the layout."""
    for panel in panels.flat:
        _apply_floor(panel)
    t_range = _time_range(panels)
    if t_range is not None:
        if zoom:
            transients = [start_transient([(t, y) for t, y, _ in panel.series], FLOORS.get(panel.unit, 0.0))
                          for panel in panels.flat]
            span = zoom_span(transients, t_range[1] - t_range[0])
            if span is not None:
                add_zoom(panels, t_range[0], span, f"first {span:g} s")
        _shade(panels, _windows(runs, t_range))
    handles: dict[str, object] = {}
    entries = [panel.ax.get_legend_handles_labels() for panel in panels.flat]
    for found, labels in sorted(entries, key=lambda entry: -len(entry[1])):  # the fullest panel sets the order
        for handle, label in zip(found, labels, strict=True):
            handles.setdefault(label, handle)
    for panel in panels.flat:
        for ax in (panel.ax, panel.zoom):
            if ax is not None:
                ax.grid(True)
    for panel in panels.cells[-1]:
        panel.ax.set_xlabel(TIME_LABEL)
        if panel.zoom is not None:
            panel.zoom.set_xlabel(ZOOM_TIME_LABEL)
    legend = _legend(panels.fig, handles, legend_cols) if handles else None
    arrange(panels, legend, title if options.titles else None)


def _legend(fig: Figure, handles: dict[str, object], most: int) -> Legend:
    """The figure's legend in the most columns (at most ``most``) that fit in its width, measured."""
    def legend(ncols: int) -> Legend:
        return fig.legend(list(handles.values()), list(handles), loc="upper center", ncols=ncols,
                          handlelength=2.0, columnspacing=1.2)

    renderer = fig.canvas.get_renderer()
    for ncols in range(min(most, len(handles)), 1, -1):
        wide = legend(ncols)
        if wide.get_window_extent(renderer).width <= fig.bbox.width:
            return wide
        wide.remove()
    return legend(1)


def _width(natural: str, options: FigureOptions) -> float:
    choice = natural if options.width == "auto" else options.width
    return TWO_COLUMN_IN if choice == "two" else ONE_COLUMN_IN


def _degrees_unwrapped(rpy: np.ndarray, yaw_near: float | None = None) -> np.ndarray:
    """Euler angles in degrees with yaw unwrapped (no +-180 deg jumps in a turning flight), its first value
    shifted by whole turns to within 180 deg of ``yaw_near`` [deg] (the same branch as the flown yaw)."""
    out = np.degrees(rpy)
    out[:, 2] = np.degrees(np.unwrap(rpy[:, 2]))
    if yaw_near is not None and len(out) and math.isfinite(out[0, 2]):
        out[:, 2] += 360.0 * round((yaw_near - out[0, 2]) / 360.0)
    return out


def _colour(index: int) -> str:
    return RUN_COLOURS[index % len(RUN_COLOURS)]


def pose_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Position (world NED) [m] and ZYX Euler attitude [deg] of each run (solid), its commanded attitude
    ``R_c`` (``attitude_cmd``: what the attitude error of the summary is measured against; dashed, the run's
    colour) and the planner's reference ``p_d``, ``R_d`` (black dashed)."""
    runs_with = [r for r in runs if r.flight.true_odom is not None]
    if not runs_with:
        return Drawn(None, "no odom")
    panels = panel_grid(3, 2, _width("two", options))
    notes = []
    yaw_start = None
    for index, run in enumerate(runs_with):
        odom = run.flight.true_odom
        rpy = _degrees_unwrapped(euler_zyx_from_rotation(odom.rotation), yaw_start)
        yaw_start = rpy[0, 2] if yaw_start is None else yaw_start
        style = {"color": _colour(index), "label": f"{run.label}: $p$, $R$"}
        for i in range(3):
            panels[i, 0].plot(odom.t, odom.position[:, i], **style)
            panels[i, 1].plot(odom.t, rpy[:, i], **style)
        commanded = run.flight.attitude_cmd
        if commanded is None:
            notes.append(f"pose: {run.label} has no attitude_cmd; its commanded attitude R_c is not drawn")
            continue
        rpy_c = _degrees_unwrapped(euler_zyx_from_rotation(commanded.rotation), rpy[0, 2])
        for i in range(3):
            panels[i, 1].plot(commanded.t, rpy_c[:, i], color=_colour(index),
                              label=f"{run.label}: commanded $R_c$", **COMMANDED)
    ref = next((r.flight.reference for r in runs_with if r.flight.reference is not None), None)
    if ref is not None:
        ref_rpy = _degrees_unwrapped(euler_zyx_from_rotation(ref.rotation), yaw_start)
        for i in range(3):
            panels[i, 0].plot(ref.t, ref.position[:, i], label=f"{REFERENCE.name} $p_d$, $R_d$", **TRUTH)
            panels[i, 1].plot(ref.t, ref_rpy[:, i], label=f"{REFERENCE.name} $p_d$, $R_d$", **TRUTH)
    for i, (name, angle) in enumerate(zip(AXES, EULER, strict=True)):
        panels[i, 0].label(f"$p_{name}$", "m", "world NED")
        panels[i, 1].label(angle, "deg", "ZYX Euler")
    finish_panels(panels, runs_with, "pose vs reference", options, legend_cols=3)
    return Drawn(panels.fig, notes=notes)


def errors_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Tracking error norms of each run: position and velocity (world), attitude angle of ``R_c^T R``
    (commanded attitude), angular velocity (body)."""
    series = [(index, run, tracking_errors(run.flight)) for index, run in enumerate(runs)]
    series = [s for s in series if s[2] is not None]
    if not series:
        return Drawn(None, "odom or reference missing")
    panels = panel_grid(4, 1, _width("one", options), row_height=0.95)
    notes = []
    for index, run, errors in series:
        style = {"color": _colour(index), "label": run.label}
        panels[0, 0].plot(errors.t, np.linalg.norm(errors.position, axis=1), **style)
        panels[1, 0].plot(errors.t, np.linalg.norm(errors.velocity, axis=1), **style)
        panels[2, 0].plot(errors.t, errors.attitude_deg, **style)
        panels[3, 0].plot(errors.t, np.linalg.norm(errors.angular_velocity, axis=1), **style)
        if not errors.attitude_commanded:
            notes.append(f"errors: {run.label} has no attitude_cmd; its attitude error is against R_d")
    panels[0, 0].label(r"$\|e_p\|$", "m", "world NED")
    panels[1, 0].label(r"$\|e_v\|$", "m/s", "world NED")
    panels[2, 0].label(r"$\angle(R_c^\top R)$", "deg", "rotation angle")
    panels[3, 0].label(r"$\|e_\Omega\|$", "rad/s", "body FRD")
    finish_panels(panels, [run for _, run, _ in series], "tracking errors", options, legend_cols=3)
    return Drawn(panels.fig, notes=notes)


def wrench_command_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Commanded body force [N] and torque [N m] (``wrench_cmd``, body FRD) of each run, with ``-m g``. A
    vehicle that is not fully actuated commands thrust along ``-z_b`` only: its ``f_x``, ``f_y`` (zero by
    construction) have no panel and the figure is one column of ``f_z``, ``tau_x``, ``tau_y``, ``tau_z``."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.wrench_cmd is not None]
    if not runs_with:
        return Drawn(None, "no wrench_cmd")
    configs = [r.flight.config for _, r in runs_with]
    thrust_only = all(c is not None and not c.vehicle.fully_actuated for c in configs)
    if thrust_only:
        panels = panel_grid(4, 1, _width("one", options), row_height=0.95)
        force_panels = {2: panels[0, 0]}
        torque_panels = {i: panels[i + 1, 0] for i in range(3)}
    else:
        panels = panel_grid(3, 2, _width("two", options))
        force_panels = {i: panels[i, 0] for i in range(3)}
        torque_panels = {i: panels[i, 1] for i in range(3)}
    for index, run in runs_with:
        cmd = run.flight.wrench_cmd
        for i, panel in force_panels.items():
            panel.plot(cmd.t, cmd.force[:, i], color=_colour(index), label=run.label)
        for i, panel in torque_panels.items():
            panel.plot(cmd.t, cmd.torque[:, i], color=_colour(index), label=run.label)
    if configs[0] is not None:
        weight = configs[0].vehicle.weight
        force_panels[2].hline(-weight, label=f"$-m g$ (controller model, {weight:.2f} N)", **ASIDE)
    for i, panel in force_panels.items():
        panel.label(f"$f_{AXES[i]}$", "N", "body FRD")
    for i, panel in torque_panels.items():
        panel.label(rf"$\tau_{AXES[i]}$", "N m", "body FRD")
    finish_panels(panels, [run for _, run in runs_with], "commanded wrench", options,
                  legend_cols=2 if thrust_only else 4)
    notes = ([f"{WRENCH_CMD.name}: no f_x, f_y panels (thrust along -z_b only: zero by construction)"]
             if thrust_only else [])
    return Drawn(panels.fig, notes=notes)


def _limit_lines(panel: Panel, limits: Iterable[float], label: str) -> None:
    """The ``limits`` near the panel's data as grey lines (:func:`~fsr_bringup.analysis.figure_rules.limits_near`)."""
    extent = panel.data_range()
    if extent is not None:
        for limit in limits_near(*extent, limits):
            panel.hline(limit, label=label, **LIMIT)


ROTORS_PER_PANEL = 2  # beyond PANEL_ROTORS rotors, a panel per pair: eight overlaid traces cannot be told apart
PANEL_ROTORS = 4
MEASURED = {"ls": (0, (2.0, 1.2)), "lw": 0.9}  # in the rotor's colour: what the rotor did (rotor_state)


def rotor_groups(count: int) -> list[list[int]]:
    """The rotors (0-based) drawn in each panel: all of them up to :data:`PANEL_ROTORS`, else pairs."""
    if count <= PANEL_ROTORS:
        return [list(range(count))]
    return [list(range(i, min(i + ROTORS_PER_PANEL, count))) for i in range(0, count, ROTORS_PER_PANEL)]


def rotors_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Commanded rotor speeds [rad/s] (and tilt angles [deg]) per run, a colour per rotor, and - where the rotors
    lag their commands - what they did (``rotor_state``, dashed in the same colour), on axes scaled to the
    data; more than four rotors get a panel per pair (rows), so that each trace can be followed; a limit is
    drawn (grey) where the data come near it."""
    runs_with = [r for r in runs if r.flight.rotor_cmd is not None]
    if not runs_with:
        return Drawn(None, "no rotor_cmd (wrench actuation has no rotors, or not recorded)")
    tilting = any(r.flight.rotor_cmd.tilts is not None for r in runs_with)
    groups = [rotor_groups(r.flight.rotor_cmd.speeds.shape[1]) for r in runs_with]
    rows = sum(len(g) for g in groups)
    panels = panel_grid(rows, 2 if tilting else 1, _width("two" if tilting else "one", options),
                        row_height=1.5 if rows == len(runs_with) else 1.15)
    row = 0
    for run, rotor_sets in zip(runs_with, groups, strict=True):
        cmd, actual = run.flight.rotor_cmd, run.flight.rotor_state
        vehicle = run.flight.config.vehicle if run.flight.config is not None else None
        prefix = f"{run.label}: " if len(runs_with) > 1 else ""
        for rotors in rotor_sets:
            which = "rotor axis" if len(rotor_sets) == 1 else f"rotors {', '.join(str(i + 1) for i in rotors)}"
            for i in rotors:
                colour = ROTOR_COLOURS[i % len(ROTOR_COLOURS)]
                panels[row, 0].plot(cmd.t, cmd.speeds[:, i], color=colour, label=f"rotor {i + 1}")
                if actual is not None and i < actual.speeds.shape[1]:
                    panels[row, 0].plot(actual.t, actual.speeds[:, i], color=colour,
                                        label=f"{ROTOR_STATE.name} (measured)", **MEASURED)
                if tilting and cmd.tilts is not None:
                    panels[row, 1].plot(cmd.t, np.degrees(cmd.tilts[:, i]), color=colour, label=f"rotor {i + 1}")
                    if actual is not None and actual.tilts is not None and i < actual.tilts.shape[1]:
                        panels[row, 1].plot(actual.t, np.degrees(actual.tilts[:, i]), color=colour,
                                            label=f"{ROTOR_STATE.name} (measured)", **MEASURED)
            panels[row, 0].label(prefix + r"$\omega_{c,i}$", "rotor rad/s", which)
            if vehicle is not None:
                _limit_lines(panels[row, 0], (vehicle.rotor_speed_min, vehicle.rotor_speed_max),
                             r"speed limits $\omega_{\min}$, $\omega_{\max}$")
            if tilting:
                panels[row, 1].label(prefix + r"$\alpha_{c,i}$", "deg",
                                     "about the arm" if len(rotor_sets) == 1 else which)
                if vehicle is not None and vehicle.tilt_angle_max < math.pi:
                    limit = math.degrees(vehicle.tilt_angle_max)
                    _limit_lines(panels[row, 1], (-limit, limit), r"tilt limits $\pm\alpha_{\max}$")
            row += 1
    finish_panels(panels, runs_with, "rotor commands", options, legend_cols=5)
    return Drawn(panels.fig)


def external_wrench_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Online wrench estimate of each run vs the effective truth (black dashed) in body FRD; the external
    wrench alone (``wrench_truth``) in grey for comparison. The estimator starts from zero: its settling
    (a few tenths of a second) gets a zoom on a long flight (:mod:`~fsr_bringup.analysis.figure_rules`)."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.wrench_estimate is not None]
    if not runs_with:
        return Drawn(None, "no wrench_estimate (estimator off, or not recorded)")
    panels = panel_grid(3, 2, _width("two", options))
    for index, run in runs_with:
        est = run.flight.wrench_estimate
        for i in range(3):
            panels[i, 0].plot(est.t, est.force[:, i], color=_colour(index), label=f"estimate, {run.label}")
            panels[i, 1].plot(est.t, est.torque[:, i], color=_colour(index), label=f"estimate, {run.label}")
    notes = []
    for _, run in runs_with:
        eff = run.effective
        if eff is None:
            notes.append(f"external_wrench: no effective truth for {run.label} (scenario or wrench_cmd missing)")
            continue
        for i in range(3):
            panels[i, 0].plot(eff.t, eff.force_body[:, i], label="effective truth", **TRUTH)
            panels[i, 1].plot(eff.t, eff.torque_body[:, i], label="effective truth", **TRUTH)
    truth = runs_with[0][1].flight.wrench_truth
    if truth is not None:
        for i in range(3):
            panels[i, 0].plot(truth.t, truth.force[:, i], label="external wrench only", **ASIDE)
            panels[i, 1].plot(truth.t, truth.torque[:, i], label="external wrench only", **ASIDE)
    for i, name in enumerate(AXES):
        panels[i, 0].label(f"$f_{{e,{name}}}$", "N", "body FRD")
        panels[i, 1].label(rf"$\tau_{{e,{name}}}$", "N m", "body FRD")
    finish_panels(panels, [run for _, run in runs_with], "wrench estimate vs effective truth", options, legend_cols=3)
    return Drawn(panels.fig, notes=notes)


def mass_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Mass estimate ``m_e + f_e,z / g`` [kg] of each run vs the true plant mass and the estimator's model."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.mass_estimate is not None]
    if not runs_with:
        return Drawn(None, "no mass_estimate (estimator off, or not recorded)")
    panels = panel_grid(1, 1, _width("one", options), row_height=1.8)
    panel = panels[0, 0]
    for index, run in runs_with:
        mass = run.flight.mass_estimate
        panel.plot(mass.t, mass.value, color=_colour(index), label=f"estimate, {run.label}")
    flight = runs_with[0][1].flight
    if flight.config is not None:
        panel.hline(flight.config.plant_vehicle.mass, label="true plant mass $m$", **TRUTH)
    if flight.estimator is not None:
        panel.hline(flight.estimator.mass, label="estimator model mass $m_e$", **ASIDE)
    panel.label(r"$\hat{m}$", "kg", r"$m_e + f_{e,z}/g$")
    finish_panels(panels, [run for _, run in runs_with], "mass estimate", options, legend_cols=2)
    return Drawn(panels.fig)


def thrust_ratio_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Thrust ratio ``T / T_OGE`` per rotor near the ground and the ceiling (first run with rotors and an
    active surface effect), with the height above the ground in grey (its own axis on the right: this figure
    has no zoom, which would not repeat it)."""
    for run in runs:
        flight = run.flight
        if flight.config is None or flight.config.actuation != "rotors" or flight.rotor_cmd is None:
            continue
        series = thrust_ratio_series(flight)
        if series is None:
            continue
        t, ground, ceiling = series
        shown = [(ratio, name) for ratio, name in ((ground, "ground"), (ceiling, "ceiling"))
                 if np.any(ratio != 1.0)]  # 1 everywhere: no surface in reach (zero effect by construction)
        if not shown:
            continue
        panels = panel_grid(len(shown), 1, _width("one", options), row_height=1.8)
        for row, (ratio, surface) in enumerate(shown):
            if np.allclose(ratio, ratio[:, :1], rtol=0.0, atol=1e-9):  # level flight: every rotor alike
                panels[row, 0].plot(t, ratio[:, 0], color=ROTOR_COLOURS[0], label="every rotor")
            else:
                for i in range(ratio.shape[1]):
                    panels[row, 0].plot(t, ratio[:, i], color=ROTOR_COLOURS[i % len(ROTOR_COLOURS)],
                                        label=f"rotor {i + 1}")
            panels[row, 0].label(rf"{surface} $T/T_{{\mathrm{{OGE}}}}$", "-", "per rotor")
        if flight.true_odom is not None:
            twin = panels.twin(panels[0, 0])
            height = flight.config.environment.ground.height - flight.true_odom.position[:, 2]
            twin.plot(*envelope(flight.true_odom.t, height), **ASIDE)
            twin.set_ylabel("height $h$ [m]\nabove ground", color="0.35")
            panels[0, 0].ax.plot([], [], label="height above ground $h$", **ASIDE)  # its legend entry
        finish_panels(panels, [run], "thrust ratio near surfaces", options, legend_cols=5, zoom=False)
        notes = [f"thrust_ratio: drawn for {run.label}"] if len(runs) > 1 else []
        return Drawn(panels.fig, notes=notes)
    return Drawn(None, "no surface effect acts on rotors in this flight (effect off, no surface in reach, or "
                       "wrench actuation)")


def _moving_reference(runs: list[Run]) -> tuple[list[Run], object | None, str]:
    """(runs with odom and reference, the first reference, why nothing is drawn: "" when its position moves by at
    least the metre floor)."""
    runs_with = [r for r in runs if r.flight.true_odom is not None and r.flight.reference is not None]
    if not runs_with:
        return [], None, "odom or reference missing"
    reference = runs_with[0].flight.reference
    span = np.ptp(reference.position, axis=0).max() if len(reference.t) else 0.0
    if not span >= FLOORS["m"]:
        return [], None, f"the reference does not move (it spans {span:.2g} m): no path to draw"
    return runs_with, reference, ""


def _decimated(points: np.ndarray) -> np.ndarray:
    """At most :data:`PATH_POINTS` evenly spaced rows of ``points`` (the last kept), for drawing a path."""
    stride = max(1, math.ceil(len(points) / PATH_POINTS))
    return np.vstack((points[::stride], points[-1:])) if stride > 1 else points


def path_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """The planned path (``reference``, black dashed) and each run's flown path (``odom``) in 3D and seen from
    above (x-y top view), in east-north-up axes (``(p_y, p_x, -p_z)`` of world NED: up drawn up, north up the
    page of the top view), one scale on every axis."""
    runs_with, reference, reason = _moving_reference(runs)
    if reference is None:
        return Drawn(None, reason)
    fig = Figure(figsize=(_width("two", options), PATH_FIGURE_HEIGHT_IN), dpi=PNG_DPI)
    FigureCanvasAgg(fig)
    space = fig.add_axes((0.0, 0.0, 0.5, 1.0), projection="3d", proj_type="ortho", label="path 3d")
    top = fig.add_axes((0.6, 0.15, 0.38, 0.7), label="path top view")
    paths = [(f"{REFERENCE.name} $p_d$", reference.position, TRUTH)]
    paths += [(f"{run.label}: $p$", run.flight.true_odom.position, {"color": _colour(index), "lw": 1.0})
              for index, run in enumerate(runs_with)]
    for label, position, style in paths:
        east, north, up = (_decimated(position) @ NED_TO_ENU.T).T
        space.plot(east, north, up, label=label, **style)
        top.plot(east, north, label=label, **style)
    start = reference.position[0] @ NED_TO_ENU.T
    space.scatter(*start, color=OKABE_ITO["black"], s=8, label="start", depthshade=False)
    top.plot(start[0], start[1], "o", color=OKABE_ITO["black"], ms=3, label="start")
    everything = np.vstack([position for _, position, _ in paths]) @ NED_TO_ENU.T
    low, high = everything.min(axis=0), everything.max(axis=0)
    half = 0.5 * max(float((high - low).max()), FLOORS["m"]) * 1.05
    middle = 0.5 * (low + high)
    extent = np.maximum(0.5 * (high - low) * 1.05, PATH_FLAT_SHARE * half)  # a flat path: a thin box, not a plane
    for axis, setter in enumerate((space.set_xlim, space.set_ylim, space.set_zlim)):
        setter(middle[axis] - extent[axis], middle[axis] + extent[axis])
    for axis, extent_k in zip((space.xaxis, space.yaxis, space.zaxis), extent, strict=True):
        axis.set_major_locator(MaxNLocator(nbins=max(2, min(5, round(5 * extent_k / half))), steps=[1, 2, 2.5, 5, 10]))
    space.set_box_aspect(tuple(extent), zoom=PATH_3D_ZOOM)
    space.set_xlabel(r"east $p_y$ [m]", labelpad=-2)
    space.set_ylabel(r"north $p_x$ [m]", labelpad=-2)
    space.set_zlabel(r"up $-p_z$ [m]", labelpad=-2)
    space.tick_params(pad=-1)
    top.set_xlim(middle[0] - half, middle[0] + half)
    top.set_ylim(middle[1] - half, middle[1] + half)
    top.set_aspect("equal", adjustable="box")
    top.set_xlabel(r"east $p_y$ [m]" + "\nworld NED, from above")
    top.set_ylabel(r"north $p_x$ [m]")
    top.grid(True)
    handles = dict(zip(*reversed(top.get_legend_handles_labels()), strict=True))
    legend = _legend(fig, handles, 4)
    renderer = fig.canvas.get_renderer()
    legend_bottom = legend.get_window_extent(renderer).y0 / fig.bbox.height
    space.set_position((0.03, 0.08, 0.47, legend_bottom - 0.1))
    box = top.get_tightbbox(renderer)
    frame = top.get_window_extent(renderer)
    below = (frame.y0 - box.y0) / fig.bbox.height
    left = (frame.x0 - box.x0) / fig.bbox.width
    top.set_position((0.55 + left, below + 0.02, 0.43 - left, legend_bottom - below - 0.06))
    if options.titles:
        fig.suptitle("planned and flown path")
    return Drawn(fig)


def speed_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Speed ``|v|`` [m/s] and acceleration ``|a|`` [m/s^2] (world NED) of the reference (black dashed) and of each
    run (``odom``'s velocity and its central differences)."""
    runs_with, reference, reason = _moving_reference(runs)
    if reference is None:
        return Drawn(None, reason)
    panels = panel_grid(2, 1, _width("one", options), row_height=1.2)
    for index, run in enumerate(runs_with):
        odom = run.flight.true_odom
        acceleration = np.gradient(odom.velocity_world, odom.t, axis=0) if len(odom.t) > 1 else odom.velocity_world
        style = {"color": _colour(index), "label": f"{run.label} ({ODOM.name})"}
        panels[0, 0].plot(odom.t, np.linalg.norm(odom.velocity_world, axis=1), **style)
        panels[1, 0].plot(odom.t, np.linalg.norm(acceleration, axis=1), **style)
    label = f"{REFERENCE.name} $p_d$"
    panels[0, 0].plot(reference.t, np.linalg.norm(reference.velocity, axis=1), label=label, **TRUTH)
    panels[1, 0].plot(reference.t, np.linalg.norm(reference.acceleration, axis=1), label=label, **TRUTH)
    panels[0, 0].label(r"speed $\|v\|$", "m/s", "world NED")
    panels[1, 0].label(r"$\|a\|$", r"m/s$^2$", "world NED")
    finish_panels(panels, runs_with, "speed and acceleration", options, legend_cols=2)
    return Drawn(panels.fig)


FIGURES: dict[str, Callable[[list[Run], FigureOptions], Drawn]] = {
    "pose": pose_figure,
    "errors": errors_figure,
    WRENCH_CMD.name: wrench_command_figure,
    "rotors": rotors_figure,
    "external_wrench": external_wrench_figure,
    "mass": mass_figure,
    "thrust_ratio": thrust_ratio_figure,
    "path": path_figure,
    "speed": speed_figure,
}


def figure_metadata(name: str, runs: list[Run], fmt: str) -> dict[str, str]:
    """File metadata naming the figure, the scenario(s) and the recordings (keys as each backend wants)."""
    title = f"fsr {name}: " + ", ".join(f"{r.label} ({r.flight.scenario_name})" for r in runs)
    description = "recordings: " + ", ".join(str(getattr(r.flight.recording, "path", None)) for r in runs)
    if fmt == "pdf":
        return {"Title": title, "Subject": description, "Creator": "fsr-analyze"}
    if fmt == "svg":
        return {"Title": title, "Description": description, "Creator": "fsr-analyze"}
    return {"Title": title, "Description": description, "Software": "fsr-analyze"}


def save_figure(fig: Figure, stem: Path, formats: Iterable[str], metadata: Callable[[str], dict]) -> list[Path]:
    """Write ``fig`` as ``stem.<fmt>`` for each format (PNG at :data:`PNG_DPI`); returns the paths."""
    paths = []
    for fmt in formats:
        path = stem.with_suffix(f".{fmt}")
        _write(fig, path, fmt, metadata(fmt))
        paths.append(path)
    return paths


def _write(fig: Figure, target: Path | io.BytesIO, fmt: str, metadata: dict) -> None:
    extra = {"pil_kwargs": {"compress_level": PNG_COMPRESS_LEVEL}} if fmt == "png" else {}
    fig.savefig(target, format=fmt, dpi=PNG_DPI, metadata=metadata, **extra)


def draw_and_save(name: str, runs: list[Run], out_dir: Path, options: FigureOptions) -> tuple[list[Path], list[str]]:
    """Draw figure ``name`` and save it in every format; returns (written files, notes)."""
    with matplotlib.rc_context(RC):
        drawn = FIGURES[name](runs, options)
        notes = list(drawn.notes)
        if drawn.figure is None:
            return [], [*notes, f"figure {name} left out: {drawn.reason}"]
        return save_figure(drawn.figure, out_dir / name, options.formats,
                           lambda fmt: figure_metadata(name, runs, fmt)), notes


def warm_up() -> None:
    """Draw one small figure the way every figure is drawn (panels, mathtext labels, a legend, the layout, a PNG
    in memory): it fills the caches of matplotlib that a process's first figure fills (font files, mathtext's
    parser, glyphs). The figures' fork server calls it once (:mod:`fsr_bringup.analysis.figure_server`), so each
    worker it forks starts warm: 0.06 s less for a worker's first figure, measured."""
    with matplotlib.rc_context(RC):
        panels = panel_grid(1, 1, ONE_COLUMN_IN)
        panel = panels[0, 0]
        panel.ax.plot([0.0, 1.0], [0.0, 1.0], label="warm-up", **TRUTH)
        panel.ax.set_ylabel(r"$p_x$, $\|e_\Omega\|$, $\tau_x$ [m]")
        panel.ax.set_xlabel(TIME_LABEL)
        panel.ax.text(0.99, 0.04, "range", transform=panel.ax.transAxes, ha="right", va="bottom")
        arrange(panels, _legend(panels.fig, {"warm-up": panel.ax.lines[0]}, 1), "warm-up")
        _write(panels.fig, io.BytesIO(), "png", {})

