"""``tune()``: a scenario's parameters found by optimisation, each candidate flown over seeded conditions by the
sweep's compiled, measured flights (:mod:`fsr_bringup.sweeps.batch`), locally or on a Dask cluster.

    from fsr_bringup import tune
    result = tune("step_disturbance", params={"controller.gains.k_p": "log:1:100"}, seeds=10, budget=200)
    result.best_values, result.trials, result.validation

The optimiser is optuna's (CMA-ES, TPE or random search, :data:`METHODS`), its study kept in ``OUT/study.db``
(SQLite): a study interrupted (Ctrl-C, SIGTERM, a lost machine) is continued by ``resume=True`` - the trials it
completed are kept, none is flown again; one in flight when it stopped is marked failed and asked anew.

Trials are asked :data:`GENERATION` at a time, their flights (each trial: ``seeds`` conditions,
:mod:`fsr_bringup.tuning.conditions`) flown in parallel - in batches over the local worker processes, or as
Dask tasks (a worker lost mid-task has its batch flown again by the scheduler) - and told back in trial order, so a
study is the same study wherever and in whatever order its flights ran: one seed gives the same trials and the same
best on one core, on two, or on a cluster. A diverged flight is a penalty (:mod:`fsr_bringup.tuning.objective`),
never an error; a trial's lost flight is not flown again for its metrics (the penalty needs none of them:
:func:`fsr_bringup.sweeps.batch.fly_one`'s ``metric``). The best candidate and the scenario's own parameters
are then flown on ``holdout`` conditions the optimiser never saw (:attr:`TuneResult.validation`).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor
from contextlib import contextmanager
from dataclasses import dataclass, field
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from fsr_bringup.api import fixed_values, load_checked
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_bringup.sweeps.axes import SampledKey, flight_scenario, sampled_key
from fsr_bringup.sweeps.batch import Batch, BatchResult, fly_batch
from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M
from fsr_bringup.sweeps.run import cluster_client, cluster_threads
from fsr_bringup.tuning.conditions import condition_values, scenario_seed_keys
from fsr_bringup.tuning.objective import DEFAULT_PENALTY, Objective, lost, parse_objective
from fsr_bringup.tuning.space import Range, TunedKey, TuneError, key_size, parse_param, tuned_key
from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError

METHODS = ("cma", "tpe", "random")
GENERATION = 8  # trials asked at once and told in order (fixed: the study does not depend on the workers)
DEFAULT_SEEDS = 10
DEFAULT_HOLDOUT = 50
DEFAULT_BUDGET = 200
STUDY_FILE = "study.db"
BATCHES_PER_WORKER = 8  # per generation, at least (flights that are lost early make batches uneven)
STRUCTURAL = ("unknown key", "out of range", "cannot hold", "has no item")  # a key the scenario cannot take


@dataclass
class TunePlan:
    """A checked tuning: the scenario (fixed values applied), the tuned keys, the conditions and the objective."""

    scenario: Scenario
    keys: list[TunedKey]
    objective: Objective
    seeds: int
    holdout: int
    seed: int
    seed_keys: list[str]
    sample: list[SampledKey]
    band: float = DEFAULT_BAND_M
    fixed: dict[str, Any] = field(default_factory=dict)  # the --set values (and the duration) every flight has

    @property
    def ranges(self) -> list[Range]:
        return [r for key in self.keys for r in key.ranges]

    @property
    def duration(self) -> float:
        """Each flight's duration [s] (the scenario's, or the one set)."""
        return float(self.scenario.data["duration"])

    def values(self, params: dict[str, float]) -> dict[str, Any]:
        """The scenario values (dotted key -> value) of the optimiser's ``params``."""
        return {key.key: key.value(params) for key in self.keys}

    def batch(self, values: dict[str, Any], first: int, count: int, objective_only: bool = False) -> Batch:
        """The flights of conditions ``first .. first+count-1`` with ``values`` (numbered by condition);
        ``objective_only``: their rows need only the objective's metric (:func:`fsr_bringup.sweeps.batch.fly_one`'s
        ``metric``)."""
        flights = [(c, {**condition_values(self.seed, c, self.seed_keys, self.sample, self.seeds), **values})
                   for c in range(first, first + count)]
        s = self.scenario
        return Batch(s.data, s.source, str(s.base_dir), flights, self.band,
                     self.objective.metric if objective_only else None)

    def spec(self) -> dict[str, Any]:
        """What makes the study this study (kept with it: a resumed study must have the same; ``training_sample``:
        how its training conditions give the sampled keys - one whose conditions drew them is not continued)."""
        return {"scenario": repr(self.scenario.data), "keys": repr(self.keys), "objective": self.objective.label,
                "penalty": self.objective.penalty, "seeds": self.seeds, "seed": self.seed,
                "sample": repr(self.sample), "training_sample": "spread", "band": self.band}


