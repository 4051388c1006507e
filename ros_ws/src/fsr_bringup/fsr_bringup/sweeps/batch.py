"""A batch of a sweep's flights, flown in one process: what a local worker process and a Dask worker run.

Each flight is set up from the sweep's scenario and its own ``set`` values: from the scenario packed once, only
the swept values packed anew, where that is exact (:mod:`fsr_bringup.sweeps.repack`), else validated in full
like any flight (a value refused is an ``invalid`` row naming the key). It is flown whole by the compiled loop in
one call (nothing passes through Python per step) and measured as it flies (:mod:`fsr_bringup.sweeps.measured`);
a flight the loop cannot measure (it ended early) is flown again into arrays this process reuses from flight to
flight and measured from them (:func:`fsr_bringup.sweeps.metrics.flight_row`). A flight that diverges is a row
with its reason; the batch goes on.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fsr_bringup.core.flight_loop import CONTROLLER_FAILED
from fsr_bringup.core.flight_loop import FINISHED as FINISHED_OUTCOME
from fsr_bringup.runner.in_process_flight import FlightArrays, prepare_flight
from fsr_bringup.sweeps.axes import flight_scenario
from fsr_bringup.sweeps.measured import fly_accumulated, fly_measured, loop_flight, measured_row
from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M, METRIC_COLUMNS, flight_row, invalid_row
from fsr_bringup.sweeps.repack import PackedSweep
from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import DIVERGED, FINISHED


@dataclass
class Batch:
    """Flights ``(number, set values)`` of one sweep, and what every flight shares (picklable)."""

    data: dict[str, Any]  # the sweep's scenario mapping (its fixed values and duration applied)
    source: str
    base_dir: str
    flights: list[tuple[int, dict[str, Any]]]
    band: float = DEFAULT_BAND_M
    metric: str | None = None  # the one metric its caller needs (fly_one); None: the whole row


@dataclass
class BatchResult:
    rows: list[tuple[int, dict[str, Any]]]  # (flight number, metrics row)
    steps: int  # vehicle-steps flown
    wall: float  # s
    worker: str  # host:pid that flew it


TRUTH_COLUMNS = tuple(c for c in METRIC_COLUMNS if c.startswith("estimate_"))  # the estimate against the truth
_ARRAYS: list[FlightArrays] = []  # this process' arrays, reused by its next flights


def packed_sweep(base: Scenario, band: float) -> PackedSweep | None:
    """This process' :class:`PackedSweep` of ``base`` (made once per sweep scenario and band), or None when the
    scenario alone cannot be set up."""
    key = (repr(base.data), base.source, str(base.base_dir), band)
    if _PACKED and _PACKED[0][0] == key:
        return _PACKED[0][1]
    try:
        packed = PackedSweep(prepare_flight(base), band)
    except ValueError:  # ConfigError too: a scenario that needs its swept values to be valid
        packed = None
    _PACKED[:] = [(key, packed)]
    return packed


_PACKED: list[tuple[tuple, PackedSweep | None]] = []


def fly_one(base: Scenario, values: dict[str, Any], band: float = DEFAULT_BAND_M, measured: bool = True,
            packed: PackedSweep | None = None, metric: str | None = None) -> tuple[dict[str, Any], int]:
    """The metrics row of one flight and the steps it flew: measured in the loop where it can be
    (:mod:`fsr_bringup.sweeps.measured`; ``measured=False``: always from the flight's arrays), set up from
    ``packed`` where it can be (:mod:`fsr_bringup.sweeps.repack`).

    ``metric``: the one column the caller needs (fsr-tune's trials: their objective's), for a flight set up from
    ``packed``: a flight that is lost (it ends early) is not flown again into arrays for its metrics and the reason
    of its end - its row is :func:`lost_row` (a lost flight counts as a penalty whatever its metrics) -, and unless
    ``metric`` is one of :data:`TRUTH_COLUMNS` the estimator is neither flown nor measured against the effective
    truth (the flight is the same: the controller does not read that estimator); the row's other columns are
    those of the whole row, the estimator's NaN."""
    repacked = packed.flight_for(values) if packed is not None and measured else None
    if repacked is not None:
        if metric is not None and metric not in TRUTH_COLUMNS:
            repacked = repacked.replace(with_estimator=False, measures=repacked.measures._replace(truth=False))
        outcome, k, acc = fly_accumulated(repacked)
        if outcome == FINISHED_OUTCOME and acc[0].truth_undefined <= 0:
            return measured_row(repacked, acc), repacked.steps
        if outcome != FINISHED_OUTCOME and metric is not None:
            return lost_row(k, repacked.period_ns), k - (outcome == CONTROLLER_FAILED)
        measured = False  # it ended early, or a truth is not finite: flown again in full, into arrays
    try:
        scenario = flight_scenario(base, values)
    except ConfigError as error:
        return invalid_row(str(error)), 0
    try:
        setup = prepare_flight(scenario, arrays=_ARRAYS[0] if _ARRAYS else None)
    except ConfigError as error:
        return invalid_row(str(scenario.attribute(error))), 0
    except ValueError as error:  # a model refusing its values (e.g. an observer filter) names them
        return invalid_row(str(error)), 0
    _ARRAYS[:] = [setup.arrays]
    if measured:
        row = fly_measured(loop_flight(setup, band))
        if row is not None:
            return row, setup.steps
        setup = prepare_flight(scenario, arrays=setup.arrays)  # flown again from the start, into its arrays
    start = time.perf_counter()
    outcome, k, detail = setup.fly(0, setup.steps)
    count = setup.flown(outcome, k)
    end_reason, reason = setup.end(outcome, k, detail) or (FINISHED, "")
    if count < 2:  # no step flown: nothing to measure
        row = invalid_row(reason)
        row["end_reason"] = end_reason
        return row, max(count - 1, 0)
    run = setup.run(count, end_reason, reason, time.perf_counter() - start, copy=False)
    return flight_row(run, band), count - 1


def lost_row(k: int, period_ns: int) -> dict[str, Any]:
    """The row of a flight lost at step ``k`` whose metrics and reason were not taken (``fly_one``)."""
    row = invalid_row(f"lost at t = {k * period_ns * 1e-9:.4f} s (not flown again for its metrics and reason)")
    row.update(end_reason=DIVERGED, flown_s=(k * period_ns) * 1e-9)
    return row


def fly_batch(batch: Batch) -> BatchResult:
    """Fly every flight of ``batch`` (module docstring)."""
    import os
    import socket

    start = time.perf_counter()
    base = Scenario(data=batch.data, source=batch.source, base_dir=Path(batch.base_dir))
    packed = packed_sweep(base, batch.band)
    rows, steps = [], 0
    for number, values in batch.flights:
        row, flown = fly_one(base, values, batch.band, packed=packed, metric=batch.metric)
        rows.append((number, row))
        steps += flown
    return BatchResult(rows, steps, time.perf_counter() - start, f"{socket.gethostname()}:{os.getpid()}")
