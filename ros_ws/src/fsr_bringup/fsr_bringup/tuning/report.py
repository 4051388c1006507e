"""What ``fsr-tune`` writes from a :class:`~fsr_bringup.tuning.study.TuneResult`: ``best.yaml`` (the best
parameters as a scenario mapping: paste it into a scenario, or pass each key with ``--set``), ``trials.csv`` (a
row per trial), ``summary.md`` (the study, the best against the scenario's own parameters on the training and
the held-out conditions, the command that flies the best) and figures in the conventions of
:mod:`fsr_bringup.analysis.figures`: ``objective.png`` (every trial's objective and the running best) and
``parameters.png`` (the objective against each parameter).
"""

from __future__ import annotations

import math
import shlex
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
import yaml
from matplotlib.figure import Figure

from fsr_bringup.analysis.figures import OKABE_ITO, ONE_COLUMN_IN, PNG_DPI, RC
from fsr_bringup.sweeps.axes import key_label
from fsr_bringup.sweeps.report import metric_label
from fsr_bringup.tuning.study import TuneResult


def _plain(value: Any) -> Any:
    """Floats rounded to 6 significant digits (what a scenario file holds), lists item by item."""
    if isinstance(value, list):
        return [_plain(item) for item in value]
    return float(f"{value:.6g}")


def nested(values: dict[str, Any]) -> dict[str, Any]:
    """Dotted keys -> the nested mapping of a scenario (``controller.gains.k_p`` -> ``controller: gains: k_p``)."""
    out: dict[str, Any] = {}
    for key, value in values.items():
        node = out
        *parents, leaf = key.split(".")
        for part in parents:
            node = node.setdefault(part, {})
        node[leaf] = _plain(value)
    return out


def set_arguments(values: dict[str, Any]) -> str:
    """The ``--set KEY=VALUE`` arguments of ``values`` (shell-quoted)."""
    def text(value: Any) -> str:
        if isinstance(value, list):
            return "[" + ",".join(text(v) for v in value) + "]"
        if isinstance(value, bool):
            return "true" if value else "false"
        return f"{value:.6g}" if isinstance(value, float | int) else str(value)

    return " ".join(f"--set {shlex.quote(f'{key}={text(value)}')}" for key, value in values.items())


def fly_command(result: TuneResult) -> str:
    """``fsr-fly SCENARIO --set ...``: the best parameters in the conditions they were tuned for (the study's
    fixed values; a sampled key or a seed takes the scenario's own value)."""
    return f"fsr-fly {result.plan.scenario.name} {set_arguments({**result.plan.fixed, **result.best_values})}"


def write_best(result: TuneResult, path: Path) -> Path:
    header = (f"# fsr-tune: the best of {len(result.trials)} trials ({result.method}) of {result.plan.scenario.name}, "
              f"{result.plan.objective.label} = {result.best_objective:.6g} over {result.plan.seeds} seeds\n"
              f"# fly it: {fly_command(result)}\n")
    path.write_text(header + yaml.safe_dump(nested(result.best_values), sort_keys=False), encoding="utf-8")
    return path


def _number(value: float) -> str:
    return "n/a" if value is None or not math.isfinite(value) else f"{value:.4g}"


