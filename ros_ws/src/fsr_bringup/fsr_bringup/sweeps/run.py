"""``sweep()``: many closed-loop flights of one scenario, in batches over all cores or on a Dask cluster, as one
table.

    from fsr_bringup import sweep
    table = sweep("ex4_geometric", sample={"plant.mass": "uniform:1.0:1.5"}, n=1000, duration=5.0)
    table = sweep("ex3_estimation", grid={"estimator.c0": [1, 10, 100], "estimator.r": [1, 2, 3]})

Flights are split into batches (:mod:`fsr_bringup.sweeps.batch`); a batch is flown by one worker process, each
flight in one call of the compiled loop, which measures the flight as it flies it (the row's metrics as running
accumulators, no per-step arrays: :mod:`fsr_bringup.sweeps.measured`). A flight is set up from the sweep's
scenario packed once, only its swept values packed anew, where that is exact (:mod:`fsr_bringup.sweeps.repack`),
else in full. Locally the workers are forked from this process (they inherit its loaded modules, compiled core
and packed scenario: no start-up per worker); a separate process per core rather than numba's ``prange`` over
vehicles in one process, because a flight's set-up is Python (0.1 ms from the packed scenario, a few ms in
full): in one process it would run on one core while the others wait, whereas each worker sets up and flies its
own flights; while flying, the workers share nothing, which is all a ``prange`` would give too (the same
compiled loop either way). On a cluster (``cluster="tcp://host:8786"``) the batches are Dask tasks: a worker
lost mid-sweep has its batches run again elsewhere by the scheduler, and each batch's rows are taken once, from
the task's one result. Rows are put back in flight order, so the table does not depend on where or in which
order the batches ran.
"""

from __future__ import annotations

import itertools
import math
import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from fsr_bringup.api import fixed_values, load_checked
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_bringup.sweeps.axes import (
    GridAxis,
    SampledKey,
    SweepError,
    check_axes,
    flight_scenario,
    grid_axis,
    plan_flights,
    sampled_key,
)
from fsr_bringup.sweeps.batch import Batch, BatchResult, fly_batch
from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M, METRIC_COLUMNS, RANKABLE_METRICS
from fsr_bringup.sweeps.pareto import pareto_front, parse_pareto
from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError

MAX_BATCH = 64  # flights per batch at most (a lost worker costs at most this many flights again)
BATCHES_PER_WORKER = 4  # at least, when there are enough flights (the last batches balance the load)


@dataclass
class SweepPlan:
    """A checked sweep: its scenario (fixed values applied), what varies, every flight's values, and the first
    flight's row (flown while checking: it validates the swept keys and loads the compiled core before any worker
    is forked)."""

    scenario: Scenario
    grid: list[GridAxis]
    sample: list[SampledKey]
    flights: list[dict[str, Any]]
    seed: int
    first: BatchResult

    @property
    def keys(self) -> list[str]:
        return [axis.key for axis in self.grid] + [item.key for item in self.sample]

    def batches(self, workers: int, band: float) -> list[Batch]:
        """The flights after the first, in batches."""
        rest = list(enumerate(self.flights))[1:]
        size = max(1, min(MAX_BATCH, math.ceil(len(rest) / (workers * BATCHES_PER_WORKER))))
        s = self.scenario
        return [Batch(s.data, s.source, str(s.base_dir), rest[i:i + size], band) for i in range(0, len(rest), size)]


