"""One call that turns a recording into ``metrics.json``, ``summary.md`` and the figures (used by
``fsr-analyze`` and ``fsr-fly``)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fsr_bringup.analysis.figures import make_figures
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S, flight_metrics
from fsr_bringup.analysis.summary import markdown_summary
from fsr_sim.recording.reader import Recording, RecordingError, open_recording


@dataclass
class Analysis:
    metrics: dict[str, Any]
    summary: str
    figures: list[Path]
    metrics_path: Path
    summary_path: Path


def analyze_recording(
    recording: Recording | str | Path,
    out_dir: str | Path,
    namespace: str | None = None,
    settle_time: float = DEFAULT_SETTLE_S,
    figures: bool = True,
) -> Analysis:
    """Analyse ``recording`` into ``out_dir``; :class:`RecordingError` if it holds no message at all."""
    if not isinstance(recording, Recording):
        recording = open_recording(recording)
    if not any(recording.count(topic) for topic in recording.topics):
        state = "truncated and holds no complete chunk" if recording.truncated else "holds no messages"
        raise RecordingError(f"{recording.path}: recording {state}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    flight = load_flight(recording, namespace)
    written: list[Path] = []
    if figures:
        written, notes = make_figures(flight, out_dir)
        flight.notes.extend(notes)
    metrics = flight_metrics(flight, settle_time)
    metrics["figures"] = [path.name for path in written]
    summary = markdown_summary(metrics)
    metrics_path = out_dir / "metrics.json"
    summary_path = out_dir / "summary.md"
    metrics_path.write_text(json.dumps(metrics, indent=2) + "\n", encoding="utf-8")
    summary_path.write_text(summary, encoding="utf-8")
    return Analysis(metrics, summary, written, metrics_path, summary_path)
