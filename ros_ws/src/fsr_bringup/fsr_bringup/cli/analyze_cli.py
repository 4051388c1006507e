"""``fsr-analyze RUN.mcap [RUN2.mcap ...] --out DIR``: metrics, figures and a Markdown summary of flights.

One recording: ``DIR/metrics.json``, ``DIR/summary.md`` and the figures (``--format png,pdf,svg``; PNG at
300 dpi, journal column widths, no titles unless ``--titles``). Several recordings are overlaid in the same
figures (a colour per run, ``--labels a,b``) with their metrics side by side in one table. A truncated
recording (writer killed) is analysed up to its last complete chunk and said so. ``--animate`` also writes
``DIR/animation.mp4`` (``--animate gif``: ``animation.gif``): the vehicle in 3D with its trail, rotor thrusts and
the true and estimated external force, at real time or ``--speed X``, ``--fps`` frames per second
(:mod:`fsr_bringup.analysis.animation`). Exit codes: ``fsr-analyze --help``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from fsr_bringup.analysis.figure_options import ANIMATION_FORMATS, AnimationOptions
from fsr_sim.cli.arguments import ArgumentParser, argument_type
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK

# fsr_estimation.estimator.metrics.SETTLING_DEFINITIONS (imported lazily)
SETTLING_CHOICES = ("standard", "report", "smoothed")
PROGRESS_EVERY_S = 0.25  # s between updates of the animation's progress line (as fsr-fly's)


def add_figure_arguments(parser: argparse.ArgumentParser) -> None:
    """Figure and estimator-metric options shared by fsr-analyze and fsr-fly."""
    parser.add_argument("--format", default="png", metavar="LIST",
                        help="figure formats, comma separated: png, pdf, svg (default png)")
    parser.add_argument("--width", choices=("auto", "one", "two"), default="auto",
                        help="figure width: one column (3.5 in), two columns (7.16 in) or each figure's own")
    parser.add_argument("--titles", action="store_true", help="put a title inside each figure (default: none)")
    parser.add_argument("--settling", choices=SETTLING_CHOICES, default="standard",
                        help="settling-time definition of the estimator metrics (default standard; report = the "
                             "definition of the report fsr started from, docs/model.md section 5, as "
                             "fsr-estimate --settling report; smoothed = standard through a 0.1 s low-pass, "
                             "for noisy flights)")
    parser.add_argument("--after", type=float, metavar="T",
                        help="estimator max error over t >= T [s] (default: the last 5 s)")


def figure_options(args: argparse.Namespace) -> object:
    """The :class:`fsr_bringup.analysis.figure_options.FigureOptions` of the parsed arguments (ValueError if bad)."""
    from fsr_bringup.analysis.figure_options import FORMATS, FigureOptions

    formats = tuple(dict.fromkeys(f.strip().lower() for f in args.format.split(",") if f.strip()))
    bad = [f for f in formats if f not in FORMATS]
    if not formats or bad:
        raise ValueError(f"--format: expected a comma-separated list of {', '.join(FORMATS)}; got '{args.format}'")
    return FigureOptions(formats=formats, width=args.width, titles=args.titles)


def positive_number(text: str) -> float:
    """A finite number > 0 (``--speed``, ``--fps``)."""
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"expected a number > 0; got '{text}'") from None
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"expected a number > 0; got '{text}'")
    return value


def add_animation_arguments(parser: argparse.ArgumentParser) -> None:
    defaults = AnimationOptions()
    parser.add_argument("--animate", nargs="?", const=defaults.format, choices=ANIMATION_FORMATS,
                        help="also write the flight as an animation in the output folder: animation.mp4 (default) "
                             "or animation.gif; after the recording: fsr-analyze RUN.mcap --animate [gif]")
    parser.add_argument("--speed", type=argument_type(positive_number), metavar="X",
                        help="animation speed: simulated seconds per second of video (default 1: real time; "
                             "2: twice as fast)")
    parser.add_argument("--fps", type=argument_type(positive_number), metavar="F",
                        help=f"animation frames per second (default {defaults.fps:g}; a GIF at most 50)")


def animation_options(args: argparse.Namespace) -> AnimationOptions | None:
    """The animation asked for (None: none), ValueError for --speed/--fps without --animate or several runs."""
    if args.animate is None:
        given = [name for name in ("speed", "fps") if getattr(args, name) is not None]
        if given:
            raise ValueError(f"--{given[0]}: only with --animate")
        return None
    if len(args.recordings) > 1:
        raise ValueError(f"--animate: draws one recording; got {len(args.recordings)}")
    defaults = AnimationOptions()
    return AnimationOptions(format=args.animate, fps=defaults.fps if args.fps is None else args.fps,
                            speed=defaults.speed if args.speed is None else args.speed)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-analyze", doc=__doc__, exit_codes={
        EXIT_OK: "done", EXIT_FAILURE: "the output cannot be written",
        EXIT_CONFIG_ERROR: "a file is missing, not MCAP or empty, or an argument is invalid (one line on stderr)",
        EXIT_INTERRUPTED: "interrupted (SIGINT/SIGTERM) while writing the animation: no animation file"})
    parser.add_argument("recordings", type=Path, nargs="+", metavar="RECORDING",
                        help="MCAP file(s) written by fsr-record / fsr-fly; several are overlaid")
    parser.add_argument("--out", type=Path, help="output folder (default: next to the first recording, "
                                                 "<name>_analysis)")
    parser.add_argument("--labels", help="comma-separated run labels for legends and table columns "
                                         "(default: the file names)")
    parser.add_argument("--namespace", help="vehicle namespace to analyse, e.g. /uav1 (default: detected)")
    parser.add_argument("--settle", type=float, default=None, help="start of the wrench RMS window [s] (default 5)")
    parser.add_argument("--no-figures", action="store_true", help="metrics and summary only")
    add_figure_arguments(parser)
    add_animation_arguments(parser)
    return parser.parse_args(animate_before_recording(sys.argv[1:] if argv is None else list(argv)))


def animate_before_recording(argv: list[str]) -> list[str]:
    """``--animate`` takes an optional format: written before a recording (``fsr-analyze --animate RUN.mcap``),
    argparse would take the recording for the format. A word after ``--animate`` that names a recording (ends in
    ``.mcap`` or is a file) is one: ``--animate`` then means its default format."""
    out = list(argv)
    for i, word in enumerate(out[:-1]):
        if word == "--":
            break
        following = out[i + 1]
        if word == "--animate" and (following.endswith(".mcap") or Path(following).is_file()):
            out[i] = f"--animate={AnimationOptions().format}"
    return out


def main(argv: list[str] | None = None) -> int:
    args = parse_args(sys.argv[1:] if argv is None else argv)
    # Imported here so that --help and argument errors stay fast (matplotlib, ROS message modules).
    from fsr_bringup.analysis.metrics import DEFAULT_SETTLE_S
    from fsr_bringup.analysis.run import analyze_recordings
    from fsr_sim.recording.reader import RecordingError, open_recording

    first = args.recordings[0]
    out = args.out or first.with_name(first.stem + "_analysis")
    labels = [label.strip() for label in args.labels.split(",")] if args.labels else None
    try:
        options = figure_options(args)
        animation = animation_options(args)
        if not args.no_figures:  # the figures' worker processes get ready while the recordings are read
            from fsr_bringup.analysis.figure_jobs import prepare_workers

            prepare_workers()
        recordings = []
        for path in args.recordings:
            recording = open_recording(path)
            if recording.truncated:
                print(f"fsr-analyze: {path}: recording is TRUNCATED (no summary/footer: the writer did not "
                      "close it); analysing up to its last complete chunk", file=sys.stderr, flush=True)
            recordings.append(recording)
        settle = DEFAULT_SETTLE_S if args.settle is None else args.settle
        result = analyze_recordings(recordings, out, labels, args.namespace, settle, not args.no_figures, options,
                                    args.settling, args.after)
    except (RecordingError, ValueError) as error:
        print(f"fsr-analyze: error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    except OSError as error:
        print(f"fsr-analyze: error: cannot write to {out}: {error.strerror or error}", file=sys.stderr)
        return EXIT_FAILURE
    print(result.summary)
    print(f"fsr-analyze: wrote {result.metrics_path}, {result.summary_path} and {len(result.figures)} figure files "
          f"in {out}")
    return EXIT_OK if animation is None else animate(result.flights[0], out, animation)


def animate(flight: object, out: Path, options: AnimationOptions) -> int:
    """Write the animation of ``flight`` (a RecordedFlight) with progress: in place on a terminal, else a line
    every 10 s (the Console of fsr-fly). SIGTERM stops it as Ctrl-C does, leaving no animation file."""
    import time

    from fsr_bringup.analysis.animation import write_animation
    from fsr_bringup.runner.flight import Console, Failure, long_run

    console = Console(prog="fsr-analyze")
    start = time.perf_counter()
    shown = [start]

    def progress(done: int, total: int) -> None:
        now = time.perf_counter()
        if now - shown[0] < PROGRESS_EVERY_S and done < total:
            return
        shown[0] = now
        console.count_progress("frames", done, total, now - start)

    failures = (Failure(KeyboardInterrupt, EXIT_INTERRUPTED,
                        lambda _: f"interrupted: no animation written (the analysis is in {out})"),
                Failure(ValueError, EXIT_CONFIG_ERROR, lambda error: f"error: {error}"),
                Failure(OSError, EXIT_FAILURE,
                        lambda error: f"error: cannot write the animation in {out}: {error.strerror or error}"))
    with long_run(console, failures) as run:
        written = write_animation(flight, out, options, progress)
    if run.exit_code is not None:
        return run.exit_code
    for note in written.notes:
        print(f"fsr-analyze: animation: {note}")
    pace = "real time" if options.speed == 1 else f"{options.speed:g}x real time"
    print(f"fsr-analyze: wrote {written.path} ({written.frames} frames at {options.fps:g} fps, {pace}) in "
          f"{time.perf_counter() - start:.1f} s")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