def plan_sweep(scenario: str | Path | dict[str, Any] | Scenario, grid: dict[str, Any] | list[GridAxis] | None = None,
               sample: dict[str, Any] | list[SampledKey] | None = None, n: int | None = None, seed: int = 0,
               duration: float | None = None, set: dict[str, Any] | None = None,  # noqa: A002
               band: float = DEFAULT_BAND_M) -> SweepPlan:
    """Check a sweep before anything flies: the scenario with its fixed ``set`` values and ``duration`` (any
    invalid value: ConfigError naming it), the swept keys (:class:`SweepError` naming the key: not a numeric
    leaf, unknown - with a "did you mean" -, swept twice, a bad distribution) and the flights."""
    base = load_checked(scenario, fixed_values(set, duration)).scenario
    axes = [grid_axis(k, v) for k, v in grid.items()] if isinstance(grid, dict) else list(grid or [])
    drawn = [sampled_key(k, v) for k, v in sample.items()] if isinstance(sample, dict) else list(sample or [])
    drawn = check_axes(base, axes, drawn)
    if not axes and not drawn:
        raise SweepError("nothing to sweep: give a grid axis (--grid KEY=V1,V2) or a sampled key (--sample)")
    flights = plan_flights(axes, drawn, n, seed)
    _check_keys(base, flights[0])
    first = fly_batch(Batch(base.data, base.source, str(base.base_dir), [(0, flights[0])], band))
    return SweepPlan(base, axes, drawn, flights, seed, first)


def _check_keys(base: Scenario, first: dict[str, Any]) -> None:
    """A swept key the scenario's validation does not know (or cannot hold) refuses the sweep; a value it refuses
    is only that flight's ``invalid`` row."""
    try:
        check_scenario(flight_scenario(base, first))
    except ConfigError as error:
        structural = ("unknown key", "out of range", "cannot hold", "has no item")
        if any(text in error.reason for text in structural):
            raise SweepError(str(error)) from None


def _local_results(batches: list[Batch], workers: int) -> Iterator[BatchResult]:
    if workers <= 1 or len(batches) <= 1:
        for batch in batches:
            yield fly_batch(batch)
        return
    # fork: the workers inherit this process' imports and loaded compiled core (spawn would pay both per worker)
    with ProcessPoolExecutor(max_workers=min(workers, len(batches)), mp_context=get_context("fork")) as pool:
        futures = [pool.submit(fly_batch, batch) for batch in batches]
        try:
            for future in as_completed(futures):
                yield future.result()
        except BaseException:
            for future in futures:
                future.cancel()
            raise


def cluster_client(address: str, error: type[Exception] = SweepError, option: str = "cluster") -> Any:
    """A Dask client of the scheduler at ``address``; ``error``, its message led by ``option``, when
    dask[distributed] is not installed or the scheduler cannot be reached."""
    try:
        from distributed import Client
    except ImportError:  # pragma: no cover - a pinned dependency
        raise error(f"{option}: dask[distributed] is not installed (pip install 'dask[distributed]')") from None
    try:
        return Client(address, timeout=30, set_as_default=False)
    except OSError as failure:
        raise error(f"{option}: cannot reach the Dask scheduler at {address}: {failure}") from None


def cluster_threads(client: Any) -> int:
    """The number of worker threads of the Dask cluster of ``client`` (the batches' parallelism there)."""
    return max(1, sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()))


def _cluster_results(batches: list[Batch], address: str) -> Iterator[BatchResult]:
    client = cluster_client(address)
    from distributed import as_completed as dask_completed

    try:
        futures = client.map(fly_batch, batches, pure=False, retries=2)
        for future in dask_completed(futures, loop=client.loop):
            yield future.result()
    finally:
        client.close()


def cluster_workers(address: str) -> int:
    """The number of worker threads of the Dask cluster at ``address`` (the batches' parallelism there)."""
    from distributed import Client

    with Client(address, timeout=30, set_as_default=False) as client:
        return cluster_threads(client)


