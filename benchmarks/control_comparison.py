"""The laws compared under real conditions (docs/control.md, "The laws compared"): one sweep per law x condition x
flight, ``--seeds`` seeded flights each, and one table of the position error against the true state (the
sweep's metrics: RMS and peak of ``|p - p_d|``, min / median over the seeds that finished) and the fraction that
diverged, with a figure of the median RMS.

    .venv/bin/python benchmarks/control_comparison.py --out runs/control_comparison          # 20 seeds
    .venv/bin/python benchmarks/control_comparison.py --seeds 2 --duration 3 --flights step_disturbance  # smoke
    .venv/bin/python benchmarks/control_comparison.py --shipped   # the built-in rotor scenarios, onboard + 30 ms

Laws: the geometric law with the report's profile (``report``: measured feed-forward, the report's gains), with
the ``flight`` profile (``flight``: reference feed-forward, designed gains, the aerodynamics model), the same with
the observer's estimate compensated (``flight+comp``: ``controller.compensation: estimate``, the estimator
switched on where the scenario has none) and INDI (``indi``, the ``flight`` profile's gains). Conditions,
cumulative as listed (:data:`CONDITIONS`), and one more for the targets: onboard sensors with the vehicle's own
motor and Dryden turbulence.

Where a law needs what a condition lacks it gets it, and the table says so: INDI flies on an IMU, which the
``mocap`` preset has none of - it gets the ``onboard`` preset's BMI088 (a vehicle flown in a motion-capture hall
carries one). Turbulence pushes through the vehicle's aerodynamics; ``quadrotor_ex4`` has none, so its flights
get ``ex3_estimation_noisy``'s parasitic drag under Dryden.

Seeds: each flight's random sources - the sensor stages' seeds and the Dryden entry's, the keys fsr-tune's
conditions seed (:func:`fsr_bringup.tuning.conditions.seed_keys`) - are sampled per flight, each its own
integer in ``[0, 2^32)`` (``numpy.random.default_rng(--seed)``); every law of a flight and condition flies the
same draws (common random numbers); the IMU's seed only where the condition has an IMU. Nothing here is a test:
the numbers are what the flights measure.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from fsr_bringup import sweep
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_bringup.tuning.conditions import MAX_SEED, scenario_seed_keys
from fsr_sim.config.scenario import load_scenario, load_vehicle_for
from fsr_sim.config.sensor_sections import IMU_SECTION, PRESETS
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.contract import FINISHED

FLIGHTS = {  # the flight and the values that make it the comparison's
    "step_disturbance": {},
    "ex4_geometric": {"actuation": "rotors"},
    "figure8_hummingbird": {},
    "race_hummingbird": {},
}
LAWS = {
    "report": {"controller.type": "geometric", "controller.profile": "report"},
    "flight": {"controller.type": "geometric", "controller.profile": "flight"},
    "flight+comp": {"controller.type": "geometric", "controller.profile": "flight",
                       "controller.compensation": "estimate", "estimator.enabled": True},
    "indi": {"controller.type": "indi", "controller.profile": "flight"},
}
MOTOR_S = 0.03  # s: the onboard conditions' motor lag
DRYDEN = {"kind": "dryden", "wind_speed": 7.7, "altitude": 6.0, "seed": 0}  # light turbulence (7.7 m/s at 6 m)
MASS_ERROR = 0.2  # the true mass 20 % above the model's
QUADROTOR_DRAG = [0.03, 0.03, 0.06]  # N s^2/m^2: ex3_estimation_noisy's, for a vehicle without aerodynamics


@dataclass(frozen=True)
class Condition:
    name: str
    preset: str
    motor: bool = False  # MOTOR_S instead of the vehicle's own lag
    dryden: bool = False
    mass_error: bool = False


CONDITIONS = (
    Condition("ideal", "ideal"),
    Condition("mocap", "mocap"),
    Condition("onboard", "onboard"),
    Condition("onboard+30ms", "onboard", motor=True),
    Condition("+Dryden", "onboard", motor=True, dryden=True),
    Condition("+20% mass", "onboard", motor=True, dryden=True, mass_error=True),
    Condition("onboard+Dryden (own motor)", "onboard", dryden=True),
)


REPORT_EXERCISES = ("ex3_estimation", "ex3_estimation_noisy", "ex4_geometric", "ex5_voliro")
AS_SHIPPED = "as shipped"  # the law of --shipped: the scenario's own controller section


def flight_values(flight: str, law: str, condition: Condition) -> tuple[dict[str, Any], list[str]]:
    """The ``set`` values of one sweep and the notes on what the law or the vehicle was given."""
    given = FLIGHTS.get(flight, {})
    base = load_scenario(flight, values=given)
    vehicle = load_vehicle_for(base)
    values: dict[str, Any] = {**given, **LAWS.get(law, {}), "sensors.preset": condition.preset}
    notes = []
    law_type = LAWS.get(law, {}).get("controller.type")
    if law_type == "indi" and IMU_SECTION not in PRESETS[condition.preset]:
        values[f"sensors.{IMU_SECTION}"] = dict(PRESETS["onboard"][IMU_SECTION])
        notes.append("INDI under mocap: the onboard preset's IMU (BMI088)")
    if condition.motor:
        values["plant.rotor_time_constant"] = MOTOR_S
    if condition.dryden:
        disturbances = list(base.data.get("disturbances") or [])
        values["disturbances"] = [*disturbances, dict(DRYDEN)]
        if not vehicle.has_aerodynamics:
            values["plant.drag_coefficients"] = list(QUADROTOR_DRAG)
            notes.append(f"{vehicle.name} under Dryden: parasitic drag {QUADROTOR_DRAG} N s^2/m^2")
    if condition.mass_error:
        values["plant.mass"] = (1.0 + MASS_ERROR) * vehicle.mass
    return values, notes


@dataclass
class Cell:
    """One law x condition x flight over the seeds: RMS and peak position error [m] of the flights that finished
    (min, median), how many diverged, or why it was not flown."""

    rms: tuple[float, float] = (math.nan, math.nan)
    peak: tuple[float, float] = (math.nan, math.nan)
    diverged: int = 0
    flights: int = 0
    skipped: str = ""

    def text(self) -> str:
        if self.skipped:
            return f"n/a ({self.skipped})"
        finished = self.flights - self.diverged
        errors = "-" if finished == 0 else (f"{_num(self.rms[0])} / {_num(self.rms[1])}; "
                                            f"{_num(self.peak[0])} / {_num(self.peak[1])}")
        return f"{errors}; {self.diverged}/{self.flights}"


def _num(value: float) -> str:
    return f"{value:.2g}" if value < 0.01 else f"{value:.3f}"


def measure(flight: str, law: str, condition: Condition, seeds: int, duration: float | None, seed: int,
            workers: int | None) -> tuple[Cell, list[str], Any]:
    """Fly one sweep: ``seeds`` flights with the seed keys sampled; the cell, the notes and the sweep's rows."""
    try:
        values, notes = flight_values(flight, law, condition)
        base = load_scenario(flight, values=values)
        check_scenario(base)
    except ConfigError as error:
        return Cell(skipped=str(error)), [], None
    keys = scenario_seed_keys(base)
    # each seed key held as an integer first, so that its draws are rounded to integers
    base = load_scenario(flight, values={**values, **dict.fromkeys(keys, 0)})
    table = sweep(base, sample=dict.fromkeys(keys, f"uniform:0:{MAX_SEED}"), n=seeds, seed=seed, duration=duration,
                  workers=workers)
    finished = table[table["end_reason"] == FINISHED]
    invalid = table[table["end_reason"] == "invalid"]
    table.insert(0, "law", law)
    table.insert(0, "condition", condition.name)
    table.insert(0, "scenario", flight)
    if len(invalid):
        return Cell(skipped=str(invalid["end_detail"].iloc[0])), notes, table
    cell = Cell(diverged=int((table["end_reason"] != FINISHED).sum()), flights=len(table))
    if len(finished):
        rms, peak = list(finished["position_error_rms_m"]), list(finished["position_error_peak_m"])
        cell.rms = (min(rms), statistics.median(rms))
        cell.peak = (min(peak), statistics.median(peak))
    return cell, notes, table