@dataclass
class Evaluation:
    """A candidate flown over conditions: the objective, the flights that did not finish, the rows."""

    objective: float
    lost: int
    rows: list[dict[str, Any]]

    def mean(self, metric: str) -> float:
        values = [row[metric] for row in self.rows if isinstance(row.get(metric), float) and math.isfinite(row[metric])]
        return sum(values) / len(values) if values else math.nan


@dataclass
class TuneResult:
    """What ``tune()`` found (``trials``: a pandas DataFrame, a row per trial; ``validation``: ``{"scenario":
    Evaluation, "best": Evaluation}`` on the held-out conditions)."""

    plan: TunePlan
    method: str
    best_params: dict[str, float]
    best_values: dict[str, Any]
    best_objective: float
    best_trial: int
    best_lost: int  # its flights that did not finish (training conditions)
    baseline: Evaluation  # the scenario's own parameters on the training conditions
    trials: Any
    validation: dict[str, Evaluation] = field(default_factory=dict)
    study_path: Path | None = None
    interrupted: bool = False
    wall_s: float = 0.0
    flights: int = 0


def _accepts(base: Scenario, values: dict[str, Any], key: str) -> bool:
    """Whether the scenario's validation takes ``values``; TuneError for a key it does not know at all."""
    try:
        check_scenario(flight_scenario(base, values))
    except ConfigError as error:
        if any(text in error.reason for text in STRUCTURAL):
            raise TuneError(f"--param {key}: {error}") from None
        return False
    return True


def _middle(r: Range) -> float:
    return math.sqrt(r.low * r.high) if r.log else 0.5 * (r.low + r.high)


def plan_tune(scenario: str | Path | dict[str, Any] | Scenario, params: dict[str, Any] | list[str],
              seeds: int = DEFAULT_SEEDS, objective: str | Objective = "position_error_rms_m",
              sample: dict[str, Any] | None = None, set: dict[str, Any] | None = None,  # noqa: A002
              duration: float | None = None, holdout: int = DEFAULT_HOLDOUT, seed: int = 0,
              penalty: float = DEFAULT_PENALTY, band: float = DEFAULT_BAND_M) -> TunePlan:
    """Check a tuning before anything flies (TuneError or ConfigError naming what is wrong)."""
    if seeds < 1:
        raise TuneError(f"--seeds: must be >= 1, got {seeds}")
    if holdout < 0:
        raise TuneError(f"--holdout: must be >= 0, got {holdout}")
    values = fixed_values(set, duration)
    base = load_checked(scenario, values).scenario
    items = [parse_param(text) for text in params] if isinstance(params, list) else [
        parse_param(f"{key}={spec if isinstance(spec, str) else ','.join(map(str, spec))}")
        for key, spec in params.items()]
    if not items:
        raise TuneError("nothing to tune: give --param KEY=[log:]LO:HI")
    keys = []
    for key, entries in items:
        if any(key == other.key for other in keys):
            raise TuneError(f"--param {key}: given twice")
        size = key_size(base.data, key, lambda value, key=key: _accepts(base, {key: value}, key))
        keys.append(tuned_key(key, entries, size))
    drawn = [sampled_key(k, v) for k, v in (sample or {}).items()]
    for item in drawn:
        if any(item.key == key.key for key in keys):
            raise TuneError(f"--sample {item.key}: also tuned (--param)")
    goal = objective if isinstance(objective, Objective) else parse_objective(objective, penalty)
    plan = TunePlan(base, keys, goal, int(seeds), int(holdout), int(seed),
                    scenario_seed_keys(base), drawn, band, values)
    middle = plan.values({r.name: _middle(r) for r in plan.ranges})
    try:
        first = condition_values(seed, 0, plan.seed_keys, drawn, plan.seeds)
        check_scenario(flight_scenario(base, {**middle, **first}))
    except ConfigError as error:
        raise TuneError(f"the middle of the ranges is refused: {error}") from None
    return plan


def _sampler(method: str, seed: int, plan: TunePlan) -> Any:
    import optuna

    if method == "cma":
        return optuna.samplers.CmaEsSampler(seed=seed, popsize=GENERATION, warn_independent_sampling=False)
    if method == "tpe":
        return optuna.samplers.TPESampler(seed=seed, multivariate=True, n_startup_trials=2 * GENERATION)
    if method == "random":
        return optuna.samplers.RandomSampler(seed=seed)
    raise TuneError(f"--method: unknown method '{method}' (one of {', '.join(METHODS)})")


