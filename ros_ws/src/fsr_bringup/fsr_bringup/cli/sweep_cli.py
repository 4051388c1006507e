"""``fsr-sweep SCENARIO``: many closed-loop flights of a scenario (a grid of values and/or a seeded sample), in
one table, with a summary and figures.

    fsr-sweep ex4_geometric --sample plant.mass=uniform:1.0:1.5 --n 1000 --duration 5 --out runs/mass
    fsr-sweep ex3_estimation --grid estimator.c0=1,10,100 --grid estimator.r=1,2,3 --out runs/observer
    fsr-sweep ex4_geometric --grid 'controller.gains.k_p=[7,7,40],[12,12,55]' --out runs/gains
    fsr-sweep ex4_geometric --sample plant.mass=normal:1.2:0.1 --n 200 --cluster tcp://10.0.0.1:8786
    fsr-sweep ex3_estimation_noisy --grid estimator.c0=1,5,10,25,50,100 --grid estimator.r=1,2,3,4,5 \
        --pareto estimate_settling_s,estimate_force_rms_N --out runs/observer_noise

Keys are the dotted keys of ``fsr-fly --set`` (numbers only); grid values are YAML flow values (a list-valued key
takes lists), a sample is ``uniform:LO:HI``, ``normal:MEAN:STD`` or ``loguniform:LO:HI`` drawn ``--n`` times
with ``--seed``. Writes ``DIR/results.csv`` (and ``results.parquet`` with pyarrow), ``DIR/summary.md`` and
figures (``heatmap.png``, one per swept key, ``ecdf.png``); ``--pareto X,Y`` marks the flights on the Pareto
front of two metrics to make small together (a ``pareto`` column, a section of the summary, ``pareto.png``);
``--record-best K`` flies the K best and the K worst flights again and records them as MCAP (``best_1.mcap``
...). Flights run over every core (``--workers``) or on a Dask cluster (``--cluster``; start one with ``dask
scheduler`` and ``dask worker tcp://HOST:8786`` on each machine, fsr installed on every one). A flight that
diverges is a row with its reason; the sweep goes on.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from fsr_bringup.runner.flight import Console, Failure, long_run
from fsr_bringup.sweeps.axes import SweepError, parse_grid, parse_sample
from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M, RANKABLE_METRICS
from fsr_bringup.sweeps.pareto import parse_pareto
from fsr_sim.cli.arguments import ArgumentParser, argument_type, command_line
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK

DEFAULT_METRIC = "position_error_rms_m"
RANKABLE = list(RANKABLE_METRICS)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-sweep", doc=__doc__, exit_codes={
        EXIT_OK: "every flight was flown (diverged flights are rows of the table)",
        EXIT_FAILURE: "the sweep failed (a worker or the cluster; named in the message)",
        EXIT_CONFIG_ERROR: "invalid scenario, key or distribution (named in the message)",
        EXIT_INTERRUPTED: "interrupted (Ctrl-C / SIGTERM): nothing written"})
    parser.add_argument("scenario", help=f"built-in scenario ({', '.join(builtin_names('scenarios'))}) or a YAML path")
    parser.add_argument("--grid", action="append", default=[], metavar="KEY=V1,V2,...", type=argument_type(parse_grid),
                        help="a grid axis: a dotted key and its values, YAML flow values (repeatable: the product)")
    parser.add_argument("--sample", action="append", default=[], type=argument_type(parse_sample),
                        metavar="KEY=uniform:LO:HI|normal:MEAN:STD|loguniform:LO:HI",
                        help="a sampled key and its distribution (repeatable), drawn --n times")
    parser.add_argument("--n", type=int, help="flights drawn for --sample (per grid point)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sample (default 0)")
    parser.add_argument("--duration", type=float, help="override the scenario's duration [s]")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="a value every flight has, as fsr-fly --set (repeatable)")
    parser.add_argument("--out", type=Path, help="output folder (default runs/sweep_<scenario>_<time>)")
    parser.add_argument("--workers", type=int, help="local worker processes (default: every core)")
    parser.add_argument("--cluster", metavar="ADDRESS", help="run on a Dask cluster (tcp://HOST:PORT of its scheduler)")
    parser.add_argument("--metric", default=DEFAULT_METRIC, choices=RANKABLE,
                        help=f"what ranks the flights (default {DEFAULT_METRIC})")
    parser.add_argument("--pareto", metavar="X,Y", type=argument_type(lambda text: parse_pareto(text, RANKABLE)),
                        help="two metrics to make small together: the flights on their Pareto front are marked "
                             "(a 'pareto' column, a section of summary.md and pareto.png)")
    parser.add_argument("--band", type=float, default=DEFAULT_BAND_M,
                        help=f"position band of settling_time_s [m] (default {DEFAULT_BAND_M:g})")
    parser.add_argument("--record-best", type=int, default=0, metavar="K",
                        help="record the K best and K worst flights as MCAP in the output folder")
    args = parser.parse_args(argv)
    if args.n is not None and args.n < 1:
        parser.error(f"argument --n: must be >= 1, got {args.n}")
    if args.workers is not None and args.workers < 1:
        parser.error(f"argument --workers: must be >= 1, got {args.workers}")
    if args.band <= 0:
        parser.error(f"argument --band: must be > 0, got {args.band:g}")
    return args


def _overrides(items: list[str]) -> dict[str, object]:
    import yaml

    from fsr_sim.config.validation import yaml_value

    values = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise SweepError(f"--set: expected KEY=VALUE, got '{item}'")
        try:
            values[key.strip()] = yaml_value(value)
        except yaml.YAMLError:
            raise SweepError(f"--set {key.strip()}: '{value}' is not a YAML value") from None
    return values


def record_extremes(table, scenario: str, fixed: dict, duration: float | None, count: int, metric: str,  # noqa: ANN001
                    out: Path) -> list[Path]:
    """Fly the ``count`` best and worst finished flights again, recorded (``best_1.mcap`` is the best)."""
    from fsr_bringup.api import simulate
    from fsr_bringup.sweeps.report import ranked

    order = ranked(table, metric)
    keys = table.attrs["keys"]
    picks = [("best", i + 1, n) for i, n in enumerate(order.index[:count])]
    picks += [("worst", i + 1, n) for i, n in enumerate(order.index[::-1][:count])]
    paths = []
    for label, rank, number in picks:
        values = {**fixed, **{k: table.at[number, k] for k in keys}}
        values = {k: (v.item() if hasattr(v, "item") else v) for k, v in values.items()}
        path = out / f"{label}_{rank}.mcap"
        simulate(scenario, set=values, duration=duration, record=path)
        paths.append(path)
    return paths


def default_output(scenario: str, kind: str = "sweep") -> Path:
    """``runs/<kind>_<scenario name>_<time>``."""
    from fsr_sim.config.scenario import load_scenario

    return Path("runs") / f"{kind}_{load_scenario(scenario).name}_{time.strftime('%Y%m%d-%H%M%S')}"


def usable_output(out: Path) -> list[Path]:
    """Create the output folder ``out`` (and its parents) and check it can be written, before any flight is flown
    (SweepError naming the folder otherwise). Returns the folders it created, deepest first."""
    created = [folder for folder in (out, *out.parents) if not folder.exists()]
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".fsr-sweep-write-test"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as error:
        remove_if_empty(created)
        raise SweepError(f"--out: cannot write to '{out}': {error.strerror or error}") from None
    return created


def remove_if_empty(folders: list[Path]) -> None:
    """Remove the folders :func:`usable_output` created where nothing was written into them."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:
            return


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from fsr_bringup.sweeps.report import summary_markdown, write_figures, write_tables
    from fsr_bringup.sweeps.run import sweep

    console = Console(prog="fsr-sweep")
    start = time.perf_counter()

    def progress(done: int, total: int, wall: float) -> None:
        console.count_progress("flights", done, total, wall)

    created: list[Path] = []
    failures = (Failure((SweepError, ConfigError), EXIT_CONFIG_ERROR),
                Failure(KeyboardInterrupt, EXIT_INTERRUPTED, lambda _: "interrupted: nothing written"),
                Failure((OSError, RuntimeError), EXIT_FAILURE, lambda error: f"the sweep failed: {error}"))
    with long_run(console, failures, lambda: remove_if_empty(created)) as run:
        fixed = _overrides(args.overrides)
        out = args.out or default_output(args.scenario)
        created = usable_output(out)
        table = sweep(args.scenario, grid={a.key: list(a.values) for a in args.grid},
                      sample={s.key: (s.distribution, s.first, s.second) for s in args.sample}, n=args.n,
                      seed=args.seed, duration=args.duration, workers=args.workers, cluster=args.cluster,
                      set=fixed, band=args.band, progress=progress, pareto=args.pareto)
    if run.exit_code is not None:
        return run.exit_code
    command = command_line("fsr-sweep", argv)
    written = write_tables(table, out)
    (out / "summary.md").write_text(summary_markdown(table, args.metric, command, args.pareto), encoding="utf-8")
    written += [out / "summary.md", *write_figures(table, out, args.metric, args.pareto)]
    if args.record_best:
        written += record_extremes(table, args.scenario, fixed, args.duration, args.record_best, args.metric, out)
    a = table.attrs
    counts = table["end_reason"].value_counts().to_dict()
    print(f"fsr-sweep: {a['flights']} flights of {a['scenario']} ("
          + ", ".join(f"{v} {k}" for k, v in sorted(counts.items())) + f") in {time.perf_counter() - start:.2f} s: "
          f"{a['vehicle_steps'] / a['wall_s']:.3g} vehicle-steps/s on {a['workers']} worker(s)")
    for path in written:
        print(f"fsr-sweep: wrote {path}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
