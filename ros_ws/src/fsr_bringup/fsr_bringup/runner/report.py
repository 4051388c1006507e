"""The end of a run: analyse the recording (figures, ``metrics.json``, ``summary.md``) and print the summary."""

from __future__ import annotations

import sys
from pathlib import Path

from fsr_bringup.analysis.figure_options import FigureOptions
from fsr_bringup.analysis.load import RecordedFlight
from fsr_bringup.analysis.run import analyze_recording
from fsr_sim.recording.reader import Recording, RecordingError, open_recording


def analyse_and_summarise(recording: Recording | Path | RecordedFlight, run_dir: Path, namespaces: list[str],
                          options: FigureOptions | None = None, settling: str = "standard",
                          after: float | None = None) -> bool:
    """Analyse each vehicle of the recording (a path, or the recording already read; or the one flight
    already in memory, :attr:`fsr_bringup.runner.in_process_flight.FlightRun.trace`) into ``run_dir``
    (``run_dir/<ns>`` for a fleet); False on error.

    ``options``: figure formats and sizes; ``settling`` / ``after``: the estimator metrics' settling-time
    definition and max-error window (:func:`fsr_bringup.analysis.metrics.flight_metrics`)."""
    try:
        if not isinstance(recording, Recording | RecordedFlight):
            recording = open_recording(recording)
    except RecordingError as error:
        print(f"fsr-fly: cannot analyse the recording: {error}", file=sys.stderr)
        return False
    if recording.truncated:
        print(f"fsr-fly: WARNING: {recording.path} is truncated (the recorder did not close it); "
              "analysing up to its last complete chunk", file=sys.stderr)
    ok = True
    for namespace in namespaces:
        out_dir = run_dir / namespace.strip("/") if namespace else run_dir
        try:
            analysis = analyze_recording(recording, out_dir, namespace or None, options=options,
                                         settling=settling, after=after)
        except (RecordingError, OSError) as error:
            print(f"fsr-fly: analysis of {namespace or 'the flight'} failed: {error}", file=sys.stderr)
            ok = False
            continue
        print(analysis.summary, flush=True)
        print(f"fsr-fly: figures and metrics in {out_dir} ({len(analysis.figures)} figures, "
              f"{analysis.metrics_path.name}, {analysis.summary_path.name})", flush=True)
    return ok