class Flyer:
    """Flies batches locally (forked worker processes, created once) or on a Dask cluster; results in the order of
    the batches given."""

    def __init__(self, workers: int | None, cluster: str | None) -> None:
        self.cluster = cluster
        self.workers = 1 if cluster else max(1, int(workers or os.cpu_count() or 1))
        self.pool: ProcessPoolExecutor | None = None
        self.client: Any = None
        if cluster:
            self.client = cluster_client(cluster, TuneError, "--cluster")
            self.workers = cluster_threads(self.client)
        elif self.workers > 1:  # fork: the workers inherit the loaded modules and compiled core
            self.pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=get_context("fork"))

    def fly(self, batches: list[Batch]) -> list[BatchResult]:
        if self.client is not None:
            futures = self.client.map(fly_batch, batches, pure=False, retries=2)
            return self.client.gather(futures)
        if self.pool is None or len(batches) == 1:
            return [fly_batch(batch) for batch in batches]
        return list(self.pool.map(fly_batch, batches))

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)
        if self.client is not None:
            self.client.close()


def evaluate(plan: TunePlan, flyer: Flyer, candidates: list[dict[str, Any]], first: int, count: int,
             objective_only: bool = False) -> list[Evaluation]:
    """Each candidate's values flown over conditions ``first .. first+count-1``, in batches small enough that
    every worker has :data:`BATCHES_PER_WORKER` of them (the last ones balance the load before the next
    generation is asked); ``objective_only``: the rows need only the objective's metric (a lost flight's row is its
    end alone: an objective needs no more of it)."""
    batches_per_candidate = max(1, math.ceil(flyer.workers * BATCHES_PER_WORKER / max(1, len(candidates))))
    per = max(1, math.ceil(count / batches_per_candidate))
    batches, owner = [], []
    for index, values in enumerate(candidates):
        for start in range(first, first + count, per):
            batches.append(plan.batch(values, start, min(per, first + count - start), objective_only))
            owner.append(index)
    rows: list[list[dict[str, Any]]] = [[] for _ in candidates]
    for index, result in zip(owner, flyer.fly(batches), strict=True):
        rows[index] += [row for _, row in sorted(result.rows, key=lambda item: item[0])]
    return [Evaluation(plan.objective.of(r, plan.duration), lost(r), r) for r in rows]


@contextmanager
def _quiet_optuna() -> Iterator[None]:
    import optuna

    level = optuna.logging.get_verbosity()
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    try:
        yield
    finally:
        optuna.logging.set_verbosity(level)


def open_study(plan: TunePlan, method: str, out: Path | None, resume: bool, seed: int) -> Any:
    """The optuna study (in ``out/study.db``, or in memory without ``out``): new, or the one to resume."""
    import optuna

    sampler = _sampler(method, seed, plan)
    if out is None:
        return optuna.create_study(direction="minimize", sampler=sampler)
    path = out / STUDY_FILE
    if path.exists() and not resume:
        raise TuneError(f"--out {out}: holds a study already ({path}): --resume continues it, or give another --out")
    if resume and not path.exists():
        raise TuneError(f"--resume: no study in {out} (no {STUDY_FILE})")
    storage = f"sqlite:///{path}"
    study = optuna.create_study(study_name="fsr-tune", storage=storage, sampler=sampler, direction="minimize",
                                load_if_exists=resume)
    spec = {**plan.spec(), "method": method}
    if resume:
        kept = study.user_attrs.get("spec")
        if kept != spec:
            changed = sorted(k for k in spec if (kept or {}).get(k) != spec[k])
            raise TuneError(f"--resume: the study in {out} was made with other settings ({', '.join(changed)}); "
                            "give the same ones, or another --out")
        for trial in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,)):
            study.tell(trial.number, state=optuna.trial.TrialState.FAIL)  # in flight when it stopped: asked anew
    else:
        study.set_user_attr("spec", spec)
    return study