def sweep(
    scenario: str | Path | dict[str, Any] | Scenario,
    grid: dict[str, Any] | None = None,
    sample: dict[str, Any] | None = None,
    n: int | None = None,
    seed: int = 0,
    duration: float | None = None,
    workers: int | None = None,
    cluster: str | None = None,
    set: dict[str, Any] | None = None,  # noqa: A002 - the name of fsr-fly's --set
    band: float = DEFAULT_BAND_M,
    progress: Callable[[int, int, float], None] | None = None,
    pareto: tuple[str, str] | str | None = None,
):  # noqa: ANN201 - pandas is imported lazily
    """Fly every flight of a grid and/or a sample of a scenario; one row per flight.

    Parameters
    ----------
    scenario : str, Path, dict or Scenario
        As :func:`fsr_bringup.simulate`.
    grid : dict, optional
        ``{dotted key: [values]}``: the product of the axes (values: numbers or lists of numbers).
    sample : dict, optional
        ``{dotted key: "uniform:LO:HI" | "normal:MEAN:STD" | "loguniform:LO:HI"}``, ``n`` draws (``seed``),
        each grid point flown with every draw.
    duration : float, optional
        Flight duration [s] (overrides the scenario's).
    workers : int, optional
        Local worker processes (default: every core); ignored with ``cluster``.
    cluster : str, optional
        A Dask scheduler's address (``tcp://host:8786``): the batches run on its workers.
    set : dict, optional
        Values every flight has (``{"controller.compensation": "estimate"}``), as ``simulate``'s ``set``.
    band : float
        The position band [m] of the ``settling_time_s`` column.
    progress : callable, optional
        Called as batches end with ``(flights done, flights, wall seconds so far)``.
    pareto : (str, str) or "X,Y", optional
        Two metric columns to make small together: a ``pareto`` column marks the finished flights on their
        Pareto front (:mod:`fsr_bringup.sweeps.pareto`), as ``fsr-sweep --pareto``.

    Returns
    -------
    pandas.DataFrame
        Indexed by flight number: a column per swept key (named by the key), then
        :data:`fsr_bringup.sweeps.metrics.METRIC_COLUMNS`. ``attrs`` holds ``scenario``, ``seed``, ``flights``,
        ``vehicle_steps``, ``wall_s`` (set-up included), ``workers`` and ``startup_s`` (checking the
        sweep, with its first flight).

    Raises
    ------
    fsr_bringup.sweeps.axes.SweepError
        A swept key or distribution refused (a ``ValueError`` naming the key); nothing is flown.
    fsr_sim.config.validation.ConfigError
        An invalid fixed value of the scenario.
    """
    import pandas as pd

    if pareto is not None:
        pareto = parse_pareto(pareto if isinstance(pareto, str) else ",".join(pareto), RANKABLE_METRICS)
    start = time.perf_counter()
    plan = plan_sweep(scenario, grid, sample, n, seed, duration, set, band)
    startup = time.perf_counter() - start
    parallel = cluster_workers(cluster) if cluster else max(1, int(workers or os.cpu_count() or 1))
    batches = plan.batches(parallel, band)
    results = _cluster_results(batches, cluster) if cluster else _local_results(batches, parallel)
    rows: dict[int, dict[str, Any]] = {}
    steps = 0
    for result in itertools.chain([plan.first], results):
        for number, row in result.rows:
            if number in rows:  # a batch is taken once; a flight in two would be a bug
                raise RuntimeError(f"flight {number} came back twice")
            rows[number] = row
        steps += result.steps
        if progress is not None:
            progress(len(rows), len(plan.flights), time.perf_counter() - start)
    missing = [i for i in range(len(plan.flights)) if i not in rows]
    if missing:
        raise RuntimeError(f"{len(missing)} flight(s) never came back (first: {missing[0]})")
    records = [{**plan.flights[i], **rows[i]} for i in range(len(plan.flights))]
    table = pd.DataFrame.from_records(records, columns=[*plan.keys, *METRIC_COLUMNS])
    table.index.name = "flight"
    table.attrs.update(scenario=plan.scenario.name, seed=seed, flights=len(records), vehicle_steps=steps,
                       wall_s=time.perf_counter() - start, workers=parallel, startup_s=startup,
                       keys=plan.keys, grid=[axis.key for axis in plan.grid], sample=[s.key for s in plan.sample])
    if pareto is not None:
        table["pareto"] = pareto_front(table, *pareto)
        table.attrs["pareto"] = list(pareto)
    return table
