#!/usr/bin/env python3
"""Benchmark of fsr-sweep: ex4_geometric flights of 5 s (metrics only), sampled over the plant mass, on every
core of this machine; min and median of ``--repeat`` runs.

    .venv/bin/python benchmarks/bench_sweep.py                       # 1, 10, 100, 1000 flights; the CLI target
    .venv/bin/python benchmarks/bench_sweep.py --flights 1,10,100,1000,10000 --repeat 3
    .venv/bin/python benchmarks/bench_sweep.py --flights 1,10 --repeat 1 --command-n 10   # a smoke run

Rows: flights, wall time [s] (the whole ``sweep()`` call: checking, the first flight, the batches), start-up
[s] (checking the sweep with its first flight, before any worker is forked), flights/s and vehicle-steps/s
over the wall time, and the CPU time [s] of this process and its workers with the vehicle-steps per CPU second
(what a busy machine does not change much: the wall rate of an idle one is at most the cores times it). The
load average is printed before and after. Then the command of the target, ``fsr-sweep ex4_geometric --sample
plant.mass=uniform:1.0:1.5 --n 1000 --duration 5`` (table and figures included) as a child process, wall time.
Targets: >= 2e6 vehicle-steps/s for 1 000 flights, the command <= 6 s.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fsr_bringup import sweep

TARGET_STEPS_PER_S = 2e6
TARGET_COMMAND_S = 6.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--flights", default="1,10,100,1000")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--duration", type=float, default=5.0)
    parser.add_argument("--command-n", type=int, default=1000, help="flights of the command (target: 1000)")
    args = parser.parse_args()
    print(f"ex4_geometric, {args.duration:g} s flights, {os.cpu_count()} cores, min / median of {args.repeat}")
    print(f"load average before: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print("| flights | wall [s] | start-up [s] | flights/s | vehicle-steps/s | CPU [s] | vehicle-steps/CPU-s |")
    print("|---|---|---|---|---|---|---|")
    for count in (int(v) for v in args.flights.split(",")):
        walls, startups, cpus, steps = [], [], [], 0
        for seed in range(args.repeat):
            before = _cpu_seconds()
            table = sweep("ex4_geometric", sample={"plant.mass": "uniform:1.0:1.5"}, n=count, seed=seed,
                          duration=args.duration)
            cpus.append(_cpu_seconds() - before)
            walls.append(table.attrs["wall_s"])
            startups.append(table.attrs["startup_s"])
            steps = table.attrs["vehicle_steps"]
        best, median = min(walls), statistics.median(walls)
        cpu, cpu_median = min(cpus), statistics.median(cpus)
        print(f"| {count} | {best:.2f} / {median:.2f} | {min(startups):.2f} / {statistics.median(startups):.2f} | "
              f"{count / best:.1f} / {count / median:.1f} | {steps / best:.3g} / {steps / median:.3g} | "
              f"{cpu:.2f} / {cpu_median:.2f} | {_rate(steps, cpu)} / {_rate(steps, cpu_median)} |")
    print(f"target: >= {TARGET_STEPS_PER_S:.0e} vehicle-steps/s at 1000 flights")
    command = [str(Path(sys.executable).with_name("fsr-sweep")), "ex4_geometric", "--sample",
               "plant.mass=uniform:1.0:1.5", "--n", str(args.command_n), "--duration", "5"]
    walls = []
    with tempfile.TemporaryDirectory() as folder:
        for i in range(args.repeat):
            start = time.perf_counter()
            subprocess.run([*command, "--out", str(Path(folder) / f"run{i}")], check=True, capture_output=True)
            walls.append(time.perf_counter() - start)
    target = f" (target <= {TARGET_COMMAND_S:g} s)" if args.command_n == 1000 else ""
    print(f"{' '.join(command[1:])}: {min(walls):.2f} / {statistics.median(walls):.2f} s wall{target}")
    print(f"load average after: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")


def _rate(steps: int, seconds: float) -> str:
    return f"{steps / seconds:.3g}" if seconds > 0 else "-"


def _cpu_seconds() -> float:
    """User + system CPU time [s] of this process and its finished children (the sweep's workers)."""
    children = os.times()
    return time.process_time() + children.children_user + children.children_system


if __name__ == "__main__":
    main()