def summary_markdown(result: TuneResult, command: str | None = None) -> str:
    plan, objective = result.plan, result.plan.objective
    completed = int((result.trials["trial_state"] == "complete").sum())
    lines = [f"# Tuning of {plan.scenario.name}", ""]
    if command:
        lines += ["```", command, "```", ""]
    lines += [
        f"- method: {result.method} (optuna), {completed} trials completed"
        + (" (**interrupted**: `--resume` continues the study)" if result.interrupted else ""),
        f"- objective: {objective.label} over {plan.seeds} seeded conditions, minimised; a flight without a finite "
        f"value counts {objective.penalty:g}, a lost one {objective.penalty:g} x (2 - flown / duration)",
        f"- conditions: seed {plan.seed}; seeded keys: {', '.join(plan.seed_keys) or 'none'}; sampled: "
        f"{', '.join(f'{s.key} ({s.distribution} {s.first:g}, {s.second:g})' for s in plan.sample) or 'none'}"
        + (" - spread over the training conditions (quantiles, bounds included), drawn on the held-out ones"
           if plan.sample else ""),
        f"- {result.flights} flights in {result.wall_s:.1f} s", "",
        "## Best", "",
        "| key | value |", "|---|---|",
        *(f"| {key} | {_plain(value)} |" for key, value in result.best_values.items()), "",
        f"Fly it: `{fly_command(result)}` (or paste `best.yaml` into the scenario, with the conditions it was tuned "
        "for).", "",
        "## Against the scenario's own parameters", "",
        f"| parameters | conditions | {objective.label} | lost flights | mean position_error_rms_m |",
        "|---|---|---|---|---|",
        f"| the scenario's | training ({plan.seeds}) | {_number(result.baseline.objective)} | "
        f"{result.baseline.lost} | {_number(result.baseline.mean('position_error_rms_m'))} |",
        f"| best (trial {result.best_trial}) | training ({plan.seeds}) | {_number(result.best_objective)} | "
        f"{result.best_lost} | - |",
    ]
    for label, name in (("the scenario's", "scenario"), ("best", "best")):
        found = result.validation.get(name)
        if found is not None:
            lines.append(f"| {label} | held out ({plan.holdout}) | {_number(found.objective)} | {found.lost} | "
                         f"{_number(found.mean('position_error_rms_m'))} |")
    if not result.validation:
        lines.append("")
        lines.append("No held-out validation (`--holdout 0`, or interrupted).")
    return "\n".join(lines) + "\n"


def objective_figure(result: TuneResult) -> Figure:
    trials = result.trials
    fig = Figure(figsize=(ONE_COLUMN_IN, 2.4), constrained_layout=True)
    ax = fig.add_subplot()
    done = trials[trials["trial_state"] == "complete"]
    ax.plot(done.index, done["objective"], ".", color=OKABE_ITO["blue"], ms=3, label="trial")
    ax.step(trials.index, trials["best_so_far"], where="post", color=OKABE_ITO["vermillion"], lw=1.0,
            label="best so far")
    baseline = result.baseline.objective
    if math.isfinite(baseline):
        ax.axhline(baseline, color="0.4", ls="--", lw=0.8, label="scenario's parameters")
    values = done["objective"].to_numpy(dtype=float)
    if len(values) and np.all(values > 0) and values.max() / values.min() > 20:
        ax.set_yscale("log")
    ax.set_xlabel("trial [-]")
    ax.set_ylabel(metric_label(result.plan.objective.metric))
    ax.grid(True)
    ax.legend(loc="lower left", bbox_to_anchor=(0.0, 1.0), ncols=3)
    return fig


def parameters_figure(result: TuneResult) -> Figure:
    ranges = result.plan.ranges
    columns = 2 if len(ranges) > 1 else 1
    rows = math.ceil(len(ranges) / columns)
    fig = Figure(figsize=(ONE_COLUMN_IN * (1.0 if columns == 1 else 2.0), 1.9 * rows), constrained_layout=True)
    done = result.trials[result.trials["trial_state"] == "complete"]
    values = done["objective"].to_numpy(dtype=float)
    for index, r in enumerate(ranges):
        ax = fig.add_subplot(rows, columns, index + 1)
        ax.plot(done[r.name], values, ".", color=OKABE_ITO["blue"], ms=3)
        ax.plot([result.best_params[r.name]], [result.best_objective], "*", color=OKABE_ITO["vermillion"], ms=7)
        if r.log:
            ax.set_xscale("log")
        if len(values) and np.all(values > 0) and values.max() / values.min() > 20:
            ax.set_yscale("log")
        ax.set_xlabel(key_label(r.name))
        ax.set_ylabel(metric_label(result.plan.objective.metric))
        ax.grid(True)
    return fig


def write_outputs(result: TuneResult, out: Path, command: str | None = None) -> list[Path]:
    """Every file of the module docstring into ``out``; returns their paths."""
    written = [write_best(result, out / "best.yaml")]
    result.trials.to_csv(out / "trials.csv")
    (out / "summary.md").write_text(summary_markdown(result, command), encoding="utf-8")
    written += [out / "trials.csv", out / "summary.md"]
    with matplotlib.rc_context(RC):
        for name, fig in (("objective", objective_figure(result)), ("parameters", parameters_figure(result))):
            path = out / f"{name}.png"
            fig.savefig(path, dpi=PNG_DPI, metadata={"Title": f"fsr-tune of {result.plan.scenario.name}: {name}",
                                                     "Software": "fsr-tune"})
            written.append(path)
    return written
