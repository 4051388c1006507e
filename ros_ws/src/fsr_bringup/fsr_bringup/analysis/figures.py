"""PNG figures of one flight (matplotlib, Agg, no pyplot state): the report's plots from a recording.

Each ``*_figure`` function draws one file and returns its path, or None when its topics are missing (the
caller records a note). Time axes are simulated time [s]; frames as in :mod:`fsr_bringup.analysis.load`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from fsr_bringup.analysis.load import Flight
from fsr_bringup.analysis.metrics import thrust_ratio_series, tracking_errors
from fsr_sim.model.so3 import euler_zyx_from_rotation

DPI = 110
AXES = ("x", "y", "z")
PLOT_BUCKETS = 1500  # longer series are drawn as per-bucket min and max (same picture, far fewer points)


def envelope(t: np.ndarray, y: np.ndarray, buckets: int = PLOT_BUCKETS) -> tuple[np.ndarray, np.ndarray]:
    """Min-max decimation of a 1-D series for drawing: each of ``buckets`` equal slices keeps its minimum and
    maximum in time order, so peaks (saturation spikes) survive. Short series are returned as they are."""
    n = len(t)
    size = n // buckets
    if size < 4:
        return t, y
    head = buckets * size
    block = y[:head].reshape(buckets, size)
    filled = np.where(np.isnan(block), np.inf, block)
    i_min = np.argmin(filled, axis=1)
    i_max = np.argmax(np.where(np.isnan(block), -np.inf, block), axis=1)
    index = np.sort(np.stack((i_min, i_max), axis=1), axis=1) + (np.arange(buckets) * size)[:, None]
    index = np.concatenate((index.ravel(), np.arange(head, n)))
    return t[index], y[index]


def _plot(ax: Axes, t: np.ndarray, y: np.ndarray, *args: object, **kwargs: object) -> None:
    ax.plot(*envelope(t, y), *args, **kwargs)


def _figure(rows: int, cols: int, title: str, height: float = 2.2) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(max(5.0 * cols, 8.0), height * rows + 0.8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = np.atleast_1d(fig.subplots(rows, cols, sharex=True, squeeze=False))
    fig.suptitle(title)
    return fig, axes


def _save(fig: Figure, path: Path, axes: np.ndarray) -> Path:
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize="small")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.savefig(path, dpi=DPI)
    return path


def _degrees_unwrapped(rpy: np.ndarray) -> np.ndarray:
    """Euler angles in degrees with yaw unwrapped (no +-180 deg jumps in a turning flight)."""
    out = np.degrees(rpy)
    out[:, 2] = np.degrees(np.unwrap(rpy[:, 2]))
    return out


def pose_figure(flight: Flight, path: Path) -> Path | None:
    """Position [m] and ZYX attitude [deg] vs the reference."""
    odom, ref = flight.odom, flight.reference
    if odom is None:
        return None
    fig, axes = _figure(3, 2, f"{flight.scenario_name}: pose vs reference")
    rpy = _degrees_unwrapped(euler_zyx_from_rotation(odom.rotation))
    for i, name in enumerate(AXES):
        ax = axes[i, 0]
        _plot(ax, odom.t, odom.position[:, i], label="actual")
        if ref is not None:
            _plot(ax, ref.t, ref.position[:, i], "--", label="reference")
        ax.set_ylabel(f"{name} (NED) [m]")
    ref_rpy = _degrees_unwrapped(euler_zyx_from_rotation(ref.rotation)) if ref is not None else None
    for i, name in enumerate(("roll", "pitch", "yaw")):
        ax = axes[i, 1]
        _plot(ax, odom.t, rpy[:, i], label="actual")
        if ref is not None:
            _plot(ax, ref.t, ref_rpy[:, i], "--", label="reference")
        ax.set_ylabel(f"{name} [deg]")
    return _save(fig, path, axes)


def errors_figure(flight: Flight, path: Path) -> Path | None:
    """Position, velocity (world), attitude and angular-velocity (body) errors."""
    errors = tracking_errors(flight)
    if errors is None:
        return None
    fig, axes = _figure(4, 1, f"{flight.scenario_name}: tracking errors", height=2.0)
    for ax, values, label, unit in (
        (axes[0, 0], errors.position, "e_p", "m"),
        (axes[1, 0], errors.velocity, "e_v", "m/s"),
        (axes[3, 0], errors.angular_velocity, "e_omega", "rad/s"),
    ):
        for i, name in enumerate(AXES):
            _plot(ax, errors.t, values[:, i], label=f"{label},{name}")
        ax.set_ylabel(f"{label} [{unit}]")
    _plot(axes[2, 0], errors.t, errors.attitude_deg, color="C3", label="angle of R_d^T R")
    axes[2, 0].set_ylabel("attitude error [deg]")
    return _save(fig, path, axes)


def wrench_command_figure(flight: Flight, path: Path) -> Path | None:
    """Commanded thrust / body force [N] and torques [N m] (``wrench_cmd``)."""
    cmd = flight.wrench_cmd
    if cmd is None:
        return None
    fig, axes = _figure(2, 1, f"{flight.scenario_name}: commanded wrench (body FRD)", height=2.6)
    _plot(axes[0, 0], cmd.t, np.linalg.norm(cmd.force, axis=1), color="k", label="u_T = |f|")
    for i, name in enumerate(AXES):
        _plot(axes[0, 0], cmd.t, cmd.force[:, i], label=f"f_{name}", alpha=0.8)
        _plot(axes[1, 0], cmd.t, cmd.torque[:, i], label=f"tau_{name}")
    if flight.config is not None:
        weight = flight.config.vehicle.weight
        axes[0, 0].axhline(weight, color="gray", ls=":", label=f"m g = {weight:.2f} N")
    axes[0, 0].set_ylabel("force [N]")
    axes[1, 0].set_ylabel("torque [N m]")
    return _save(fig, path, axes)


def rotors_figure(flight: Flight, path: Path) -> Path | None:
    """Rotor speeds [rad/s] (and tilt angles [deg]) with the vehicle's limits."""
    cmd = flight.rotor_cmd
    if cmd is None:
        return None
    rows = 2 if cmd.tilts is not None else 1
    fig, axes = _figure(rows, 1, f"{flight.scenario_name}: rotor commands", height=2.8)
    for i in range(cmd.speeds.shape[1]):
        _plot(axes[0, 0], cmd.t, cmd.speeds[:, i], label=f"rotor {i + 1}")
    axes[0, 0].set_ylabel("rotor speed [rad/s]")
    vehicle = flight.config.vehicle if flight.config is not None else None
    if vehicle is not None:
        for limit in (vehicle.rotor_speed_min, vehicle.rotor_speed_max):
            axes[0, 0].axhline(limit, color="r", ls="--", lw=1)
        axes[0, 0].plot([], [], "r--", lw=1, label="limits")
    if cmd.tilts is not None:
        for i in range(cmd.tilts.shape[1]):
            _plot(axes[1, 0], cmd.t, np.degrees(cmd.tilts[:, i]), label=f"tilt {i + 1}")
        axes[1, 0].set_ylabel("tilt angle [deg]")
        if vehicle is not None and vehicle.tilt_angle_max < math.pi:
            for sign in (-1, 1):
                axes[1, 0].axhline(sign * math.degrees(vehicle.tilt_angle_max), color="r", ls="--", lw=1)
    return _save(fig, path, axes)


