"""Regenerate the figure gallery of docs/analysis.md (``docs/gallery/*.png``) from in-process flights.

    .venv/bin/python scripts/make_gallery.py                 # fly the four scenarios (about a minute or two)
    .venv/bin/python scripts/make_gallery.py --from runs/    # reuse runs/<scenario>.mcap where they exist

Each gallery image is one figure of ``fsr-analyze`` (same code, same style), saved at 150 dpi so that the
committed PNGs stay small (< 150 KB); ``fsr-analyze`` itself writes 300 dpi PNG and vector PDF/SVG.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import matplotlib

from fsr_bringup.analysis.figures import FIGURES, RC, FigureOptions, Run, figure_metadata
from fsr_bringup.analysis.load import load_flight
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_sim.config.scenario import load_scenario
from fsr_sim.contract import FINISHED

GALLERY_DPI = 150
MAX_BYTES = 150_000
# (scenario, figure, gallery file)
GALLERY = (
    ("ex3_estimation", "external_wrench", "ex3_wrench_estimate.png"),
    ("ex4_geometric", "pose", "ex4_pose.png"),
    ("ex5_voliro", "rotors", "ex5_rotors_tilts.png"),
    ("octo_ground_effect", "thrust_ratio", "octo_ground_effect.png"),
)


def recording_for(scenario: str, source: Path | None, work: Path) -> Path:
    """``source/<scenario>.mcap`` if it exists, else a fresh in-process flight in ``work``."""
    if source is not None and (source / f"{scenario}.mcap").is_file():
        return source / f"{scenario}.mcap"
    path = work / f"{scenario}.mcap"
    print(f"flying {scenario} in-process ...", flush=True)
    result = fly_in_process(load_scenario(scenario), recording=path)
    if result.end_reason != FINISHED:
        raise SystemExit(f"{scenario}: {result.reason}")
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--from", dest="source", type=Path, help="folder with <scenario>.mcap recordings to reuse")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "docs" / "gallery")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work, matplotlib.rc_context(RC):
        for scenario, name, file_name in GALLERY:
            runs = [Run.of(load_flight(recording_for(scenario, args.source, Path(work))))]
            drawn = FIGURES[name](runs, FigureOptions())
            if drawn.figure is None:
                raise SystemExit(f"{scenario}: figure {name} has nothing to show: {drawn.reason}")
            path = args.out / file_name
            drawn.figure.savefig(path, dpi=GALLERY_DPI, metadata=figure_metadata(name, runs, "png"))
            size = path.stat().st_size
            print(f"{path} ({size / 1000:.0f} kB)", flush=True)
            if size > MAX_BYTES:
                raise SystemExit(f"{path} is {size} bytes, more than {MAX_BYTES}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
