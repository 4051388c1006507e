"""Fly ``fsr-fly`` (the node graph) as a child and measure it: the real-time factor fsr-fly reports, the CPU
time of every process of the run (fsr-fly and each node, from ``/proc/<pid>/stat``, sampled while they run)
and the total from ``getrusage(RUSAGE_CHILDREN)``.

    .venv/bin/python benchmarks/graph_cpu.py ex4_geometric --duration 10

Used by :mod:`run_all` and :mod:`bench_scaling`.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from fsr_sim.contract import topic_named

VENV_BIN = Path(sys.executable).parent
CLOCK_TICKS = os.sysconf("SC_CLK_TCK")
RTF = re.compile(r"real-time factor ([0-9.]+)")
NODE_NAMES = ("simulator", "controller", "estimator", "fsr-record", "fsr-fly")
WATCHER_MODULE = "fsr_bringup.runner.watcher_node"  # fsr-fly's watcher process: python -m WATCHER_MODULE


@dataclass
class GraphRun:
    """One measured flight of the graph."""

    scenario: str
    sim_time: float
    wall_time: float
    real_time_factor: float
    cpu_total: float  # s: fsr-fly and every node
    cpu_by_node: dict[str, float] = field(default_factory=dict)  # s, per node kind (summed over namespaces)
    exit_code: int = 0
    output: str = ""
    stepping_rate: float = float("nan")  # fsr-fly's "stepping at X x real time" (start-up excluded)
    ready: dict[str, float] = field(default_factory=dict)  # node log name -> s from its start to ready
    counts: dict[str, int] = field(default_factory=dict)  # recorded topic -> messages (from the recorder's log)

    def incomplete_topics(self) -> list[str]:
        """Per-step topics of the recording that do not hold every step (``/clock`` included)."""
        steps = round(self.sim_time * 1000) + 1
        per_step = [t for t, n in self.counts.items() if n > 2 and (topic := topic_named(t)) and topic.per_step]
        return [t for t in per_step if self.counts[t] != steps]


def _descendants(pid: int) -> list[int]:
    children: dict[int, list[int]] = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as stat:
                fields = stat.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        children.setdefault(int(fields[1]), []).append(int(entry))
    found, todo = [], [pid]
    while todo:
        current = todo.pop()
        found.append(current)
        todo.extend(children.get(current, []))
    return found


def _cpu_and_name(pid: int) -> tuple[float, str] | None:
    try:
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
        with open(f"/proc/{pid}/cmdline", "rb") as cmdline:
            argv = cmdline.read().split(b"\0")
    except OSError:
        return None
    cpu = (int(fields[11]) + int(fields[12])) / CLOCK_TICKS  # utime + stime
    words = [Path(a.decode(errors="replace")).name for a in argv[:3]]
    if WATCHER_MODULE in words:
        return cpu, "watcher"
    name = next((n for n in NODE_NAMES for w in words if w == n), words[0] if words else "?")
    return cpu, name


def fly_graph(scenario: str, duration: float | None = None, extra: list[str] | None = None) -> GraphRun:
    """Fly ``scenario`` (a scenario or fleet) with ``fsr-fly`` (no analysis) and measure it."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    with tempfile.TemporaryDirectory(prefix="fsr_bench_") as tmp:
        command = [str(VENV_BIN / "fsr-fly"), scenario, "--quiet", "--no-analysis", "--out", f"{tmp}/run.mcap"]
        if duration is not None:
            command += ["--duration", repr(duration)]
        command += extra or []
        start = time.monotonic()
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        peak: dict[int, tuple[float, str]] = {}
        while process.poll() is None:
            for pid in _descendants(process.pid):
                sample = _cpu_and_name(pid)
                if sample is not None:
                    name = sample[1] if sample[1] in NODE_NAMES else peak.get(pid, (0.0, sample[1]))[1]
                    peak[pid] = (sample[0], name)
            time.sleep(0.2)
        output = process.stdout.read()
        wall = time.monotonic() - start
        ready, counts = {}, {}
        for log in Path(tmp, "run", "logs").glob("*.log"):
            text = log.read_text(errors="replace")
            found = re.search(r"ready ([0-9.]+) s after the process started", text)
            if found and log.stem != "flight_watcher":  # the nodes' figure; the watcher is fsr-fly's own
                ready[log.stem] = float(found.group(1))
            if log.stem == "recorder":
                counts = {m.group(1): int(m.group(2)) for m in re.finditer(r"^\s+(/\S+): (\d+)$", text, re.M)}
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    total = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    by_node: dict[str, float] = {}
    for cpu, name in peak.values():
        by_node[name] = by_node.get(name, 0.0) + cpu
    match = RTF.findall(output)
    sim = re.findall(r"simulated ([0-9.]+) s", output)
    stepping = re.findall(r"stepping at ([0-9.]+)x real time", output)
    return GraphRun(scenario, float(sim[-1]) if sim else float("nan"), wall,
                    float(match[-1]) if match else float("nan"), total, by_node, process.returncode, output,
                    float(stepping[-1]) if stepping else float("nan"), ready, counts)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("scenario")
    parser.add_argument("--duration", type=float)
    args = parser.parse_args()
    run = fly_graph(args.scenario, args.duration)
    steps = run.sim_time * 1000.0
    print(f"{run.scenario}: RTF {run.real_time_factor:.2f} (stepping {run.stepping_rate:.2f}), exit "
          f"{run.exit_code}, CPU {run.cpu_total:.2f} s ({1e6 * run.cpu_total / steps:.0f} us per step)")
    print(f"  ready: {run.ready}; incomplete topics: {run.incomplete_topics() or 'none'}")
    for name, cpu in sorted(run.cpu_by_node.items(), key=lambda item: -item[1]):
        print(f"  {name:12s} {cpu:6.2f} s  {1e6 * cpu / steps:6.0f} us/step")


if __name__ == "__main__":
    main()