def tune(scenario: str | Path | dict[str, Any] | Scenario, params: dict[str, Any] | list[str],
         seeds: int = DEFAULT_SEEDS, objective: str = "position_error_rms_m", budget: int = DEFAULT_BUDGET,
         method: str = "cma", sample: dict[str, Any] | None = None, set: dict[str, Any] | None = None,  # noqa: A002
         duration: float | None = None, holdout: int = DEFAULT_HOLDOUT, seed: int = 0,
         penalty: float = DEFAULT_PENALTY, workers: int | None = None, cluster: str | None = None,
         out: str | Path | None = None, resume: bool = False,
         progress: Callable[[int, int, float, float], None] | None = None) -> TuneResult:
    """Tune ``params`` of ``scenario`` (module docstring).

    Parameters
    ----------
    scenario : str, Path, dict or Scenario
        As :func:`fsr_bringup.simulate`.
    params : dict or list of str
        ``{key: "[log:]LO:HI"}`` or ``{key: ["[log:]LO:HI" | "same" | number, ...]}`` for a list-valued key, or
        ``--param`` texts (:mod:`fsr_bringup.tuning.space`).
    seeds : int
        Conditions each candidate is flown under (:mod:`fsr_bringup.tuning.conditions`).
    objective : str
        ``METRIC[:STAT]`` (:mod:`fsr_bringup.tuning.objective`), minimised; ``penalty`` per lost flight.
    budget : int
        Trials to complete (a resumed study counts the ones it has).
    method : {"cma", "tpe", "random"}
        optuna's CMA-ES, TPE or random search, seeded by ``seed`` (which also seeds the conditions).
    sample : dict, optional
        ``{key: "uniform:LO:HI" | ...}``: drawn per condition (a mass error), as ``fsr-sweep --sample``.
    set, duration : optional
        Values every flight has, and its duration [s], as ``simulate``'s.
    holdout : int
        Held-out conditions the best and the scenario's own parameters are flown on at the end (0: none).
    workers, cluster : optional
        Local worker processes (default: every core), or a Dask scheduler's address.
    out : str or Path, optional
        Folder of the study (``study.db``); without it the study lives in memory. ``resume``: continue it.
    progress : callable, optional
        Called after each generation with ``(trials done, budget, wall seconds, best so far)``.

    Raises
    ------
    fsr_bringup.tuning.space.TuneError
        A key, range, metric, method or study refused (a ``ValueError`` naming it); nothing is flown.
    fsr_sim.config.validation.ConfigError
        An invalid value of the scenario.
    """
    import optuna

    if method not in METHODS:
        raise TuneError(f"--method: unknown method '{method}' (one of {', '.join(METHODS)})")
    if budget < 1:
        raise TuneError(f"--budget: must be >= 1, got {budget}")
    start = time.perf_counter()
    plan = plan_tune(scenario, params, seeds, objective, sample, set, duration, holdout, seed, penalty)
    out = None if out is None else Path(out)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
    with _quiet_optuna():
        study = open_study(plan, method, out, resume, seed)
    distributions = {r.name: optuna.distributions.FloatDistribution(r.low, r.high, log=r.log) for r in plan.ranges}
    flyer = Flyer(workers, cluster)
    flights = 0
    interrupted = False
    complete = optuna.trial.TrialState.COMPLETE
    baseline = Evaluation(math.nan, 0, [])
    validation: dict[str, Evaluation] = {}
    try:
        baseline = evaluate(plan, flyer, [{}], 0, plan.seeds)[0]
        flights += plan.seeds
        with _quiet_optuna():
            done = len(study.get_trials(deepcopy=False, states=(complete,)))
            while done < budget:
                asked = [study.ask(distributions) for _ in range(min(GENERATION, budget - done))]
                try:
                    results = evaluate(plan, flyer, [plan.values(t.params) for t in asked], 0, plan.seeds,
                                       objective_only=True)
                except BaseException:
                    for trial in asked:
                        study.tell(trial, state=optuna.trial.TrialState.FAIL)
                    raise
                for trial, result in zip(asked, results, strict=True):
                    trial.set_user_attr("lost", result.lost)
                    study.tell(trial, result.objective)
                flights += len(asked) * plan.seeds
                done += len(asked)
                if progress is not None:
                    progress(done, budget, time.perf_counter() - start, study.best_value)
        best = study.best_trial
        if plan.holdout:
            scenario_own, found = evaluate(plan, flyer, [{}, plan.values(best.params)], plan.seeds, plan.holdout)
            validation = {"scenario": scenario_own, "best": found}
            flights += 2 * plan.holdout
    except KeyboardInterrupt:
        interrupted = True
        best = study.best_trial if study.get_trials(deepcopy=False, states=(complete,)) else None
    finally:
        flyer.close()
    trials = trials_table(study, plan)
    if best is None:
        raise KeyboardInterrupt("interrupted before a trial completed")
    return TuneResult(plan, method, dict(best.params), plan.values(best.params), float(best.value), best.number,
                      int(best.user_attrs.get("lost", 0)), baseline,
                      trials, validation, None if out is None else out / STUDY_FILE, interrupted,
                      time.perf_counter() - start, flights)


def trials_table(study: Any, plan: TunePlan) -> Any:
    """A row per trial: its number, state, objective, flights lost and parameters, and the best so far."""
    import pandas as pd

    rows = []
    best = math.inf
    for trial in study.get_trials(deepcopy=False):
        value = trial.value if trial.value is not None else math.nan
        if math.isfinite(value):
            best = min(best, value)
        rows.append({"trial": trial.number, "trial_state": trial.state.name.lower(), "objective": value,
                     "best_so_far": best if math.isfinite(best) else math.nan,
                     "lost": trial.user_attrs.get("lost", math.nan),
                     **{r.name: trial.params.get(r.name, math.nan) for r in plan.ranges}})
    return pd.DataFrame.from_records(rows, columns=["trial", "trial_state", "objective", "best_so_far", "lost",
                                                    *(r.name for r in plan.ranges)]).set_index("trial")
