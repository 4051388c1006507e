#!/usr/bin/env python3
"""Benchmark of the report's estimator sweep: c0 in {1, 5, 10, 25, 50, 100} x r = 1..5 (30 runs) over the
30 s, 1 kHz exercise-3 log, by the whole-log path (``scipy.signal.sosfilt``, the momentum residual computed
once) and by the sample-by-sample recursion (``MomentumObserver.update``, what the node runs).

    .venv/bin/python benchmarks/bench_estimation_sweep.py [LOG] [--online-runs N]

LOG defaults to examples/ex3_flight_log.mcap. The sample-by-sample sweep takes minutes (30 x 30 001
updates), so by default it times N = 3 runs and extrapolates to 30 (say --online-runs 30 for all of them).
Target: whole sweep < 1 s.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from fsr_estimation.estimator.metrics import sweep
from fsr_estimation.estimator.observer import MomentumObserver, ObserverModel, estimate_log
from fsr_estimation.io.flight_log import load_flight_log

ROOT = Path(__file__).resolve().parent.parent
C0_VALUES = [1.0, 5.0, 10.0, 25.0, 50.0, 100.0]
R_VALUES = [1, 2, 3, 4, 5]
MODEL = ObserverModel(1.5, np.diag([1.2416, 1.2416, 2.4832]))
TRUTH = np.array([1.0, 1.0, 0.0, 0.0, 0.0, -0.4])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("log", nargs="?", default=str(ROOT / "examples" / "ex3_flight_log.mcap"))
    parser.add_argument("--online-runs", type=int, default=3)
    args = parser.parse_args()
    log = load_flight_log(args.log)
    arrays = (log.velocity_world, log.eta, log.eta_dot, log.force_body, log.torque_body)
    pairs = [(c0, r) for c0 in C0_VALUES for r in R_VALUES]
    print(f"log: {args.log}: {len(log)} samples, T_s = {log.sample_time} s; {len(pairs)} runs")

    start = time.perf_counter()
    results = sweep(log, MODEL, C0_VALUES, R_VALUES, TRUTH, settling="report")
    whole = time.perf_counter() - start
    print(f"whole-log sweep with metrics (30 runs):          {whole:8.3f} s  ({'meets' if whole < 1 else 'MISSES'} "
          "the < 1 s target)")
    start = time.perf_counter()
    offline = {(c0, r): estimate_log(*arrays, model=MODEL, c0=c0, r=r, sample_time=log.sample_time)
               for c0, r in pairs[: args.online_runs]}
    separate = (time.perf_counter() - start) / len(offline)
    print(f"whole-log estimate_log, residual recomputed:     {separate * 1e3:8.1f} ms per run")

    start = time.perf_counter()
    worst = 0.0
    for c0, r in pairs[: args.online_runs]:
        observer = MomentumObserver(MODEL.mass, MODEL.inertia, c0, r, log.sample_time)
        out = np.empty((len(log), 6))
        for k in range(len(log)):
            out[k] = observer.update(arrays[0][k], arrays[1][k], arrays[2][k], arrays[3][k], arrays[4][k])
        worst = max(worst, float(np.abs(out - offline[(c0, r)]).max()))
    online = time.perf_counter() - start
    per_run = online / args.online_runs
    per_sample = per_run / len(log)
    print(f"sample-by-sample: {args.online_runs} runs in {online:.2f} s -> 30-run sweep ~ {30 * per_run:8.2f} s "
          f"(max |difference| to the whole-log path {worst:.1e})")
    print(f"ratio sample-by-sample / whole-log sweep:        {30 * per_run / whole:8.0f} x")
    print(f"online recursion cost: {per_sample * 1e6:.1f} us per sample (MomentumObserver.update, c0/r as above)")
    best = min(results, key=lambda res: float(np.nanmean(res.mae[[0, 1, 5]])))
    print(f"lowest mean MAE (f_x, f_y, tau_z): c0 = {best.c0:g}, r = {best.r}")


if __name__ == "__main__":
    main()
