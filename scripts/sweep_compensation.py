"""Stability of the disturbance compensation over the observer's filter: c0 x r, in-process, report gains.

    .venv/bin/python scripts/sweep_compensation.py [--c0 1,5,10,25,50,100] [--r 1:5] [--json OUT]

Flies ``ex3_estimation`` (8 s: its waypoint in 5 s instead of 10 s, 3 s hold) and ``wind_rejection`` (9.5 s: the
ramped gust, 1 s of the sinusoidal wind) with ``controller.compensation: estimate`` for each ``(c0, r)`` and
prints a Markdown table:

* steady error [m]: ex3, the largest position error over the last 1 s (7-8 s); wind, the largest over the last 0.5 s
  of the gust (6.5-7.0 s, the gust at full strength);
* peak error [m]: the largest position error of the flight;
* diverged: the flight ended as a divergence, or its position error exceeded ``DIVERGED_M``.

Each flight is deterministic, so the table is the same on every machine (to rounding).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from fsr_bringup.api import simulate
from fsr_sim.contract import DIVERGED

DIVERGED_M = 1.0  # m: a position error beyond this counts as a divergence
CASES = {
    "ex3_estimation": {"duration": 8.0, "steady": (7.0, 8.0), "set": {"trajectory.waypoints.0.duration": 5.0}},
    "wind_rejection": {"duration": 9.5, "steady": (6.5, 7.0), "set": {}},
}


def fly(name: str, c0: float, r: int) -> dict[str, float | bool | str]:
    """One compensated flight: steady and peak position error [m], divergence."""
    case = CASES[name]
    try:
        run = simulate(name, set={"controller.compensation": "estimate", "estimator.c0": c0, "estimator.r": r,
                                  **case["set"]}, duration=case["duration"])
    except ValueError as error:  # e.g. a filter the observer refuses
        return {"steady_m": float("nan"), "peak_m": float("nan"), "diverged": True, "note": str(error)}
    error = np.linalg.norm(run.position - run.reference_position, axis=1)
    start, end = case["steady"]
    window = (run.time >= start) & (run.time <= end)
    steady = float(error[window].max()) if window.any() else float("nan")
    peak = float(error.max())
    diverged = run.end_reason == DIVERGED or not np.isfinite(peak) or peak > DIVERGED_M
    return {"steady_m": steady, "peak_m": peak, "diverged": bool(diverged), "note": run.reason if diverged else ""}


def parse_list(text: str, kind: type) -> list:
    if ":" in text:
        low, high = (int(v) for v in text.split(":"))
        return list(range(low, high + 1))
    return [kind(v) for v in text.split(",")]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--c0", default="1,5,10,25,50,100")
    parser.add_argument("--r", default="1:5")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    c0s, rs = parse_list(args.c0, float), parse_list(args.r, int)
    results: dict[str, dict[str, dict]] = {name: {} for name in CASES}
    start = time.perf_counter()
    for name in CASES:
        for c0 in c0s:
            for r in rs:
                results[name][f"{c0:g},{r}"] = fly(name, c0, r)
    print("| c0 | r | ex3 steady [m] | ex3 peak [m] | wind steady [m] | wind peak [m] | diverged |")
    print("|---|---|---|---|---|---|---|")
    for c0 in c0s:
        for r in rs:
            a, b = results["ex3_estimation"][f"{c0:g},{r}"], results["wind_rejection"][f"{c0:g},{r}"]
            diverged = ", ".join(n for n, x in (("ex3", a), ("wind", b)) if x["diverged"]) or "no"
            print(f"| {c0:g} | {r} | {a['steady_m']:.2e} | {a['peak_m']:.2e} | {b['steady_m']:.2e} | "
                  f"{b['peak_m']:.2e} | {diverged} |")
    print(f"\n{len(c0s) * len(rs) * len(CASES)} flights in {time.perf_counter() - start:.0f} s")
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()
