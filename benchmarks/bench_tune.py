"""fsr-tune's walk-through (docs/tuning.md) as a benchmark: its wall time on this machine against the speed target,
the held-out objective of CMA-ES against random search with the same budget, and the same study on a loopback Dask
cluster (min / median over ``--repeat`` tuner seeds; nothing here is a test: the figures depend on the machine and
its load).

    .venv/bin/python benchmarks/bench_tune.py                          # the walk-through: 400 trials x 10 seeds
    .venv/bin/python benchmarks/bench_tune.py --speed                  # its wall time only (no random search)
    .venv/bin/python benchmarks/bench_tune.py --budget 16 --seeds 2 --repeat 1 --holdout 4 --duration 3  # smoke
    .venv/bin/python benchmarks/bench_tune.py --dask                   # + the study through a scheduler, 2 workers

The speed target: 400 trials x 10 seeds of 15 s flights (4000 flights, 60 000 flight-seconds) in 60 s on 2 cores,
scaled by the flight-seconds of a smaller study (``target``; the ratio printed is wall / target, <= 1 meets it).
Printed per tuner seed: the study's wall time, flights and flights/s, its ratio to the target, the best's objective
on the training conditions and on the held-out ones (with the flights lost), the scenario's own parameters on the
held-out conditions, random search's best on the same held-out conditions, and their ratio; with ``--dask``,
whether the cluster's study has the same trials and best as the local one.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from fsr_bringup import tune

SCENARIO = "step_disturbance"
PARAMS = {  # the geometric law's gains, x and y tied (a symmetric vehicle), z on its own
    "controller.gains.k_p": "log:1:60,same,log:2:120",
    "controller.gains.k_v": "log:1:60,same,log:2:120",
    "controller.gains.k_r": "log:0.5:60,same,log:0.5:60",
    "controller.gains.k_w": "log:0.2:30,same,log:0.2:30",
}
CONDITIONS = {"sensors.preset": "onboard", "plant.rotor_time_constant": 0.03}  # a 30 ms motor, onboard sensors
SAMPLE = {"plant.mass": "uniform:0.96:1.44"}  # 20 % mass error about quadrotor_ex4's 1.2 kg model
TARGET_S = 60.0  # the study's wall time [s] on 2 cores the walk-through at full size should take at most
TARGET_FLIGHT_SECONDS = 400 * 10 * 15.0  # its trials x seeds x duration [s]


def target(args: argparse.Namespace) -> float:
    """The target wall time [s] of a study of ``args``' size (the full-size target scaled by its flight-seconds)."""
    return TARGET_S * args.budget * args.seeds * args.duration / TARGET_FLIGHT_SECONDS


def cpu_seconds() -> float:
    """CPU time [s] of this process and its finished children (a study's workers end with it)."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def study(method: str, seed: int, args: argparse.Namespace, **extra: object) -> object:
    return tune(SCENARIO, PARAMS, seeds=args.seeds, budget=args.budget, method=method, sample=SAMPLE,
                set=CONDITIONS, duration=args.duration, holdout=args.holdout, seed=seed, workers=args.workers,
                **extra)


def loopback_cluster(folder: Path) -> tuple[str, list[subprocess.Popen]]:
    """A Dask scheduler and two one-thread workers on 127.0.0.1 (killed by the caller)."""
    dask = str(Path(sys.executable).with_name("dask"))
    env = {**os.environ, "DASK_TEMPORARY_DIRECTORY": str(folder)}
    scheduler_file = folder / "scheduler.json"
    started = [subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                 "--scheduler-file", str(scheduler_file)], cwd=folder, env=env,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    deadline = time.monotonic() + 60
    while not (scheduler_file.exists() and scheduler_file.stat().st_size):
        if time.monotonic() > deadline:
            raise RuntimeError("the Dask scheduler did not start within 60 s")
        time.sleep(0.1)
    address = json.loads(scheduler_file.read_text())["address"]
    for i in range(2):
        started.append(subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                         "--host", "127.0.0.1", "--local-directory", str(folder / f"worker{i}")],
                                        cwd=folder, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    from distributed import Client

    with Client(address, timeout=30, set_as_default=False) as client:
        client.wait_for_workers(2, timeout=60)
    return address, started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budget", type=int, default=400)
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--duration", type=float, default=15.0)
    parser.add_argument("--holdout", type=int, default=50)
    parser.add_argument("--repeat", type=int, default=3, help="tuner seeds")
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--dask", action="store_true", help="also the first seed's study on a loopback cluster")
    parser.add_argument("--speed", action="store_true", help="the CMA-ES study's wall time only (no random search)")
    args = parser.parse_args()
    walls, rates, ratios, cpus = [], [], [], []
    goal = target(args)
    print(f"{SCENARIO}: {args.budget} trials x {args.seeds} seeds of {args.duration:g} s, {len(PARAMS)} gains "
          f"(x, y tied), {CONDITIONS}, {SAMPLE}; held out: {args.holdout} conditions; {os.cpu_count()} cores; "
          f"target {goal:.1f} s")
    for seed in range(args.repeat):
        cpu = cpu_seconds()
        cma = study("cma", seed, args)
        cpu = cpu_seconds() - cpu
        walls.append(cma.wall_s)
        rates.append(cma.flights / cma.wall_s)
        cpus.append(cpu)
        held, own = cma.validation["best"], cma.validation["scenario"]
        line = (f"seed {seed}: cma {cma.wall_s:.1f} s ({cma.flights} flights, {rates[-1]:.1f} flights/s, "
                f"{cma.wall_s / goal:.2f} x the target; CPU {cpu:.1f} s, {1e3 * cpu / cma.flights:.1f} ms a flight, "
                f"load average {os.getloadavg()[0]:.1f}); best {cma.best_objective:.4g} training, {held.objective:.4g} "
                f"held out ({held.lost} lost); scenario's own {own.objective:.4g} ({own.lost} lost)")
        if not args.speed:
            blind = study("random", seed, args).validation["best"]
            ratios.append(held.objective / blind.objective)
            line += f"; random search {blind.objective:.4g} ({blind.lost} lost): cma / random {ratios[-1]:.3f}"
        print(line, flush=True)
    print(f"study wall [s] min / median: {min(walls):.1f} / {statistics.median(walls):.1f} (target {goal:.1f}: "
          f"{min(walls) / goal:.2f} / {statistics.median(walls) / goal:.2f} x); flights/s max / median: "
          f"{max(rates):.1f} / {statistics.median(rates):.1f}; CPU [s] min / median: {min(cpus):.1f} / "
          f"{statistics.median(cpus):.1f} (half of it: the wall time on two free cores at best)")
    if ratios:
        print(f"held-out objective cma / random min / median: {min(ratios):.3f} / {statistics.median(ratios):.3f}")
    if args.dask:
        local = study("cma", 0, args)
        with tempfile.TemporaryDirectory() as tmp:
            address, started = loopback_cluster(Path(tmp))
            try:
                remote = study("cma", 0, args, cluster=address)
            finally:
                for process in started:
                    process.kill()
                    process.wait(timeout=30)
        same = remote.trials.equals(local.trials) and remote.best_trial == local.best_trial
        print(f"dask (scheduler + 2 workers on loopback): {remote.wall_s:.1f} s, the same trials and best as "
              f"locally: {same}")


if __name__ == "__main__":
    main()
