"""One call that turns recordings into ``metrics.json``, ``summary.md`` and the figures (used by
``fsr-analyze`` and ``fsr-fly``): one run, or several overlaid in the same figures with their metrics side
by side."""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from fsr_bringup.analysis.figure_jobs import Run, start_figures
from fsr_bringup.analysis.figure_options import FigureOptions
from fsr_bringup.analysis.load import RecordedFlight, load_flight
from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S, flight_metrics
from fsr_bringup.analysis.summary import comparison_summary, markdown_summary
from fsr_sim.recording.reader import Recording, RecordingError, open_recording


@dataclass
class Analysis:
    metrics: dict[str, Any]
    summary: str
    figures: list[Path]
    metrics_path: Path
    summary_path: Path
    flights: list[RecordedFlight] = field(default_factory=list)  # the recordings as loaded, in order


def _opened(recording: Recording | str | Path) -> Recording:
    """The recording, refused (:class:`RecordingError`) when it holds no message at all."""
    if not isinstance(recording, Recording):
        recording = open_recording(recording)
    if not any(recording.count(topic) for topic in recording.topics):
        state = "truncated and holds no complete chunk" if recording.truncated else "holds no messages"
        raise RecordingError(f"{recording.path}: recording {state}")
    return recording


def _stem(flight: RecordedFlight) -> str:
    """The file stem of the flight's recording (its scenario's name where it has none)."""
    path = getattr(flight.recording, "path", None)
    return path.stem if path is not None else flight.scenario_name


RUN_STAMP = re.compile(r"_\d{8}-\d{6}$")  # fsr-fly's default run name: <scenario>_<YYYYmmdd-HHMMSS>


def run_labels(stems: list[str]) -> list[str]:
    """Legend labels of recordings named ``stems``: without ``fsr-fly``'s time stamp (``ex4_geometric``), unless
    that makes two of them the same (then as they are)."""
    short = [RUN_STAMP.sub("", stem) or stem for stem in stems]
    return short if len(set(short)) == len(short) else list(stems)


def analyze_recordings(
    recordings: list[Recording | str | Path | RecordedFlight],
    out_dir: str | Path,
    labels: list[str] | None = None,
    namespace: str | None = None,
    settle_time: float = DEFAULT_SETTLE_S,
    figures: bool = True,
    options: FigureOptions | None = None,
    settling: str = "standard",
    after: float | None = None,
) -> Analysis:
    """Analyse one or several recordings (or flights already loaded, such as one flown in this process:
    :attr:`fsr_bringup.runner.in_process_flight.FlightRun.trace`) into ``out_dir``.

    One recording: ``metrics.json`` is its metrics (:func:`fsr_bringup.analysis.metrics.flight_metrics`).
    Several: every figure overlays them (a colour per run, ``labels`` in the legends, default the file
    stems without the time stamp ``fsr-fly`` gives them, :func:`run_labels`), ``metrics.json`` is
    ``{"labels": [...], "runs": {label: metrics}}`` and ``summary.md`` one table with a column per run.
    :class:`RecordingError` for a recording without messages; ValueError for labels
    that do not match the recordings one to one.
    """
    flights = [r if isinstance(r, RecordedFlight) else load_flight(_opened(r), namespace) for r in recordings]
    if labels is None:
        labels = run_labels([_stem(flight) for flight in flights])
    if len(labels) != len(flights) or len(set(labels)) != len(labels):
        raise ValueError(f"--labels: need {len(flights)} distinct labels, one per recording; got {labels}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    runs = [Run.of(flight, label) for flight, label in zip(flights, labels, strict=True)]
    drawing = start_figures(runs, out_dir, options) if figures else None  # drawn while the metrics are computed
    per_run = [flight_metrics(flight, settle_time, settling, after) for flight in flights]
    written, notes = drawing.result() if drawing is not None else ([], [])
    if len(flights) == 1:  # the figures' notes after the recording's own, as if known before the metrics
        known = len(flights[0].notes)
        per_run[0]["notes"][known:known] = notes
    names = sorted({path.name for path in written})
    if len(flights) == 1:
        metrics = per_run[0]
        metrics["figures"] = names
        summary = markdown_summary(metrics)
    else:
        metrics = {"labels": labels, "runs": dict(zip(labels, per_run, strict=True)), "figures": names,
                   "notes": notes}
        summary = comparison_summary(labels, per_run, notes)
    metrics_path = out_dir / "metrics.json"
    summary_path = out_dir / "summary.md"
    metrics_path.write_text(json.dumps(metrics, indent=2) + "\n", encoding="utf-8")
    summary_path.write_text(summary, encoding="utf-8")
    return Analysis(metrics, summary, written, metrics_path, summary_path, flights)


def analyze_recording(recording: Recording | str | Path | RecordedFlight, out_dir: str | Path,
                      namespace: str | None = None, **keywords: Any) -> Analysis:
    """Analyse one recording into ``out_dir``: :func:`analyze_recordings` with one run (the same keywords:
    ``settle_time``, ``figures``, ``options``, ``settling``, ``after``)."""
    return analyze_recordings([recording], out_dir, None, namespace, **keywords)
