"""The 1 kHz lockstep over a network vs on one host: real-time factor and time per step (round trip).

Flies ``ex4_geometric`` with ``fsr-fly`` (simulator, controller, estimator, recorder) in these setups:

* ``one host``: every node on this host, fsr-fly's defaults (localhost discovery, shared memory);
* ``one host, UDP only``: the same with ``FASTDDS_BUILTIN_TRANSPORTS=UDPv4`` (no shared memory);
* ``3 hosts (netns)``: simulator + recorder, controller and estimator each in a network namespace of its own,
  joined by a bridge (``tests/harness/netns.py``'s ``NetLab``), ``fsr-fly --network --nodes ...`` on each;
* ``3 hosts + X ms``: the same with ``tc netem`` delaying every packet leaving each host by X/2 ms (a link
  with round-trip time X ms), if ``--delay-ms`` is given and the kernel has netem.

Each number comes from the simulator's own end-of-flight line (steps, stepping wall time, real-time factor
of the stepping phase, start-up excluded): time per step = wall / steps is one lockstep cycle, i.e. state
out, command back (the round trip) plus the step's own work. Several runs per setup; min and median are
printed, because the machine may be shared (other processes' load makes single runs noisy).

Usage: ``.venv/bin/python benchmarks/bench_network.py [--runs 3] [--duration 3] [--delay-ms 1]`` (root;
the namespace setups are skipped with the reason where namespaces cannot be made).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the network lab: tests/harness (not installed)
from harness.netns import NetLab, network_environment, unavailable_reason  # noqa: E402

FLY = str(Path(sys.executable).parent / "fsr-fly")
FINISHED = re.compile(r"finished: .*\((\d+) steps, t = ([\d.]+) s in ([\d.]+) s wall")
SIDES = (("sim", "simulator,recorder"), ("ctl", "controller"), ("est", "estimator"))


def stepping(log: Path) -> tuple[int, float]:
    """(steps, stepping wall time [s]) from the simulator's log."""
    match = FINISHED.search(log.read_text(errors="replace"))
    if match is None:
        raise RuntimeError(f"no end-of-flight line in {log}:\n{log.read_text(errors='replace')[-2000:]}")
    return int(match.group(1)), float(match.group(3))


def fly_one_host(work: Path, duration: float, udp_only: bool) -> tuple[int, float]:
    env = {**os.environ, "MPLBACKEND": "Agg"}
    if udp_only:
        env["FASTDDS_BUILTIN_TRANSPORTS"] = "UDPv4"
    out = work / "one.mcap"
    subprocess.run([FLY, "ex4_geometric", "--duration", str(duration), "--quiet", "--no-analysis", "--out", str(out)],
                   env=env, check=True, timeout=600, stdout=subprocess.DEVNULL)
    return stepping(out.with_suffix("") / "logs" / "simulator.log")


def fly_namespaces(work: Path, duration: float, delay_ms: float) -> tuple[int, float]:
    with acquire_domain(TEST_RANGE) as lease, NetLab([host for host, _ in SIDES]) as lab:
        if delay_ms > 0:
            for host, _ in SIDES:  # half the round trip on each host's way out
                subprocess.run(lab.command(host, ["tc", "qdisc", "add", "dev", "eth0", "root", "netem", "delay",
                                                  f"{delay_ms / 2}ms"]), check=True, capture_output=True)
        env = network_environment(lease.domain_id)
        processes = []
        try:
            for host, nodes in SIDES:
                argv = [FLY, "ex4_geometric", "--duration", str(duration), "--network", "--domain-id",
                        str(lease.domain_id), "--nodes", nodes, "--quiet", "--no-analysis",
                        "--out", str(work / host / f"{host}.mcap")]
                processes.append(lab.popen(host, argv, env=env, stdout=subprocess.DEVNULL,
                                           stderr=open(work / f"{host}.err", "w")))
            for (host, _), process in zip(SIDES, processes, strict=True):
                if process.wait(timeout=600) != 0:
                    raise RuntimeError(f"{host} exited with {process.returncode}: {(work / f'{host}.err').read_text()}")
        finally:
            for process in processes:
                if process.poll() is None:
                    process.kill()
                    process.wait()
    return stepping(work / "sim" / "sim" / "logs" / "simulator.log")


def netem_available() -> str | None:
    """None if ``tc ... netem`` works in a namespace here, else why not."""
    if shutil.which("tc") is None:
        return "no 'tc' command"
    with NetLab(["probe"]) as lab:
        run = subprocess.run(lab.command("probe", ["tc", "qdisc", "add", "dev", "eth0", "root", "netem", "delay",
                                                   "1ms"]), capture_output=True, text=True)
    return None if run.returncode == 0 else f"netem refused: {run.stderr.strip()}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds per flight")
    parser.add_argument("--delay-ms", type=float, action="append", default=[],
                        help="also fly the 3 namespaces over a link with this round-trip time (repeatable)")
    args = parser.parse_args()
    setups = [("one host", lambda w: fly_one_host(w, args.duration, False)),
              ("one host, UDP only", lambda w: fly_one_host(w, args.duration, True))]
    reason = unavailable_reason()
    if reason is None:
        setups.append(("3 hosts (netns, bridge)", lambda w: fly_namespaces(w, args.duration, 0.0)))
        netem = netem_available() if args.delay_ms else None
        for delay in args.delay_ms:
            if netem is None:
                setups.append((f"3 hosts + {delay:g} ms RTT", lambda w, d=delay: fly_namespaces(w, args.duration, d)))
            else:
                print(f"skipping the {delay:g} ms link: {netem}")
    else:
        print(f"skipping the namespace setups: {reason}")
    load = os.getloadavg()
    print(f"ex4_geometric, {args.duration:g} s at 1 kHz, {args.runs} runs per setup; load average {load[0]:.1f} "
          f"on {os.cpu_count()} CPUs at the start (shared machine: compare min and median, not single runs)\n")
    print("| setup | RTF best | RTF median | ms per step min | ms per step median |")
    print("|---|---|---|---|---|")
    for name, fly in setups:
        per_step = []
        for run in range(args.runs):
            with tempfile.TemporaryDirectory(prefix="fsr-bench-net-") as work:
                steps, wall = fly(Path(work))
            per_step.append(wall / steps)
            print(f"  {name}, run {run + 1}: {steps} steps in {wall:.2f} s", file=sys.stderr)
        best, median = min(per_step), statistics.median(per_step)
        print(f"| {name} | {1e-3 / best:.2f} | {1e-3 / median:.2f} | {best * 1e3:.3f} | {median * 1e3:.3f} |",
              flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