def markdown(cells: dict[tuple[str, str, str], Cell], flights: list[str], laws: list[str],
             conditions: list[Condition]) -> str:
    header = "| flight | condition | " + " | ".join(f"`{law}`" for law in laws) + " |"
    lines = [header, "|" + "---|" * (2 + len(laws))]
    for flight in flights:
        for condition in conditions:
            row = [cells[(flight, law, condition.name)].text() for law in laws]
            lines.append(f"| `{flight}` | {condition.name} | " + " | ".join(row) + " |")
    return "\n".join(lines)


def figure(cells: dict[tuple[str, str, str], Cell], flights: list[str], laws: list[str],
           conditions: list[Condition], path: Path) -> None:
    """Median RMS per law over the conditions, a panel per flight, log scale; a cell whose every flight diverged
    is an ``x`` on the panel's top edge."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    columns = min(2, len(flights))
    rows = math.ceil(len(flights) / columns)
    fig, axes = plt.subplots(rows, columns, figsize=(6.0 * columns, 4.2 * rows), squeeze=False, layout="constrained")
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, flight in zip(axes.flat, flights, strict=False):
        lost = []
        for i, law in enumerate(laws):
            x = [k + 0.06 * (i - (len(laws) - 1) / 2) for k in range(len(conditions))]
            cell = [cells[(flight, law, c.name)] for c in conditions]
            colour = colours[i % len(colours)]
            ax.plot(x, [c.rms[1] for c in cell], marker="o", color=colour, label=law)
            lost += [(k, colour) for k, c in zip(x, cell, strict=True) if not c.skipped and c.diverged == c.flights]
        ax.set_yscale("log")
        top = ax.get_ylim()[1]
        for k, colour in lost:
            ax.plot([k], [top], "x", color=colour, markersize=9, clip_on=False)
        ax.set_ylim(top=top)
        ax.set_xticks(range(len(conditions)), [c.name for c in conditions], rotation=30, ha="right", fontsize=8)
        ax.set_title(flight, fontsize=10)
        ax.set_ylabel("median RMS position error [m]", fontsize=9)
        ax.grid(True, which="major", alpha=0.3)
    for ax in list(axes.flat)[len(flights):]:
        ax.set_visible(False)
    axes.flat[0].legend(fontsize=8, title="x on top: every flight diverged", title_fontsize=7)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def shipped_rotor_scenarios() -> list[str]:
    """The built-in scenarios on rotors other than the report's exercises."""
    return [name for name in builtin_names("scenarios") if name not in REPORT_EXERCISES
            and load_scenario(name).data.get("actuation") == "rotors"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=20, help="flights per law x condition x flight (default 20)")
    parser.add_argument("--duration", type=float, default=None, help="flight duration [s] (default: each scenario's)")
    parser.add_argument("--flights", nargs="+", choices=list(FLIGHTS), default=list(FLIGHTS))
    parser.add_argument("--laws", nargs="+", choices=list(LAWS), default=list(LAWS))
    names = [c.name for c in CONDITIONS]
    parser.add_argument("--conditions", nargs="+", choices=names, default=names)
    parser.add_argument("--seed", type=int, default=0, help="seeds the sampled seed keys (default 0)")
    parser.add_argument("--workers", type=int, default=None, help="worker processes (default: every core)")
    parser.add_argument("--shipped", action="store_true",
                        help="instead: every built-in rotor scenario but the report's exercises, as shipped (its own "
                             "law), under onboard sensors and a 30 ms motor")
    parser.add_argument("--out", type=Path, default=Path("runs/control_comparison"))
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error(f"--seeds: must be >= 1, got {args.seeds}")
    if args.shipped:
        args.flights, args.laws = shipped_rotor_scenarios(), [AS_SHIPPED]
        args.conditions = ["onboard+30ms"]
    conditions = [c for c in CONDITIONS if c.name in args.conditions]
    cells: dict[tuple[str, str, str], Cell] = {}
    notes: set[str] = set()
    rows = []
    start = time.perf_counter()
    for flight in args.flights:
        for condition in conditions:
            for law in args.laws:
                cell, said, flown = measure(flight, law, condition, args.seeds, args.duration, args.seed,
                                            args.workers)
                cells[(flight, law, condition.name)] = cell
                notes.update(said)
                if flown is not None:
                    rows.append(flown)
                print(f"[{time.perf_counter() - start:6.0f} s] {flight} | {condition.name} | {law}: {cell.text()}",
                      file=sys.stderr, flush=True)
    table = markdown(cells, args.flights, args.laws, conditions)
    legend = (f"Each cell: RMS min / median; peak min / median [m] of the flights that finished (a flight that flies "
              f"away without touching the ground finishes: tens of metres); diverged / flown ({args.seeds} seeds, "
              f"duration {args.duration if args.duration else 'as the scenario'}).")
    text = "\n".join([table, "", legend, *(f"* {note}" for note in sorted(notes))])
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "shipped_onboard" if args.shipped else "control_comparison"
    (args.out / f"{stem}.md").write_text(text + "\n", encoding="utf-8")
    if rows:
        import pandas as pd

        pd.concat(rows).to_csv(args.out / f"{stem}_flights.csv")
    if not args.shipped:
        figure(cells, args.flights, args.laws, conditions, args.out / f"{stem}.png")
    print(text)
    print(f"wrote {stem}.md, {stem}_flights.csv{'' if args.shipped else f' and {stem}.png'} into {args.out} in "
          f"{time.perf_counter() - start:.0f} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
