"""``fsr-tune SCENARIO --param KEY=[log:]LO:HI ...``: a scenario's parameters found by optimisation over many
compiled flights, each candidate flown over seeded conditions, locally or on a Dask cluster.

    fsr-tune step_disturbance --param controller.gains.k_p=log:1:60,same,log:5:200 --seeds 10 --budget 400 \\
        --set sensors.preset=onboard --set plant.rotor_time_constant=0.03 --sample plant.mass=uniform:0.96:1.44 \\
        --objective position_error_rms_m:mean --out runs/tune_step
    fsr-tune step_disturbance --param ... --out runs/tune_step --resume      # continue an interrupted study

Each trial is one candidate flown over ``--seeds`` conditions (the seed drives the sensor noise and the turbulence;
each ``--sample``d key is spread over its distribution on them, its bounds included, and drawn on the held-out
ones); its objective is ``METRIC[:STAT]`` (mean, median, q90 or max over the seeds) of a sweep
metric, a lost flight counting ``--penalty``. optuna's CMA-ES, TPE or random search (``--method``) proposes the
candidates; the study is kept in ``OUT/study.db``, so Ctrl-C keeps what was flown and ``--resume`` continues it.
Writes ``OUT/best.yaml`` (the best parameters as a scenario mapping), ``trials.csv``, ``summary.md`` (the best
against the scenario's own parameters, also on ``--holdout`` conditions never seen while tuning) and figures.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from fsr_bringup.runner.flight import Console, Failure, long_run
from fsr_bringup.sweeps.axes import parse_sample
from fsr_bringup.tuning.objective import DEFAULT_PENALTY, STATISTICS
from fsr_bringup.tuning.space import TuneError, parse_param
from fsr_bringup.tuning.study import DEFAULT_BUDGET, DEFAULT_HOLDOUT, DEFAULT_SEEDS, METHODS
from fsr_sim.cli.arguments import ArgumentParser, argument_type, command_line
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_OK


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-tune", doc=__doc__, exit_codes={
        EXIT_OK: "the study reached its budget (the best, the summary and the figures written)",
        EXIT_FAILURE: "the study failed (a worker or the cluster; named in the message)",
        EXIT_CONFIG_ERROR: "invalid scenario, key, range, metric or study (named in the message); nothing flown",
        EXIT_INTERRUPTED: "interrupted (Ctrl-C / SIGTERM): the study is kept (--resume continues it), the best so "
                          "far written"})
    parser.add_argument("scenario", help=f"built-in scenario ({', '.join(builtin_names('scenarios'))}) or a YAML path")
    parser.add_argument("--param", action="append", default=[], metavar="KEY=[log:]LO:HI",
                        type=argument_type(parse_param),
                        help="a tuned key and its range (repeatable); a list-valued key takes one range for every "
                             "entry or one item per entry (a range, 'same' or a number)")
    parser.add_argument("--seeds", type=int, default=DEFAULT_SEEDS,
                        help=f"seeded conditions per candidate (default {DEFAULT_SEEDS})")
    parser.add_argument("--sample", action="append", default=[], type=argument_type(parse_sample),
                        metavar="KEY=uniform:LO:HI|normal:MEAN:STD|loguniform:LO:HI",
                        help="a key per condition (repeatable), e.g. a mass error: spread over its distribution on the "
                             "training conditions (its quantiles, bounds included), drawn on the held-out ones")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="a value every flight has, as fsr-fly --set (repeatable)")
    parser.add_argument("--duration", type=float, help="override the scenario's duration [s]")
    parser.add_argument("--objective", default="position_error_rms_m", metavar="METRIC[:STAT]",
                        help=f"the sweep metric to minimise and its statistic over the seeds ({', '.join(STATISTICS)};"
                             " default position_error_rms_m:mean)")
    parser.add_argument("--penalty", type=float, default=DEFAULT_PENALTY,
                        help=f"what a flight without a finite value counts, in the metric's unit; a lost one counts "
                             f"up to twice it, less the later it was lost (default {DEFAULT_PENALTY:g})")
    parser.add_argument("--budget", type=int, default=DEFAULT_BUDGET, help=f"trials (default {DEFAULT_BUDGET})")
    parser.add_argument("--method", choices=METHODS, default="cma", help="optuna sampler (default cma)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the sampler and the conditions (default 0)")
    parser.add_argument("--holdout", type=int, default=DEFAULT_HOLDOUT,
                        help=f"held-out conditions for the final comparison (default {DEFAULT_HOLDOUT}; 0: none)")
    parser.add_argument("--workers", type=int, help="local worker processes (default: every core)")
    parser.add_argument("--cluster", metavar="ADDRESS", help="run on a Dask cluster (tcp://HOST:PORT of its scheduler)")
    parser.add_argument("--out", type=Path, help="output folder (default runs/tune_<scenario>_<time>)")
    parser.add_argument("--resume", action="store_true", help="continue the study in --out")
    args = parser.parse_args(argv)
    if not args.param:
        parser.error("give at least one --param KEY=[log:]LO:HI")
    if args.resume and args.out is None:
        parser.error("--resume needs the --out of the study to continue")
    if args.workers is not None and args.workers < 1:
        parser.error(f"argument --workers: must be >= 1, got {args.workers}")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    from fsr_bringup.cli.sweep_cli import _overrides, default_output, remove_if_empty, usable_output
    from fsr_bringup.tuning.report import write_outputs
    from fsr_bringup.tuning.study import tune

    console = Console(prog="fsr-tune")
    created: list[Path] = []
    failures = (Failure((TuneError, ConfigError, ValueError), EXIT_CONFIG_ERROR),
                Failure(KeyboardInterrupt, EXIT_INTERRUPTED, lambda _: f"interrupted before a trial completed: the "
                        f"study in {out} continues with --resume", clean_up=False),
                Failure((OSError, RuntimeError), EXIT_FAILURE, lambda error: f"the study failed: {error}",
                        clean_up=False))

    def progress(done: int, total: int, wall: float, best: float) -> None:
        console.count_progress("trials", done, total, wall)

    with long_run(console, failures, lambda: remove_if_empty(created)) as run:
        fixed = _overrides(args.overrides)
        out = args.out or default_output(args.scenario, "tune")
        created = usable_output(out)
        result = tune(args.scenario, [f"{key}={','.join(items)}" for key, items in args.param], seeds=args.seeds,
                      objective=args.objective, budget=args.budget, method=args.method,
                      sample={s.key: (s.distribution, s.first, s.second) for s in args.sample}, set=fixed,
                      duration=args.duration, holdout=args.holdout, seed=args.seed, penalty=args.penalty,
                      workers=args.workers, cluster=args.cluster, out=out, resume=args.resume, progress=progress)
    if run.exit_code is not None:
        return run.exit_code
    written = write_outputs(result, out, command_line("fsr-tune", argv))
    plan = result.plan
    print(f"fsr-tune: {len(result.trials)} trials of {plan.scenario.name} ({result.method}) in {result.wall_s:.1f} s, "
          f"{result.flights} flights: best {plan.objective.label} = {result.best_objective:.4g} (trial "
          f"{result.best_trial}; the scenario's own: {result.baseline.objective:.4g})")
    for name, found in result.validation.items():
        print(f"fsr-tune: held out ({plan.holdout} conditions), {'best' if name == 'best' else 'scenario'}: "
              f"{plan.objective.label} = {found.objective:.4g}, {found.lost} lost")
    for path in written:
        print(f"fsr-tune: wrote {path}")
    if result.interrupted:
        print(f"fsr-tune: interrupted: the study in {out} continues with --resume", file=sys.stderr)
        return EXIT_INTERRUPTED
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
