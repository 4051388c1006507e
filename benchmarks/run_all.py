"""Every speed figure in one table (min and median of ``--repeat`` runs; CPU time where it applies), with the
targets of the compiled flight core (docs/testing.md, *Speed*).

    .venv/bin/python benchmarks/run_all.py                 # ~15 min on 2 cores (installs RotorPy once)
    .venv/bin/python benchmarks/run_all.py --quick         # a smoke pass (~1 min): 1 run each, 1-3 s flights,
                                                           # graph ex4 only, no floor, no RotorPy

Rows:

* in-process loop [us per step, CPU]: ``fly_in_process`` of ex4, ex5 and the octocopter with ground effect,
  without and with its recording (``process_time`` over the flight / steps); ex5 and the octocopter also as
  a ratio to ex4; for ex4 with its recording also the flight's own thread (``thread_time``: the recording's
  chunks are compressed on a writer thread, which another core runs meanwhile);
* in-process command [s, wall and CPU]: ``fsr-fly ex4_geometric --in-process`` (30 s flight, recording and
  analysis) as a child process; its start-up to the first step (fsr-fly prints it);
* graph real-time factor (as fsr-fly reports it: the whole flight, and the stepping phase alone), CPU per
  step over all processes, node ready times (each node logs it), and whether every per-step topic of the
  recording holds every step (``/clock`` included);
* the graph's floor (:mod:`graph_floor`: stub nodes with the same topics, QoS, message sizes and recorder, no
  model work) and ours / floor;
* RotorPy 3.0 side by side (:mod:`rotorpy_side_by_side`, installed into a throwaway environment), as the
  ratio of its cost per step to fsr's in-process loop, measured in the same run.

The machine is shared: wall-clock figures are noisy, CPU figures less so. Targets are printed next to the
figures; nothing here is a test.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from graph_cpu import VENV_BIN, fly_graph  # noqa: E402

ROWS: list[tuple[str, str, float, float, str]] = []  # (figure, target, min, median, unit)


def add(name: str, target: str, values: list[float], unit: str) -> None:
    values = sorted(v for v in values if v == v) or [float("nan")]  # NaN: not reported by this version
    ROWS.append((name, target, values[0], statistics.median(values), unit))
    print(f"  {name}: min {values[0]:.3g} median {statistics.median(values):.3g} {unit}", flush=True)


def in_process_loop(repeat: int, seconds: float | None) -> None:
    from fsr_bringup.runner.in_process_flight import fly_in_process
    from fsr_sim.config.scenario import load_scenario

    medians = {}
    for name, target, ratio_target in (("ex4_geometric", "<= 2 / <= 10", None), ("ex5_voliro", "", "<= 2"),
                                       ("octo_ground_effect", "", "<= 2")):
        overrides = [] if seconds is None else [f"duration={seconds}"]
        scenario = load_scenario(name, overrides)
        for recorded in (False, True):
            values, flight_thread = [], []
            with tempfile.TemporaryDirectory() as tmp:
                fly_in_process(scenario, Path(tmp) / "warm.mcap", max_steps=20)
                for _ in range(repeat):
                    start, start_thread = time.process_time(), time.thread_time()
                    run = fly_in_process(scenario, Path(tmp) / "run.mcap" if recorded else None)
                    values.append(1e6 * (time.process_time() - start) / len(run.time))
                    flight_thread.append(1e6 * (time.thread_time() - start_thread) / len(run.time))
            what = "loop + recording" if recorded else "loop"
            add(f"in-process {what}, {name}", target if name == "ex4_geometric" else "", values, "us/step CPU")
            if recorded and name == "ex4_geometric":  # without the chunks compressed on the writer thread
                add(f"in-process {what}, {name}: the flight's thread", "", flight_thread, "us/step CPU")
            medians[(name, recorded)] = statistics.median(values)
            if ratio_target:
                ROWS.append((f"in-process {what}, {name} / ex4", ratio_target,
                             min(values) / medians[("ex4_geometric", recorded)],
                             medians[(name, recorded)] / medians[("ex4_geometric", recorded)], "x"))


def in_process_command(repeat: int, duration: float | None = None) -> None:
    walls, cpus, startups = [], [], []
    shorter = [] if duration is None else ["--duration", repr(duration)]  # --quick only: not the 30 s figure
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.monotonic()
            done = subprocess.run([str(VENV_BIN / "fsr-fly"), "ex4_geometric", "--in-process", "--out",
                                   f"{tmp}/ex4.mcap", *shorter], capture_output=True, text=True,
                                  env={**os.environ, "MPLBACKEND": "Agg"})
            walls.append(time.monotonic() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            found = re.search(r"first step ([0-9.]+) s after", done.stdout)
            if done.returncode != 0:
                raise SystemExit(f"fsr-fly --in-process failed:\n{done.stdout}\n{done.stderr}")
            startups.append(float(found.group(1)) if found else float("nan"))
    flown = "30 s" if duration is None else f"{duration:g} s"
    add(f"fsr-fly ex4_geometric --in-process ({flown}, recorded, analysed), wall", "<= 2.0", walls, "s")
    add("fsr-fly ex4_geometric --in-process, CPU", "-", cpus, "s CPU")
    add("in-process start-up to the first step", "<= 0.5", startups, "s")


GRAPH_CASES = {"ex4_geometric": ">= 1.6", "ex5_voliro": "", "octo_ground_effect": "", "three_vehicles": ""}


def graph(repeat: int, duration: float, names: list[str] | None = None) -> None:
    cases = [(name, GRAPH_CASES[name]) for name in (names or GRAPH_CASES)]
    ready: list[float] = []
    for name, target in cases:
        runs = [fly_graph(name, duration) for _ in range(repeat)]
        for run in runs:
            if run.exit_code != 0:
                print(f"  WARNING: fsr-fly {name} exited {run.exit_code}:\n{run.output[-2000:]}", flush=True)
            ready += list(run.ready.values())
        vehicles = 3 if name == "three_vehicles" else 1
        add(f"graph {name}: real-time factor (fsr-fly, whole flight)", target,
            [r.real_time_factor for r in runs], "x")
        add(f"graph {name}: stepping rate (start-up excluded)", target, [r.stepping_rate for r in runs], "x")
        add(f"graph {name}: CPU per vehicle-step (all processes)", "<= 1200" if name == "ex4_geometric" else "-",
            [1e6 * r.cpu_total / (r.sim_time * 1000 * vehicles) for r in runs], "us")
        incomplete = sorted({t for r in runs for t in r.incomplete_topics()})
        ROWS.append((f"graph {name}: topics missing steps", "none", len(incomplete), len(incomplete),
                     ", ".join(incomplete) or "none"))
        print(f"  {name}: incomplete topics: {incomplete or 'none'}", flush=True)
    add("graph: node ready (imports, parameters), all nodes of all runs", "<= 0.5", ready or [float("nan")], "s")


def floor(repeat: int, steps: int) -> None:
    from graph_floor import floor_run

    runs = [floor_run(steps) for _ in range(repeat)]
    add("graph floor (stub nodes, no model work, recorder): CPU per step", "-", [cpu for cpu, _ in runs], "us")
    add("graph floor: steps per second", "-", [rate for _, rate in runs], "steps/s")


def rotorpy(repeat: int) -> None:
    from rotorpy_side_by_side import fsr_us_per_step, rotorpy_python, rotorpy_us_per_step

    with tempfile.TemporaryDirectory() as scratch:
        python = rotorpy_python(Path(scratch) / "rotorpy-venv")
        fsr_us_per_step(0.01)
        theirs = [rotorpy_us_per_step(python, 5.0) for _ in range(repeat)]
        ours = [fsr_us_per_step(5.0) for _ in range(repeat)]
    add("RotorPy 3.0, 5 s quadrotor flight at 1 kHz", "-", theirs, "us/step wall")
    add("fsr in-process, the same flight (ex4, rotors, no recording)", "-", ours, "us/step wall")
    ROWS.append(("RotorPy / fsr", "-", min(theirs) / statistics.median(ours),
                 statistics.median(theirs) / statistics.median(ours), "x"))


def machine() -> str:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = ", ".join(f"{v:.1f}" for v in os.getloadavg())
    return f"{cpu}, {os.cpu_count()} CPUs, Python {platform.python_version()}, load average {load}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--duration", type=float, default=10.0, help="graph flights [s] (default 10)")
    parser.add_argument("--loop-seconds", type=float, help="in-process loop flights [s] (default: the scenario's)")
    parser.add_argument("--quick", action="store_true",
                        help="smoke pass: 1 run each, 1 s graph and loop flights, a 3 s in-process command, graph "
                             "ex4_geometric only (unless --graph-scenario)")
    parser.add_argument("--skip-graph", action="store_true")
    parser.add_argument("--graph-scenario", action="append", choices=tuple(GRAPH_CASES),
                        help="graph scenarios to fly (repeatable; default: all four)")
    parser.add_argument("--only", choices=("loop", "command", "graph", "floor", "rotorpy"), action="append",
                        help="run only these groups (repeatable)")
    args = parser.parse_args()
    if args.quick:
        args.repeat, args.duration, args.loop_seconds = 1, 1.0, 1.0
        args.graph_scenario = args.graph_scenario or ["ex4_geometric"]
    print(f"machine: {machine()}", flush=True)
    groups = set(args.only or (("loop", "command", "graph") if args.quick else
                               ("loop", "command", "graph", "floor", "rotorpy")))
    if args.skip_graph:
        groups.discard("graph")
    if "loop" in groups:
        in_process_loop(args.repeat, args.loop_seconds)
    if "command" in groups:
        in_process_command(args.repeat, 3.0 if args.quick else None)
    if "graph" in groups:
        graph(args.repeat, args.duration, args.graph_scenario)
    if "floor" in groups:
        floor(args.repeat, int(args.duration * 1000))
    if "rotorpy" in groups:
        rotorpy(args.repeat)
    print("\n| figure | target | min | median | unit |\n|---|---|---|---|---|")
    for name, target, low, middle, unit in ROWS:
        print(f"| {name} | {target} | {low:.3g} | {middle:.3g} | {unit} |")
    print(f"\nmachine: {machine()}; {args.repeat} run(s) each; graph flights {args.duration:g} s")


if __name__ == "__main__":
    main()
