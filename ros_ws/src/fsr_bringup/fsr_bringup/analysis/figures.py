"""Figures of one or several flights for a paper (matplotlib, Agg, no pyplot state).

Each ``*_figure`` function draws one figure from a list of :class:`Run` (one run, or several overlaid: two
estimator settings, two controllers) and returns it, or a reason why it has nothing to show (topics
missing, no surface effect, no rotors); :func:`make_figures` saves every figure in every requested format
and turns the reasons into notes. Conventions, the same in every figure:

* size: one journal column (3.5 in) or two (7.16 in) wide, 8 pt text (:data:`RC`), no title inside the
  figure unless asked for; the scenario and the runs go into the file's metadata (PNG text chunks, PDF info,
  SVG ``<metadata>``) and into ``summary.md``;
* every axis label names its quantity, frame (world NED, body FRD, ZYX Euler) and unit; time is the
  simulated time [s];
* colours from the Okabe-Ito palette (colour-blind safe), one meaning per colour in a figure: a run per
  colour (:data:`RUN_COLOURS`), black dashed the reference / the truth the estimate must reach, grey what
  is only shown for comparison (the external wrench alone, model values, limits); in rotor figures a rotor
  per colour;
* a panel whose data spans less than its :data:`FLOORS` value is drawn on a fixed axis of that height with
  a note (no autoscaled rounding noise), tick labels without offset notation;
* legends are placed above the panels, never over the data;
* long series are decimated for drawing only (:func:`envelope`: per-bucket min and max, so peaks survive);
  metrics always use every sample.
"""

from __future__ import annotations

import math
import multiprocessing
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fsr_bringup.analysis.effective import EffectiveWrench, effective_wrench, thrust_ratio_series
from fsr_bringup.analysis.figure_options import FORMATS, FigureOptions
from fsr_bringup.analysis.load import RecordedFlight
from fsr_bringup.analysis.metrics import tracking_errors
from fsr_sim.contract import REFERENCE, WRENCH_CMD
from fsr_sim.model.so3 import euler_zyx_from_rotation

ONE_COLUMN_IN = 3.5  # in, one journal column
TWO_COLUMN_IN = 7.16  # in, full page width (two columns)
PNG_DPI = 300
FONT_PT = 8.0
PLOT_BUCKETS = 1500  # longer series are drawn as per-bucket min and max (same picture, far fewer points)
AXES = ("x", "y", "z")

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
ASIDE = {"color": "0.55", "ls": ":", "lw": 1.0}  # grey: shown for comparison only (not a target)
LIMIT = {"color": "0.55", "ls": "-.", "lw": 0.8}

# Smallest axis height per unit: a channel spanning less is drawn flat on this fixed axis, with a note.
FLOORS = {"m": 1e-3, "m/s": 1e-3, "deg": 1e-3, "rad/s": 1e-3, "N": 1e-3, "N m": 1e-4, "kg": 1e-4, "-": 1e-4,
          "rotor rad/s": 1e-2}

RC = {
    "font.size": FONT_PT, "axes.labelsize": FONT_PT, "axes.titlesize": FONT_PT, "xtick.labelsize": FONT_PT,
    "ytick.labelsize": FONT_PT, "legend.fontsize": FONT_PT, "figure.titlesize": FONT_PT + 1,
    "axes.formatter.useoffset": False, "axes.formatter.limits": (-4, 5), "lines.linewidth": 1.0,
    "axes.linewidth": 0.6, "grid.linewidth": 0.4, "grid.alpha": 0.4, "legend.frameon": False,
    "svg.fonttype": "none", "pdf.fonttype": 42, "savefig.dpi": PNG_DPI, "font.family": "DejaVu Sans",
}


@dataclass
class Run:
    """One flight to draw: its label in legends, the decoded recording and its effective truth."""

    label: str
    flight: RecordedFlight
    effective: EffectiveWrench | None = None

    @classmethod
    def of(cls, flight: RecordedFlight, label: str | None = None) -> Run:
        return cls(label or flight.scenario_name, flight, effective_wrench(flight))


