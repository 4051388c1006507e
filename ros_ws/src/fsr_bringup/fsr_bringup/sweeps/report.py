"""What ``fsr-sweep`` writes from a sweep's table: ``results.csv`` (and ``results.parquet`` when pyarrow is
installed), ``summary.md`` and figures, in the conventions of :mod:`fsr_bringup.analysis.figures` (one journal
column wide, 8 pt, Okabe-Ito colours, labels with units).

Figures (PNG):

* ``heatmap.png``: with two or more numeric grid axes, the ranked metric (mean over the other axes and the
  samples) over the first two, a cell per pair; cells whose flights all diverged are hatched and marked "div";
* ``<key>.png`` for each swept key: the metric of every flight against the key's value (finished flights as
  dots, diverged ones as red crosses along the top of the axis); a list-valued key (a gain ``[7, 7, 40]``) has
  its values as categories along the axis, in the grid's order;
* ``pareto.png`` (with ``--pareto X,Y``): every finished flight in the plane of the two metrics, the flights on
  the Pareto front joined and numbered (their swept values in a box);
* ``ecdf.png``: with 10 or more flights, the empirical CDF of the position error (RMS and peak) and of the
  metric, over the finished flights, the share that diverged in the legend.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.figure import Figure

from fsr_bringup.analysis.figures import OKABE_ITO, ONE_COLUMN_IN, PNG_DPI, RC
from fsr_bringup.sweeps.axes import key_label
from fsr_bringup.sweeps.metrics import INVALID, METRIC_COLUMNS
from fsr_sim.contract import DIVERGED, FINISHED

UNITS = {"_m": "m", "_deg": "deg", "_s": "s", "_rad_s": "rad/s", "_N": "N", "_N_m": "N m", "_fraction": "-"}
QUANTILES = (0.0, 0.05, 0.5, 0.95, 1.0)
LISTED = 10  # flights listed per section of summary.md


def metric_label(name: str) -> str:
    """``position_error_rms_m`` -> ``position error rms [m]``."""
    for suffix, unit in sorted(UNITS.items(), key=lambda item: -len(item[0])):
        if name.endswith(suffix):
            return f"{name[: -len(suffix)].replace('_', ' ')} [{unit}]"
    return name.replace("_", " ")


def numeric_metrics(table: Any) -> list[str]:
    return [c for c in METRIC_COLUMNS if c in table.columns and table[c].dtype.kind == "f" and c != "flown_s"]


def _scalar_keys(table: Any, keys: list[str]) -> list[str]:
    return [k for k in keys if table[k].map(lambda v: isinstance(v, (int, float))).all()]


def ranked(table: Any, metric: str) -> Any:
    """The finished flights, best (smallest ``metric``) first; NaN last."""
    done = table[table["end_reason"] == FINISHED]
    return done.sort_values(metric, kind="stable", na_position="last")


def write_tables(table: Any, out: Path) -> list[Path]:
    """``results.csv`` (and ``results.parquet`` with pyarrow)."""
    paths = [out / "results.csv"]
    table.to_csv(paths[0])
    try:
        import pyarrow  # noqa: F401
    except ImportError:
        return paths
    frame = table.copy()
    for key in table.attrs.get("keys", []):  # list-valued keys: as text (Parquet wants one type per column)
        if frame[key].dtype == object:
            frame[key] = frame[key].map(repr)
    frame.attrs = {}
    frame.to_parquet(out / "results.parquet")
    return [*paths, out / "results.parquet"]


def _cell(value: Any) -> str:
    if isinstance(value, float):
        return "nan" if math.isnan(value) else f"{value:.4g}"
    return str(value)


def _rows(frame: Any, columns: list[str]) -> list[str]:
    lines = ["| flight | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    for number, row in frame.iterrows():
        lines.append(f"| {number} | " + " | ".join(_cell(row[c]).replace("|", "/") for c in columns) + " |")
    return lines


def summary_markdown(table: Any, metric: str, command: str | None = None,
                     pareto: tuple[str, str] | None = None) -> str:
    """The summary: counts and speed, divergences, quantiles of every metric, the best and worst flights and,
    with ``pareto`` (two metric names; the table's ``pareto`` column marks the front), the front."""
    a = table.attrs
    keys = a.get("keys", [])
    finished = int((table["end_reason"] == FINISHED).sum())
    diverged = table[table["end_reason"] == DIVERGED]
    invalid = table[table["end_reason"] == INVALID]
    wall = a.get("wall_s", float("nan"))
    steps = a.get("vehicle_steps", 0)
    lines = [f"# Sweep of {a.get('scenario', '?')}", ""]
    if command:
        lines += ["```", command, "```", ""]
    lines += [
        f"- flights: {len(table)} ({finished} finished, {len(diverged)} diverged, {len(invalid)} invalid)",
        f"- swept: {', '.join(keys)} (seed {a.get('seed', 0)})",
        f"- {steps} vehicle-steps in {wall:.2f} s on {a.get('workers', '?')} worker(s): "
        f"{len(table) / wall:.1f} flights/s, {steps / wall:.3g} vehicle-steps/s "
        f"(start-up {a.get('startup_s', 0):.2f} s)",
        f"- ranked by {metric} (smallest first)", "",
    ]
    if len(diverged) or len(invalid):
        lines += ["## Flights that did not finish", ""]
        lines += _rows(table[table["end_reason"] != FINISHED].head(LISTED), [*keys, "end_reason", "end_detail"]) + [""]
    metrics = numeric_metrics(table)
    done = table[table["end_reason"] == FINISHED]
    if len(done):
        lines += ["## Quantiles over the finished flights", "",
                  "Over the flights with a finite value; `inf` counts the flights where the metric never came "
                  "(e.g. never settled), `n/a` those where it does not apply (NaN).", "",
                  "| metric | min | 5 % | median | 95 % | max | inf | n/a |", "|---|---|---|---|---|---|---|---|"]
        for name in metrics:
            column = done[name].astype(float)
            values = column[np.isfinite(column)]
            infinite, missing = int(np.isinf(column).sum()), int(column.isna().sum())
            q = values.quantile(list(QUANTILES)) if len(values) else [math.nan] * len(QUANTILES)
            lines.append(f"| {name} | " + " | ".join(_cell(float(v)) for v in q) + f" | {infinite} | {missing} |")
        lines.append("")
        lines += _ranked_sections(ranked(table, metric), [*keys, metric, "position_error_peak_m",
                                                          "saturated_fraction"], table.columns)
    if pareto is not None:
        x, y = pareto
        front = table[table["pareto"]].sort_values([x, y], kind="stable")
        lines += [f"## Pareto front of {x} and {y}", "",
                  f"{len(front)} of {finished} finished flights: none of the others is at least as small in both "
                  "(flights where either is NaN or infinite are left out).", ""]
        lines += _rows(front, list(dict.fromkeys([*keys, x, y]))) + [""]
    return "\n".join(lines)


def _ranked_sections(order: Any, wanted: list[str], available: Any) -> list[str]:
    """The finished flights best first: all of them when they are at most ``LISTED``, else the ``LISTED`` best
    and, apart from those, up to ``LISTED`` worst (worst first)."""
    columns = list(dict.fromkeys(c for c in wanted if c in available))
    if len(order) <= LISTED:
        return [f"## All {len(order)} finished flights, best first", ""] + _rows(order, columns) + [""]
    worst = order.iloc[LISTED:].tail(LISTED)[::-1]
    return ([f"## Best {LISTED}", ""] + _rows(order.head(LISTED), columns) + ["",
            f"## Worst {len(worst)}", ""] + _rows(worst, columns) + [""])


def _figure(height_in: float, width_in: float = ONE_COLUMN_IN) -> Figure:
    return Figure(figsize=(width_in, height_in), constrained_layout=True)


def heatmap_figure(table: Any, metric: str) -> Figure | None:
    grid = _scalar_keys(table, table.attrs.get("grid", []))
    if len(grid) < 2:
        return None
    x_key, y_key = grid[0], grid[1]
    values = table.assign(_m=table[metric].where(table["end_reason"] == FINISHED))
    mean = values.groupby([y_key, x_key])["_m"].mean().unstack(x_key)
    xs, ys = list(mean.columns), list(mean.index)
    fig = _figure(2.6)
    ax = fig.add_subplot()
    data = mean.to_numpy(dtype=float)
    shown = np.log10(data) if np.nanmin(data, initial=np.inf) > 0 and np.nanmax(data, initial=0) / max(
        np.nanmin(data, initial=np.inf), 1e-300) > 100 else data
    image = ax.imshow(shown, origin="lower", aspect="auto", cmap="viridis")
    bar = fig.colorbar(image, ax=ax)
    bar.set_label(("log10 " if shown is not data else "") + metric_label(metric))
    for (i, j), value in np.ndenumerate(data):
        if math.isnan(value):
            ax.text(j, i, "div", ha="center", va="center", color=OKABE_ITO["vermillion"], fontsize=7)
    ax.set_xticks(range(len(xs)), [f"{v:g}" for v in xs])
    ax.set_yticks(range(len(ys)), [f"{v:g}" for v in ys])
    ax.set_xlabel(key_label(x_key))
    ax.set_ylabel(key_label(y_key))
    return fig


def key_figure(table: Any, key: str, metric: str) -> Figure:
    fig = _figure(2.2)
    ax = fig.add_subplot()
    positions = table[key]
    if key not in _scalar_keys(table, [key]):  # list values: categories in the order they first appear
        categories = list(dict.fromkeys(map(repr, table[key])))
        positions = table[key].map(lambda value: categories.index(repr(value)))
        ax.set_xticks(range(len(categories)), [c.replace(" ", "") for c in categories],
                      rotation=30 if len(categories) > 3 else 0, ha="right" if len(categories) > 3 else "center")
    done = table["end_reason"] == FINISHED
    ax.plot(positions[done], table.loc[done, metric], ".", color=OKABE_ITO["blue"], ms=3,
            label=f"finished ({int(done.sum())})")
    failed = table["end_reason"] == DIVERGED
    if failed.any():
        top = np.nanmax(table.loc[done, metric].replace(np.inf, np.nan)) if done.any() else 1.0
        ax.plot(positions[failed], np.full(int(failed.sum()), top if np.isfinite(top) else 1.0), "x",
                color=OKABE_ITO["vermillion"], ms=4, label=f"diverged ({int(failed.sum())})")
    ax.set_xlabel(key_label(key))
    ax.set_ylabel(metric_label(metric))
    ax.grid(True)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=2)
    return fig


