"""Scaling of the node graph with the number of vehicles: 1, 2, 4 and 8 quadrotors at 1 kHz (the fleet
mechanism of ``fsr-fly``: per vehicle a simulator, a controller and an estimator; one recorder).

    .venv/bin/python benchmarks/bench_scaling.py [--duration 3] [--repeat 2] [--out docs/benchmarks]

Writes ``scaling.md`` (a Markdown table: real-time factor as fsr-fly reports it, the stepping rate, CPU per
vehicle-step over all processes; min and median of the runs) and ``scaling.png`` (both against the vehicle
count), and prints the table. The vehicles are ``ex4_geometric`` with rotor actuation, side by side.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent))

from graph_cpu import fly_graph  # noqa: E402
from run_all import machine  # noqa: E402

COUNTS = (1, 2, 4, 8)


def fleet_file(directory: Path, count: int, duration: float) -> Path:
    fleet = [{"namespace": f"/uav{i + 1}", "scenario": "ex4_geometric",
              "set": [f"duration={duration}", "actuation=rotors", f"initial_state.position=[0.0, {3.0 * i}, -1.0]",
                      f"trajectory.waypoints=[{{position: [1.0, {3.0 * i + 1.0}, -3.0], duration: {duration}}}]"]}
             for i in range(count)]
    path = directory / f"fleet_{count}.yaml"
    path.write_text(yaml.safe_dump({"name": f"scaling_{count}", "fleet": fleet}, sort_keys=False), encoding="utf-8")
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds per flight")
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--counts", type=int, nargs="+", default=list(COUNTS))
    parser.add_argument("--out", type=Path, default=Path("docs/benchmarks"))
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory(prefix="fsr_scaling_") as tmp:
        for count in args.counts:
            runs = [fly_graph(str(fleet_file(Path(tmp), count, args.duration))) for _ in range(args.repeat)]
            failed = [r for r in runs if r.exit_code != 0]
            if failed:
                raise SystemExit(f"{count} vehicles: fsr-fly failed:\n{failed[0].output}")
            rtf = sorted(r.real_time_factor for r in runs)
            stepping = sorted(r.stepping_rate for r in runs)
            cpu = sorted(1e6 * r.cpu_total / (r.sim_time * 1000 * count) for r in runs)
            rows.append((count, rtf, stepping, cpu))
            print(f"{count} vehicle(s): RTF {rtf}, stepping {stepping}, CPU/vehicle-step {cpu}", flush=True)
    header = ("| vehicles | real-time factor min / median | stepping rate min / median "
              "| CPU per vehicle-step [us] min / median |\n|---|---|---|---|")
    lines = [header] + [
        f"| {count} | {rtf[0]:.2f} / {statistics.median(rtf):.2f} | {st[0]:.2f} / {statistics.median(st):.2f} "
        f"| {cpu[0]:.0f} / {statistics.median(cpu):.0f} |" for count, rtf, st, cpu in rows]
    table = "\n".join(lines)
    note = (f"\n\n{args.duration:g} s flights at 1 kHz, {args.repeat} run(s) each; machine: {machine()}.\n")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scaling.md").write_text(table + note, encoding="utf-8")
    plot(rows, args.out / "scaling.png")
    print(table + note)
    print(f"wrote {args.out / 'scaling.md'} and {args.out / 'scaling.png'}")


def plot(rows: list, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    counts = [r[0] for r in rows]
    fig, (left, right) = plt.subplots(1, 2, figsize=(7.0, 2.8), layout="constrained")
    left.plot(counts, [statistics.median(r[1]) for r in rows], "o-", label="whole flight")
    left.plot(counts, [statistics.median(r[2]) for r in rows], "s--", label="stepping")
    left.set(xlabel="vehicles", ylabel="real-time factor (median)", xscale="log", xticks=counts, xticklabels=counts)
    left.legend()
    right.plot(counts, [statistics.median(r[3]) for r in rows], "o-")
    right.set(xlabel="vehicles", ylabel="CPU per vehicle-step [us]", xscale="log", xticks=counts,
              xticklabels=counts)
    for ax in (left, right):
        ax.grid(alpha=0.4)
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
