"""What watching live costs an in-process flight (min and median of ``--repeat`` runs, us per step, wall).

    .venv/bin/python benchmarks/bench_live.py [--seconds 5] [--repeat 5]

Rows, each an ex4 flight of ``--seconds`` with its recording (:func:`fsr_bringup.runner.in_process_flight.
fly_in_process`, what ``fsr-fly --in-process`` runs):

* without ``--live``: the flight as before ``--live`` existed (its speed must not change);
* ``--live``, nobody connected: the recording's messages handed to the server too (only the held ones kept);
* ``--live``, Foxglove's WebSocket client (tests/viewer/live_client.cjs with the pinned npm packages, installed
  with ``npm ci`` into a temporary folder) subscribed to every topic: the cost of serving everything.

The live rows are flown at ``lockstep.real_time_factor`` 50, in chunks of 1000 steps, so the pacing never waits
(the loop and the serving are slower than 50x real time): their time is the work alone. The machine is shared:
wall-clock figures are noisy; nothing here is a test.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from fsr_bringup.live import serve
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_sim.config.scenario import load_scenario

VIEWER = Path(__file__).resolve().parents[1] / "tests" / "viewer"
UNPACED = 50.0  # real-time factor the live rows are paced at: never reached, so never waited for


def scenario(seconds: float, real_time_factor: float = 1.0):  # noqa: ANN201 - a checked Scenario
    return check_scenario(load_scenario("ex4_geometric", values={
        "duration": seconds, "lockstep.real_time_factor": real_time_factor})).scenario


def per_step_us(fly, repeat: int, steps: int) -> tuple[float, float]:  # noqa: ANN001 - a callable of nothing
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fly()
        times.append(time.perf_counter() - start)
    return 1e6 * min(times) / steps, 1e6 * statistics.median(times) / steps


def client(folder: Path, url: str, topics: list[str]) -> subprocess.Popen:
    """Foxglove's client subscribed to ``topics`` (every topic the server offers)."""
    topics = ",".join(topics)
    return subprocess.Popen(["node", str(folder / "live_client.cjs"), url, "--subscribe", topics, "--timeout", "600"],
                            stdout=subprocess.DEVNULL)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    steps = int(round(args.seconds * 1000)) + 1
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run.mcap"
        plain, live_scenario = scenario(args.seconds), scenario(args.seconds, UNPACED)
        fly_in_process(plain, out)  # warm: the compiled core loaded, the imports done
        rows = {"without --live": per_step_us(lambda: fly_in_process(plain, out), args.repeat, steps)}
        with serve(0) as live:
            fly_in_process(live_scenario, out, live=live)  # starts the server
            rows["--live, nobody connected"] = per_step_us(lambda: fly_in_process(live_scenario, out, live=live),
                                                           args.repeat, steps)
            folder = Path(tmp) / "viewer"
            folder.mkdir()
            for path in (VIEWER / "package.json", VIEWER / "package-lock.json", VIEWER / "live_client.cjs"):
                shutil.copy(path, folder / path.name)
            subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=folder, check=True,
                           timeout=300)
            watcher = client(folder, live.endpoint.url, sorted(live.channels))
            try:
                deadline = time.monotonic() + 30
                channels = list(live.channels.values())
                while not all(channel.has_sinks() for channel in channels) and time.monotonic() < deadline:
                    time.sleep(0.05)
                rows["--live, a client on every topic"] = per_step_us(
                    lambda: fly_in_process(live_scenario, out, live=live), args.repeat, steps)
            finally:
                watcher.kill()
                watcher.wait(timeout=30)
    print(f"ex4 in-process, {args.seconds:g} s flights with their recording, us per step (min / median of "
          f"{args.repeat}):")
    for name, (low, median) in rows.items():
        print(f"  {name:<34} {low:7.1f} / {median:7.1f}")


if __name__ == "__main__":
    main()