@dataclass
class Drawn:
    """A drawn figure, or why there is none (``figure`` None and ``reason``)."""

    figure: Figure | None
    reason: str = ""
    notes: list[str] = field(default_factory=list)


def envelope(t: np.ndarray, y: np.ndarray, buckets: int = PLOT_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """Min-max decimation of a 1-D series for drawing: each of ``buckets`` equal slices keeps its minimum and
    maximum in time order, so peaks (saturation spikes) survive. Short series are returned as they are."""
    n = len(t)
    size = n // buckets
    if size < 4:
        return t, y
    head = buckets * size
    block = y[:head].reshape(buckets, size)
    i_min = np.argmin(np.where(np.isnan(block), np.inf, block), axis=1)
    i_max = np.argmax(np.where(np.isnan(block), -np.inf, block), axis=1)
    index = np.sort(np.stack((i_min, i_max), axis=1), axis=1) + (np.arange(buckets) * size)[:, None]
    index = np.concatenate((index.ravel(), np.arange(head, n)))
    return t[index], y[index]


def _plot(ax: Axes, t: np.ndarray, y: np.ndarray, **kwargs: object) -> None:
    ax.plot(*envelope(t, y), **kwargs)


def _figure(rows: int, cols: int, width: float, row_height: float = 1.15) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(width, row_height * rows + 0.55), layout="constrained")
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True, squeeze=False))
    return fig, axes


def _label(ax: Axes, text: str, unit: str, frame: str = "") -> None:
    """Axis label ``text [unit]`` with the frame on a second line; the unit also selects the panel's floor
    (:data:`FLOORS`)."""
    shown = unit.removeprefix("rotor ")
    ax.set_ylabel(f"{text} [{shown}]" + (f"\n{frame}" if frame else ""))
    ax._fsr_unit = unit  # type: ignore[attr-defined]


def _apply_floor(ax: Axes) -> str | None:
    """Fixed axis for a panel whose data spans less than its floor; returns the note drawn on it."""
    unit = getattr(ax, "_fsr_unit", None)
    floor = FLOORS.get(unit) if unit else None
    if floor is None:
        return None
    values = [np.asarray(line.get_ydata(), dtype=float) for line in ax.get_lines()
              if line.get_transform() == ax.transData]
    values = [v[np.isfinite(v)] for v in values if v.size]
    values = [v for v in values if v.size]
    if not values:
        return None
    low = min(float(v.min()) for v in values)
    high = max(float(v.max()) for v in values)
    if high - low >= floor:
        return None
    centre = round(0.5 * (low + high) / floor) * floor
    bottom = 0.0 if low >= 0.0 and centre - floor < 0.0 else centre - floor  # a norm stays on [0, 2 floor]
    ax.set_ylim(bottom, bottom + 2.0 * floor)
    note = f"range < {floor:g} {unit}"
    ax.text(0.99, 0.04, note, transform=ax.transAxes, ha="right", va="bottom", color="0.35")
    return note


def _finish(fig: Figure, axes: np.ndarray, title: str, options: FigureOptions, legend_cols: int = 4) -> None:
    """Grid, floors, time label, one legend above the panels (no duplicates), optional title."""
    handles: dict[str, object] = {}
    for ax in axes.flat:
        ax.grid(True)
        _apply_floor(ax)
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(label, handle)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside upper center",
                   ncols=_legend_columns(list(handles), fig.get_figwidth(), legend_cols), handlelength=2.0,
                   columnspacing=1.2)
    if options.titles:
        fig.suptitle(title)


