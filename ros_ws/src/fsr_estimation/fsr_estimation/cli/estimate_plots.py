"""The report's exercise-3 figures (PNG, matplotlib Agg) from a ``fsr-estimate`` sweep.

* ``estimates_r<r>.png``: the six estimated channels for every c0 at filter order r (report Figs. 2-7);
* ``estimates_c0_<c0>.png``: the same for every r at one c0;
* ``error_c0_<c0>.png``: estimation error vs time for every r (Fig. 8), channels with a non-zero truth;
* ``mae_vs_r.png`` and ``settling_vs_r.png``: MAE and settling time against r, one line per c0 (Figs. 10-11).

Force in world NED [N], torque in Euler-angle coordinates [N m] (the frame of ``w_hat``).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 - the backend must be chosen first
import numpy as np  # noqa: E402

from fsr_estimation.estimator.metrics import CHANNELS, SweepResult  # noqa: E402
from fsr_estimation.io.flight_log import FlightLog  # noqa: E402

LABELS = {"fx": "f_x [N]", "fy": "f_y [N]", "fz": "f_z [N]", "tx": "tau_x [N m]", "ty": "tau_y [N m]",
          "tz": "tau_z [N m]"}


def _channel_axes(title: str, count: int = 6) -> tuple[plt.Figure, np.ndarray]:
    rows = 3 if count > 3 else count
    cols = 2 if count > 3 else 1
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.6 * rows + 0.6), sharex=True, squeeze=False)
    fig.suptitle(title)
    return fig, axes.T.reshape(-1)  # column-major: forces left, torques right


def _plot_estimates(path: Path, time: np.ndarray, runs: list[SweepResult], label: str, truth: np.ndarray | None,
                    title: str) -> None:
    fig, axes = _channel_axes(title)
    for run in runs:
        for i, ax in enumerate(axes):
            ax.plot(time, run.estimate[:, i], linewidth=0.9, label=label.format(c0=run.c0, r=run.r))
    for i, ax in enumerate(axes):
        if truth is not None:
            ax.axhline(truth[i], color="k", linestyle="--", linewidth=0.9, label="truth")
        ax.set_ylabel(LABELS[CHANNELS[i]])
        ax.grid(True, alpha=0.3)
    axes[2].set_xlabel("time [s]")
    axes[5].set_xlabel("time [s]")
    axes[0].legend(loc="best", fontsize="small")
    _save(fig, path)


def _save(fig: plt.Figure, path: Path) -> None:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def write_plots(directory: Path, log: FlightLog, results: list[SweepResult], truth: np.ndarray | None,
                settling: str) -> list[Path]:
    """Write the figures into ``directory`` (existing); returns the files written."""
    time = log.time - log.time[0]
    c0_values = list(dict.fromkeys(r.c0 for r in results))
    r_values = list(dict.fromkeys(r.r for r in results))
    written = []
    for order in r_values:
        runs = [r for r in results if r.r == order]
        path = directory / f"estimates_r{order}.png"
        _plot_estimates(path, time, runs, "c0 = {c0:g}", truth, f"Estimated wrench for different c0, r = {order}")
        written.append(path)
    for c0 in c0_values:
        runs = [r for r in results if r.c0 == c0]
        path = directory / f"estimates_c0_{c0:g}.png"
        _plot_estimates(path, time, runs, "r = {r}", truth, f"Estimated wrench for different r, c0 = {c0:g} rad/s")
        written.append(path)
    if truth is None:
        return written
    shown = [i for i, value in enumerate(truth) if value != 0.0] or list(range(6))
    for c0 in c0_values:
        fig, axes = _channel_axes(f"Estimation error w_hat - truth for different r, c0 = {c0:g} rad/s", len(shown))
        for run in (r for r in results if r.c0 == c0):
            for ax, i in zip(axes, shown, strict=False):
                ax.plot(time, run.estimate[:, i] - truth[i], linewidth=0.9, label=f"r = {run.r}")
        for ax, i in zip(axes, shown, strict=False):
            ax.set_ylabel("error " + LABELS[CHANNELS[i]])
            ax.grid(True, alpha=0.3)
        axes[len(shown) - 1].set_xlabel("time [s]")
        axes[0].legend(loc="best", fontsize="small")
        path = directory / f"error_c0_{c0:g}.png"
        _save(fig, path)
        written.append(path)
    for name, attribute, unit in (("mae_vs_r", "mae", ""), ("settling_vs_r", "settling_time", " [s]")):
        fig, axes = plt.subplots(1, len(shown), figsize=(4 * len(shown), 3.6), squeeze=False)
        what = "Mean absolute error" if attribute == "mae" else f"Settling time ({settling}, 3 % band)"
        fig.suptitle(f"{what} vs filter order r")
        for ax, i in zip(axes[0], shown, strict=True):
            for c0 in c0_values:
                runs = [r for r in results if r.c0 == c0]
                ax.plot([r.r for r in runs], [getattr(r, attribute)[i] for r in runs], marker="o", label=f"c0 = {c0:g}")
            channel_unit = LABELS[CHANNELS[i]].split(" ", 1)[1] if attribute == "mae" else unit.strip()
            ax.set_title(LABELS[CHANNELS[i]].split(" ")[0])
            ax.set_xlabel("filter order r")
            ax.set_ylabel(("MAE " if attribute == "mae" else "settling time ") + channel_unit)
            ax.set_xticks(r_values)
            ax.grid(True, alpha=0.3)
        axes[0][0].legend(loc="best", fontsize="small")
        path = directory / f"{name}.png"
        _save(fig, path)
        written.append(path)
    return written
