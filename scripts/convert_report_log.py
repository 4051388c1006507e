#!/usr/bin/env python3
"""Convert the report's MATLAB flight log to the shipped example recording.

    .venv/bin/python scripts/convert_report_log.py [MAT] [OUT]

defaults: ../shared/data/ws_homework_3_2025.mat -> examples/ex3_flight_log.mcap. The MCAP holds only
``/odom`` and ``/wrench_cmd`` (zstd chunks); ``fsr-estimate`` reads it like any fsr recording.
"""

from __future__ import annotations

import sys
from pathlib import Path

from fsr_estimation.io.flight_log import FlightLogError, load_mat, write_mcap
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_OK

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_MAT = ROOT.parent / "shared" / "data" / "ws_homework_3_2025.mat"
DEFAULT_OUT = ROOT / "examples" / "ex3_flight_log.mcap"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) > 2 or any(a in ("-h", "--help") for a in args):
        print(__doc__)
        return EXIT_OK if args and args[0] in ("-h", "--help") else EXIT_CONFIG_ERROR
    mat = Path(args[0]) if args else DEFAULT_MAT
    out = Path(args[1]) if len(args) > 1 else DEFAULT_OUT
    try:
        log = load_mat(mat)
    except FlightLogError as error:
        print(f"error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    out.parent.mkdir(parents=True, exist_ok=True)
    write_mcap(log, out, metadata={"fsr_flight_log_origin": {"file": mat.name, "report": "hw3 exercise 3"}})
    print(f"wrote {out} ({len(log)} samples, {out.stat().st_size / 1e6:.2f} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