def _legend_columns(labels: list[str], width_in: float, most: int) -> int:
    """Most legend columns (at most ``most``) whose entries fit in the figure width: an entry is about its
    text (0.6 em per character) plus the handle and spacing (~3.2 em)."""
    em = FONT_PT / 72.0  # in
    entry = max(len(label) for label in labels) * 0.6 * em + 3.2 * em
    return max(1, min(most, len(labels), int(width_in // entry)))


def _width(natural: str, options: FigureOptions) -> float:
    choice = natural if options.width == "auto" else options.width
    return TWO_COLUMN_IN if choice == "two" else ONE_COLUMN_IN


def _degrees_unwrapped(rpy: np.ndarray) -> np.ndarray:
    """Euler angles in degrees with yaw unwrapped (no +-180 deg jumps in a turning flight)."""
    out = np.degrees(rpy)
    out[:, 2] = np.degrees(np.unwrap(rpy[:, 2]))
    return out


def _colour(index: int) -> str:
    return RUN_COLOURS[index % len(RUN_COLOURS)]


def pose_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Position (world NED) [m] and ZYX Euler attitude [deg] of each run vs the planner's reference."""
    runs_with = [r for r in runs if r.flight.odom is not None]
    if not runs_with:
        return Drawn(None, "no odom")
    fig, axes = _figure(3, 2, _width("two", options))
    ref = next((r.flight.reference for r in runs_with if r.flight.reference is not None), None)
    ref_rpy = _degrees_unwrapped(euler_zyx_from_rotation(ref.rotation)) if ref is not None else None
    for index, run in enumerate(runs_with):
        odom = run.flight.odom
        rpy = _degrees_unwrapped(euler_zyx_from_rotation(odom.rotation))
        for i in range(3):
            _plot(axes[i, 0], odom.t, odom.position[:, i], color=_colour(index), label=run.label)
            _plot(axes[i, 1], odom.t, rpy[:, i], color=_colour(index), label=run.label)
    for i, (name, angle) in enumerate(zip(AXES, ("roll", "pitch", "yaw"), strict=True)):
        if ref is not None:
            _plot(axes[i, 0], ref.t, ref.position[:, i], label=REFERENCE.name, **TRUTH)
            _plot(axes[i, 1], ref.t, ref_rpy[:, i], label=REFERENCE.name, **TRUTH)
        _label(axes[i, 0], f"p_{name}", "m", "world NED")
        _label(axes[i, 1], angle, "deg", "ZYX Euler")
    _finish(fig, axes, "pose vs reference", options)
    return Drawn(fig)


def errors_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Tracking error norms of each run: position and velocity (world), attitude angle of ``R_c^T R``
    (commanded attitude), angular velocity (body)."""
    series = [(index, run, tracking_errors(run.flight)) for index, run in enumerate(runs)]
    series = [s for s in series if s[2] is not None]
    if not series:
        return Drawn(None, "odom or reference missing")
    fig, axes = _figure(4, 1, _width("one", options), row_height=0.95)
    notes = []
    for index, run, errors in series:
        style = {"color": _colour(index), "label": run.label}
        _plot(axes[0, 0], errors.t, np.linalg.norm(errors.position, axis=1), **style)
        _plot(axes[1, 0], errors.t, np.linalg.norm(errors.velocity, axis=1), **style)
        _plot(axes[2, 0], errors.t, errors.attitude_deg, **style)
        _plot(axes[3, 0], errors.t, np.linalg.norm(errors.angular_velocity, axis=1), **style)
        if not errors.attitude_commanded:
            notes.append(f"errors: {run.label} has no attitude_cmd; its attitude error is against R_d")
    _label(axes[0, 0], "|e_p|", "m", "world NED")
    _label(axes[1, 0], "|e_v|", "m/s", "world NED")
    _label(axes[2, 0], "att. error", "deg", "angle of R_c^T R")
    _label(axes[3, 0], "|e_omega|", "rad/s", "body FRD")
    _finish(fig, axes, "tracking errors", options, legend_cols=3)
    return Drawn(fig, notes=notes)


def wrench_command_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Commanded body force [N] and torque [N m] (``wrench_cmd``, body FRD) of each run, with ``-m g``."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.wrench_cmd is not None]
    if not runs_with:
        return Drawn(None, "no wrench_cmd")
    fig, axes = _figure(3, 2, _width("two", options))
    for index, run in runs_with:
        cmd = run.flight.wrench_cmd
        for i in range(3):
            _plot(axes[i, 0], cmd.t, cmd.force[:, i], color=_colour(index), label=run.label)
            _plot(axes[i, 1], cmd.t, cmd.torque[:, i], color=_colour(index), label=run.label)
    config = runs_with[0][1].flight.config
    if config is not None:
        weight = config.vehicle.weight
        axes[2, 0].axhline(-weight, label=f"-m g (controller model, {weight:.2f} N)", **ASIDE)
    for i, name in enumerate(AXES):
        _label(axes[i, 0], f"f_{name}", "N", "body FRD")
        _label(axes[i, 1], f"tau_{name}", "N m", "body FRD")
    _finish(fig, axes, "commanded wrench", options)
    return Drawn(fig)


def rotors_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Rotor speeds [rad/s] (and tilt angles [deg]) per run (one row each), a colour per rotor, limits grey."""
    runs_with = [r for r in runs if r.flight.rotor_cmd is not None]
    if not runs_with:
        return Drawn(None, "no rotor_cmd (wrench actuation has no rotors, or not recorded)")
    tilting = any(r.flight.rotor_cmd.tilts is not None for r in runs_with)
    fig, axes = _figure(len(runs_with), 2 if tilting else 1, _width("two" if tilting else "one", options),
                        row_height=1.5)
    for row, run in enumerate(runs_with):
        cmd = run.flight.rotor_cmd
        vehicle = run.flight.config.vehicle if run.flight.config is not None else None
        prefix = f"{run.label}: " if len(runs_with) > 1 else ""
        for i in range(cmd.speeds.shape[1]):
            colour = ROTOR_COLOURS[i % len(ROTOR_COLOURS)]
            _plot(axes[row, 0], cmd.t, cmd.speeds[:, i], color=colour, label=f"rotor {i + 1}")
            if tilting and cmd.tilts is not None:
                _plot(axes[row, 1], cmd.t, np.degrees(cmd.tilts[:, i]), color=colour, label=f"rotor {i + 1}")
        _label(axes[row, 0], f"{prefix}speed", "rotor rad/s", "rotor axis")
        if vehicle is not None:
            for limit in (vehicle.rotor_speed_min, vehicle.rotor_speed_max):
                axes[row, 0].axhline(limit, label="limits", **LIMIT)
        if tilting:
            _label(axes[row, 1], f"{prefix}tilt", "deg", "about the arm")
            if vehicle is not None and vehicle.tilt_angle_max < math.pi:
                for sign in (-1, 1):
                    axes[row, 1].axhline(sign * math.degrees(vehicle.tilt_angle_max), label="limits", **LIMIT)
    _finish(fig, axes, "rotor commands", options, legend_cols=5)
    return Drawn(fig)


def external_wrench_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Online wrench estimate of each run vs the effective truth (black dashed) in body FRD; the external
    wrench alone (``wrench_truth``) in grey for comparison."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.wrench_estimate is not None]
    if not runs_with:
        return Drawn(None, "no wrench_estimate (estimator off, or not recorded)")
    fig, axes = _figure(3, 2, _width("two", options))
    for index, run in runs_with:
        est = run.flight.wrench_estimate
        for i in range(3):
            _plot(axes[i, 0], est.t, est.force[:, i], color=_colour(index), label=f"estimate, {run.label}")
            _plot(axes[i, 1], est.t, est.torque[:, i], color=_colour(index), label=f"estimate, {run.label}")
    notes = []
    for _, run in runs_with:
        eff = run.effective
        if eff is None:
            notes.append(f"external_wrench: no effective truth for {run.label} (scenario or wrench_cmd missing)")
            continue
        for i in range(3):
            _plot(axes[i, 0], eff.t, eff.force_body[:, i], label="effective truth", **TRUTH)
            _plot(axes[i, 1], eff.t, eff.torque_body[:, i], label="effective truth", **TRUTH)
    truth = runs_with[0][1].flight.wrench_truth
    if truth is not None:
        for i in range(3):
            _plot(axes[i, 0], truth.t, truth.force[:, i], label="external wrench only", **ASIDE)
            _plot(axes[i, 1], truth.t, truth.torque[:, i], label="external wrench only", **ASIDE)
    for i, name in enumerate(AXES):
        _label(axes[i, 0], f"f_{name}", "N", "body FRD")
        _label(axes[i, 1], f"tau_{name}", "N m", "body FRD")
    _finish(fig, axes, "wrench estimate vs effective truth", options, legend_cols=3)
    return Drawn(fig, notes=notes)


def mass_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Mass estimate ``m_e + f_e,z / g`` [kg] of each run vs the true plant mass and the estimator's model."""
    runs_with = [(i, r) for i, r in enumerate(runs) if r.flight.mass_estimate is not None]
    if not runs_with:
        return Drawn(None, "no mass_estimate (estimator off, or not recorded)")
    fig, axes = _figure(1, 1, _width("one", options), row_height=1.8)
    ax = axes[0, 0]
    for index, run in runs_with:
        mass = run.flight.mass_estimate
        _plot(ax, mass.t, mass.value, color=_colour(index), label=f"estimate, {run.label}")
    flight = runs_with[0][1].flight
    if flight.config is not None:
        ax.axhline(flight.config.plant_vehicle.mass, label="true plant mass", **TRUTH)
    if flight.estimator is not None:
        ax.axhline(flight.estimator.mass, label="estimator model mass", **ASIDE)
    _label(ax, "mass", "kg", "m_e + f_e,z / g")
    _finish(fig, axes, "mass estimate", options, legend_cols=2)
    return Drawn(fig)


def thrust_ratio_figure(runs: list[Run], options: FigureOptions) -> Drawn:
    """Thrust ratio ``T / T_OGE`` per rotor near the ground and the ceiling (first run with rotors and an
    active surface effect), with the height above the ground in grey."""
    for run in runs:
        flight = run.flight
        if flight.config is None or flight.config.actuation != "rotors" or flight.rotor_cmd is None:
            continue
        series = thrust_ratio_series(flight)
        if series is None:
            continue
        t, ground, ceiling = series
        panels = [(ratio, name) for ratio, name in ((ground, "ground"), (ceiling, "ceiling"))
                  if np.any(ratio != 1.0)]
        if not panels:
            continue
        fig, axes = _figure(len(panels), 1, _width("one", options), row_height=1.8)
        for row, (ratio, surface) in enumerate(panels):
            if np.allclose(ratio, ratio[:, :1], rtol=0.0, atol=1e-9):  # level flight: every rotor alike
                _plot(axes[row, 0], t, ratio[:, 0], color=ROTOR_COLOURS[0], label="every rotor")
            else:
                for i in range(ratio.shape[1]):
                    _plot(axes[row, 0], t, ratio[:, i], color=ROTOR_COLOURS[i % len(ROTOR_COLOURS)],
                          label=f"rotor {i + 1}")
            _label(axes[row, 0], f"{surface} T/T_OGE", "-", "per rotor")
        if flight.odom is not None:
            twin = axes[0, 0].twinx()
            height = flight.config.environment.ground.height - flight.odom.position[:, 2]
            _plot(twin, flight.odom.t, height, **ASIDE)
            twin.set_ylabel("height [m]\nabove ground", color="0.35")
            axes[0, 0].plot([], [], label="height above ground", **ASIDE)  # its legend entry
        _finish(fig, axes, "thrust ratio near surfaces", options, legend_cols=5)
        notes = [f"thrust_ratio: drawn for {run.label}"] if len(runs) > 1 else []
        return Drawn(fig, notes=notes)
    return Drawn(None, "no surface effect acts on rotors in this flight (effect off, no surface in reach, or "
                       "wrench actuation)")


FIGURES: dict[str, Callable[[list[Run], FigureOptions], Drawn]] = {
    "pose": pose_figure,
    "errors": errors_figure,
    WRENCH_CMD.name: wrench_command_figure,
    "rotors": rotors_figure,
    "external_wrench": external_wrench_figure,
    "mass": mass_figure,
    "thrust_ratio": thrust_ratio_figure,
}


def figure_metadata(name: str, runs: list[Run], fmt: str) -> dict[str, str]:
    """File metadata naming the figure, the scenario(s) and the recordings (keys as each backend wants)."""
    title = f"fsr {name}: " + ", ".join(f"{r.label} ({r.flight.scenario_name})" for r in runs)
    description = "recordings: " + ", ".join(str(r.flight.recording.path) for r in runs)
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
        fig.savefig(path, format=fmt, dpi=PNG_DPI, metadata=metadata(fmt))
        paths.append(path)
    return paths


def draw_and_save(name: str, runs: list[Run], out_dir: Path, options: FigureOptions) -> tuple[list[Path], list[str]]:
    """Draw figure ``name`` and save it in every format; returns (written files, notes)."""
    with matplotlib.rc_context(RC):
        drawn = FIGURES[name](runs, options)
        notes = list(drawn.notes)
        if drawn.figure is None:
            return [], [*notes, f"figure {name} left out: {drawn.reason}"]
        return save_figure(drawn.figure, out_dir / name, options.formats,
                           lambda fmt: figure_metadata(name, runs, fmt)), notes


_JOB: tuple[list[Run], Path, FigureOptions] | None = None  # the figures' input, inherited by forked workers


def _draw_in_worker(name: str) -> tuple[list[Path], list[str]]:
    return draw_and_save(name, *_JOB)


class FigureJob:
    """Figures being drawn: :meth:`result` waits for them. With more than one core they are drawn by forked
    worker processes (one figure each, at most one per core) while the caller goes on (the analysis computes
    its metrics meanwhile); otherwise here, one after the other, when :meth:`result` is called."""

    def __init__(self, runs: list[Run], out_dir: Path, options: FigureOptions) -> None:
        global _JOB
        self.job = (runs, out_dir, options)
        self.pool = self.pending = None
        workers = min(len(FIGURES), len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else 1)
        if workers > 1 and "fork" in multiprocessing.get_all_start_methods():
            _JOB = self.job
            self.pool = multiprocessing.get_context("fork").Pool(workers)
            self.pending = self.pool.map_async(_draw_in_worker, list(FIGURES), chunksize=1)

    def result(self) -> tuple[list[Path], list[str]]:
        """(written files, notes for skipped figures), in the order of :data:`FIGURES`."""
        if self.pool is None:
            results = [draw_and_save(name, *self.job) for name in FIGURES]
        else:
            try:
                results = self.pending.get()
            finally:
                self.pool.close()
                self.pool.join()
        written = [path for paths, _ in results for path in paths]
        return written, [note for _, notes in results for note in notes]


def start_figures(runs: list[Run] | RecordedFlight, out_dir: Path, options: FigureOptions | None = None) -> FigureJob:
    """Start drawing every figure the runs allow into ``out_dir`` (:class:`FigureJob`)."""
    if isinstance(runs, RecordedFlight):
        runs = [Run.of(runs)]
    options = options or FigureOptions()
    unknown = [f for f in options.formats if f not in FORMATS]
    if unknown:
        raise ValueError(f"figure format(s) {', '.join(unknown)} not supported (use {', '.join(FORMATS)})")
    out_dir.mkdir(parents=True, exist_ok=True)
    return FigureJob(runs, out_dir, options)


def make_figures(runs: list[Run] | RecordedFlight, out_dir: Path, options: FigureOptions | None = None
                 ) -> tuple[list[Path], list[str]]:
    """Draw every figure the runs allow into ``out_dir``; returns (written files, notes for skipped ones)."""
    return start_figures(runs, out_dir, options).result()