def external_wrench_figure(flight: Flight, path: Path) -> Path | None:
    """Estimated vs true external wrench, six panels (body FRD)."""
    est, truth = flight.wrench_estimate, flight.wrench_truth
    if est is None and truth is None:
        return None
    fig, axes = _figure(2, 3, f"{flight.scenario_name}: external wrench, estimate vs truth")
    for row, (kind, unit) in enumerate((("force", "N"), ("torque", "N m"))):
        for col, name in enumerate(AXES):
            ax = axes[row, col]
            label = f"{'f' if row == 0 else 'tau'}_{name}"
            if truth is not None:
                _plot(ax, truth.t, getattr(truth, kind)[:, col], "k--", label="true")
            if est is not None:
                _plot(ax, est.t, getattr(est, kind)[:, col], label="estimate")
            ax.set_ylabel(f"{label} [{unit}]")
    return _save(fig, path, axes)


def mass_figure(flight: Flight, path: Path) -> Path | None:
    """Mass estimate [kg] vs the true plant mass and the nominal model mass."""
    mass = flight.mass_estimate
    if mass is None:
        return None
    fig, axes = _figure(1, 1, f"{flight.scenario_name}: mass estimate", height=3.0)
    ax = axes[0, 0]
    _plot(ax, mass.t, mass.value, label="estimate m_model + dm")
    if flight.config is not None:
        ax.axhline(flight.config.plant_vehicle.mass, color="k", ls="--", label="true plant mass")
        ax.axhline(flight.config.vehicle.mass, color="gray", ls=":", label="nominal mass")
    ax.set_ylabel("mass [kg]")
    return _save(fig, path, axes)


def thrust_ratio_figure(flight: Flight, path: Path) -> Path | None:
    """Ground and ceiling thrust ratio ``T / T_OGE`` per rotor along the flight."""
    series = thrust_ratio_series(flight)
    if series is None:
        return None
    t, ground, ceiling = series
    fig, axes = _figure(2, 1, f"{flight.scenario_name}: thrust ratio near surfaces", height=2.6)
    for ax, ratio, surface in ((axes[0, 0], ground, "ground"), (axes[1, 0], ceiling, "ceiling")):
        for i in range(ratio.shape[1]):
            _plot(ax, t, ratio[:, i], label=f"rotor {i + 1}")
        ax.set_ylabel(f"{surface} T / T_OGE [-]")
    if flight.odom is not None and flight.config is not None:
        # Height above the ground on a twin axis: tells why the ratio moves.
        twin = axes[0, 0].twinx()
        height = flight.config.environment.ground.height - flight.odom.position[:, 2]
        _plot(twin, t, height, color="gray", lw=0.8, ls=":")
        twin.set_ylabel("height above ground [m]", color="gray")
    return _save(fig, path, axes)


FIGURES: dict[str, Callable[[Flight, Path], Path | None]] = {
    "pose.png": pose_figure,
    "errors.png": errors_figure,
    "wrench_cmd.png": wrench_command_figure,
    "rotors.png": rotors_figure,
    "external_wrench.png": external_wrench_figure,
    "mass.png": mass_figure,
    "thrust_ratio.png": thrust_ratio_figure,
}


def make_figures(flight: Flight, out_dir: Path) -> tuple[list[Path], list[str]]:
    """Write every figure that the recording allows into ``out_dir``; returns (written, notes)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    written, notes = [], []
    for name, draw in FIGURES.items():
        path = draw(flight, out_dir / name)
        if path is None:
            notes.append(f"figure {name} skipped: its topics (or the scenario) are missing")
        else:
            written.append(path)
    return written, notes