def ecdf_figure(table: Any, metric: str) -> Figure | None:
    if len(table) < 10:
        return None
    names = list(dict.fromkeys(["position_error_rms_m", "position_error_peak_m", metric]))
    fig = _figure(1.6 * len(names))
    done = table[table["end_reason"] == FINISHED]
    share = 1.0 - len(done) / len(table)
    for i, name in enumerate(names):
        ax = fig.add_subplot(len(names), 1, i + 1)
        values = np.sort(done[name].replace([np.inf, -np.inf], np.nan).dropna().to_numpy(dtype=float))
        if len(values):
            ax.step(values, np.arange(1, len(values) + 1) / len(table), where="post", color=OKABE_ITO["blue"],
                    label=f"finished; {share:.1%} diverged or invalid")
        ax.set_xlabel(metric_label(name))
        ax.set_ylabel("share of flights [-]")
        ax.set_ylim(0.0, 1.0)
        ax.grid(True)
        if i == 0:
            ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0))
    return fig


def pareto_figure(table: Any, x: str, y: str) -> Figure:
    fig = _figure(2.6)
    ax = fig.add_subplot()
    done = table[(table["end_reason"] == FINISHED)]
    shown = done[np.isfinite(done[x].to_numpy(dtype=float)) & np.isfinite(done[y].to_numpy(dtype=float))]
    ax.plot(shown[x], shown[y], ".", color=OKABE_ITO["blue"], ms=4, label=f"flights ({len(shown)})")
    front = shown[shown["pareto"]].sort_values([x, y], kind="stable")
    ax.plot(front[x], front[y], "o-", color=OKABE_ITO["vermillion"], ms=4, mfc="none", lw=0.8,
            label=f"Pareto front ({len(front)})")
    keys = table.attrs.get("keys", [])
    names = []  # the front's points numbered in the summary's order, their swept values in a box
    for number, (_, row) in enumerate(front.iterrows(), start=1):
        ax.annotate(str(number), (row[x], row[y]), xytext=(3, 2), textcoords="offset points", fontsize=6)
        names.append(f"{number}: " + ", ".join(f"{k.rsplit('.', 1)[-1]}={_cell(row[k])}" for k in keys))
    if names and keys:
        ax.text(0.98, 0.98, "\n".join(names[:LISTED]), transform=ax.transAxes, ha="right", va="top", fontsize=6,
                multialignment="left", bbox={"boxstyle": "round", "fc": "white", "ec": "0.8"})
    for values, scale in ((shown[x], ax.set_xscale), (shown[y], ax.set_yscale)):
        if len(values) and (values > 0).all() and values.max() / values.min() > 20:
            scale("log")
    ax.set_xlabel(metric_label(x))
    ax.set_ylabel(metric_label(y))
    ax.grid(True)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=2)
    return fig


def write_figures(table: Any, out: Path, metric: str, pareto: tuple[str, str] | None = None) -> list[Path]:
    """The figures of the module docstring that apply; returns their paths."""
    figures: dict[str, Figure | None] = {}
    with matplotlib.rc_context(RC):
        figures["heatmap"] = heatmap_figure(table, metric)
        for key in table.attrs.get("keys", []):
            figures[key] = key_figure(table, key, metric)
        figures["ecdf"] = ecdf_figure(table, metric)
        if pareto is not None:
            figures["pareto"] = pareto_figure(table, *pareto)
        paths = []
        for name, fig in figures.items():
            if fig is not None:
                path = out / f"{name}.png"
                fig.savefig(path, dpi=PNG_DPI, metadata={"Title": f"fsr sweep of {table.attrs.get('scenario')}: "
                                                                  f"{name}", "Software": "fsr-sweep"})
                paths.append(path)
    return paths
