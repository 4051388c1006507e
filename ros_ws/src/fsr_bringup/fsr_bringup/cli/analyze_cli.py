"""``fsr-analyze RUN.mcap --out DIR``: metrics, figures and a Markdown summary of a recorded flight.

Writes ``DIR/metrics.json``, ``DIR/summary.md`` and ``DIR/*.png`` and prints the summary. A truncated
recording (writer killed) is analysed up to its last complete chunk and said so. Exit codes: 0 done,
2 the file is missing, not MCAP or empty (one line on stderr), 1 the output cannot be written.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fsr_sim.cli.arguments import ArgumentParser

EXIT_OK = 0
EXIT_WRITE_ERROR = 1
EXIT_BAD_INPUT = 2


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-analyze", description=__doc__.split("\n")[0])
    parser.add_argument("recording", type=Path, help="MCAP file written by fsr-record / fsr-fly")
    parser.add_argument("--out", type=Path, help="output folder (default: next to the recording, <name>_analysis)")
    parser.add_argument("--namespace", help="vehicle namespace to analyse, e.g. /uav1 (default: detected)")
    parser.add_argument("--settle", type=float, default=None, help="start of the wrench RMS window [s] (default 5)")
    parser.add_argument("--no-figures", action="store_true", help="metrics and summary only")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    # Imported here so that --help and argument errors stay fast (matplotlib, ROS message modules).
    from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S
    from fsr_bringup.analysis.run import analyze_recording
    from fsr_sim.recording.reader import RecordingError, open_recording

    out = args.out or args.recording.with_name(args.recording.stem + "_analysis")
    try:
        recording = open_recording(args.recording)
        if recording.truncated:
            print(f"fsr-analyze: {args.recording}: recording is TRUNCATED (no summary/footer: the writer did not "
                  "close it); analysing up to its last complete chunk", file=sys.stderr, flush=True)
        settle = DEFAULT_SETTLE_S if args.settle is None else args.settle
        result = analyze_recording(recording, out, args.namespace, settle, figures=not args.no_figures)
    except RecordingError as error:
        print(f"fsr-analyze: error: {error}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as error:
        print(f"fsr-analyze: error: cannot write to {out}: {error.strerror or error}", file=sys.stderr)
        return EXIT_WRITE_ERROR
    print(result.summary)
    print(f"fsr-analyze: wrote {result.metrics_path}, {result.summary_path} and {len(result.figures)} figures "
          f"in {out}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
