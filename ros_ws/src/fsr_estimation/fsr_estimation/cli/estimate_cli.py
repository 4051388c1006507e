"""``fsr-estimate``: run the momentum observer over a flight log for a sweep of (c0, r) and measure it.

Prints Markdown tables (settling times to the millisecond, MAE over the whole log to 4 decimals, max error
after ``--after``, dm and m_real to 3 decimals); ``--json`` writes the numbers, ``--plots`` the report's
figures. A truncated MCAP recording (no footer) is refused (exit 2, one line with the time it covers) unless
``--allow-truncated`` is given, which prints that line as a warning and estimates over the part that is there.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fsr_estimation.estimator.metrics import CHANNELS, SETTLING_DEFINITIONS, SweepResult, sweep
from fsr_estimation.estimator.observer import ObserverModel
from fsr_estimation.io.flight_log import CSV_COLUMNS_HELP, FlightLog, FlightLogError, load_flight_log
from fsr_sim.cli.arguments import exit_codes_text
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_OK

CHANNEL_LABELS = {"fx": "f_x", "fy": "f_y", "fz": "f_z", "tx": "tau_x", "ty": "tau_y", "tz": "tau_z"}

DESCRIPTION = """\
Momentum-based external wrench estimation (docs/model.md section 3.8) over a flight log, for every (c0, r) pair.

The estimate w_hat = [f_e; tau_e] has the force in the world NED frame [N] and the torque in Euler-angle
(ZYX eta) coordinates [N m], as in the report; --truth is compared with w_hat in that same frame (the
report uses --truth 1,1,0,0,0,-0.4). The tables show the channels whose true value is not zero (a zero
has no 3 % band); --json holds all six (null where undefined).

LOG formats: .mat (the report's layout: attitude, attitude_vel, linear_vel, thrust, tau, each with .time and
.signals.values), .mcap (fsr recordings: odom + wrench_cmd paired by header stamp), .csv.
{csv}
"""

EPILOG = """\
settling: 'standard' = the time after which |error| stays within 3 % of |truth| to the end of the log;
'report' = the report's convergence time (first k whose moving max of the signed error over [k - 2 s, k + 4 s]
is within 3 %, reported as k T_s), which reproduces its Table 3 (docs/model.md, section 5: the report this
project started from and where fsr differs from it).
example: fsr-estimate examples/ex3_flight_log.mcap --mass 1.5 --inertia 1.2416,1.2416,2.4832 --c0 10 --r 1:5
         --truth 1,1,0,0,0,-0.4 --settling report
"""
EXIT_MEANINGS = {EXIT_OK: "done", EXIT_CONFIG_ERROR: "invalid argument, or a log that cannot be read or used "
                                                     "(one line on stderr)"}


class UsageError(ValueError):
    """A bad command-line value: printed as one line, exit code 2."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line instead of usage + message
        raise UsageError(message)


def parse_numbers(text: str, name: str, count: int | None = None) -> list[float]:
    """``"1,5,10"`` -> [1.0, 5.0, 10.0] (finite numbers; exactly ``count`` of them if given)."""
    try:
        values = [float(item) for item in text.split(",") if item.strip()]
    except ValueError:
        raise UsageError(f"{name}: expected comma-separated numbers, got '{text}'") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise UsageError(f"{name}: expected finite numbers, got '{text}'")
    if count is not None and len(values) != count:
        raise UsageError(f"{name}: expected {count} numbers, got {len(values)} ('{text}')")
    return values


def parse_orders(text: str) -> list[int]:
    """Filter orders: ``"1,3"``, ``"1:5"`` (inclusive) or a mix ``"1:3,5"``; integers >= 1, no duplicates."""
    orders: list[int] = []
    for item in (part.strip() for part in text.split(",")):
        bounds = item.split(":")
        try:
            numbers = [int(b) for b in bounds]
        except ValueError:
            raise UsageError(f"--r: expected integers, lists '1,3' or ranges '1:5', got '{text}'") from None
        if len(numbers) == 1:
            orders.append(numbers[0])
        elif len(numbers) == 2 and numbers[0] <= numbers[1]:
            orders.extend(range(numbers[0], numbers[1] + 1))
        else:
            raise UsageError(f"--r: bad range '{item}' (expected LOW:HIGH with LOW <= HIGH)")
    if any(r < 1 for r in orders):
        raise UsageError(f"--r: filter orders must be integers >= 1, got '{text}'")
    return list(dict.fromkeys(orders))


def build_parser() -> argparse.ArgumentParser:
    description = DESCRIPTION.format(csv=textwrap.fill(CSV_COLUMNS_HELP, 105))
    parser = _Parser(prog="fsr-estimate", description=description, epilog=EPILOG + exit_codes_text(EXIT_MEANINGS),
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("log", metavar="LOG", help="flight log (.mat, .mcap or .csv)")
    parser.add_argument("--mass", required=True, type=float, metavar="M", help="model mass [kg] > 0")
    parser.add_argument("--inertia", required=True, metavar="IXX,IYY,IZZ", help="diagonal body inertia [kg m^2]")
    parser.add_argument("--c0", required=True, metavar="LIST", help="filter bandwidths [rad/s], e.g. 1,5,10")
    parser.add_argument("--r", required=True, metavar="LIST", help="filter orders, e.g. 1,3 or 1:5")
    parser.add_argument("--truth", metavar="FX,FY,FZ,TX,TY,TZ",
                        help="true external wrench in the estimate's frame (world force [N], eta torque [N m])")
    parser.add_argument("--json", metavar="OUT", type=Path, help="write the results as JSON")
    parser.add_argument("--plots", metavar="DIR", type=Path, help="write the figures (PNG) to DIR")
    parser.add_argument("--settling", choices=SETTLING_DEFINITIONS, default="standard",
                        help="settling-time definition (default: standard; smoothed: standard through a 0.1 s "
                             "low-pass, for noisy logs)")
    parser.add_argument("--after", type=float, metavar="T",
                        help="max error over samples at time >= T [s] (default: the last 5 s of the log)")
    parser.add_argument("--allow-truncated", action="store_true",
                        help="use a truncated MCAP recording (no footer) up to where it stops, with a warning "
                             "(default: refuse it)")
    return parser


def _fmt(value: float, spec: str) -> str:
    return "n/a" if not math.isfinite(value) else format(value, spec)


def _table(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def format_tables(results: list[SweepResult], truth: np.ndarray | None, settling: str, after: float | None) -> str:
    """The Markdown tables printed by the command (channels with a non-zero truth)."""
    parts = []
    if truth is not None:
        shown = [i for i, value in enumerate(truth) if value != 0.0]
        names = [CHANNEL_LABELS[CHANNELS[i]] for i in shown]
        rows = [[f"{r.c0:g}", str(r.r)] + [_fmt(r.settling_time[i], ".3f") for i in shown] for r in results]
        parts.append(f"Settling time [s] ({settling}, 3 % band)\n\n"
                     + _table(["c0", "r"] + [f"settle {n}" for n in names], rows))
        when = "the last 5 s" if after is None else f"t >= {after:g} s"
        rows = [[f"{r.c0:g}", str(r.r)] + [_fmt(r.mae[i], ".4f") for i in shown]
                + [_fmt(r.max_error[i], ".6e") for i in shown] for r in results]
        parts.append(f"Mean absolute error over the whole log and max error over {when}\n\n"
                     + _table(["c0", "r"] + [f"MAE {n}" for n in names] + [f"max err {n}" for n in names], rows))
    rows = [[f"{r.c0:g}", str(r.r), _fmt(r.dm, ".3f"), _fmt(r.m_real, ".3f")] for r in results]
    parts.append("Mass estimate (dm = f_e,z(end) / g)\n\n" + _table(["c0", "r", "dm [kg]", "m_real [kg]"], rows))
    return "\n\n".join(parts) + "\n"


def _mapping(values: np.ndarray) -> dict[str, float | None]:
    return {name: (float(v) if math.isfinite(v) else None) for name, v in zip(CHANNELS, values, strict=True)}


def results_json(results: list[SweepResult], truth_given: bool) -> list[dict]:
    """One object per (c0, r): c0, r, dm, m_real and per-channel settling_time, mae, max_error."""
    empty = np.full(6, np.nan)
    return [
        {
            "c0": r.c0, "r": r.r, "dm": r.dm, "m_real": r.m_real,
            "settling_time": _mapping(r.settling_time if truth_given else empty),
            "mae": _mapping(r.mae if truth_given else empty),
            "max_error": _mapping(r.max_error if truth_given else empty),
        }
        for r in results
    ]


def run(args: argparse.Namespace) -> str:
    """Load, sweep, write JSON/plots; returns the tables. UsageError / FlightLogError on bad input."""
    inertia = parse_numbers(args.inertia, "--inertia", 3)
    c0_values = parse_numbers(args.c0, "--c0")
    r_values = parse_orders(args.r)
    truth = np.array(parse_numbers(args.truth, "--truth", 6)) if args.truth else None
    if args.after is not None and not math.isfinite(args.after):
        raise UsageError(f"--after: must be a finite time [s], got {args.after}")
    try:
        model = ObserverModel(args.mass, np.array(inertia))
    except ValueError as error:
        raise UsageError(f"--{error}") from None
    log: FlightLog = load_flight_log(args.log)
    if log.truncated:
        covered = (f"{log.source}: truncated recording (no MCAP footer), covers only t = {log.time[0]:.3f} .. "
                   f"{log.time[-1]:.3f} s ({len(log)} samples)")
        if not args.allow_truncated:
            raise UsageError(f"{covered}; pass --allow-truncated to estimate over that part")
        print(f"fsr-estimate: warning: {covered}; estimating over that part (--allow-truncated)", file=sys.stderr)
    try:
        results = sweep(log, model, c0_values, r_values, np.zeros(6) if truth is None else truth,
                        settling=args.settling, after=args.after, keep_estimates=args.plots is not None)
    except ValueError as error:
        raise UsageError(f"--{error}") from None
    if args.json is not None:
        try:
            args.json.write_text(json.dumps(results_json(results, truth is not None), indent=2) + "\n")
        except OSError as error:
            raise UsageError(f"--json: cannot write '{args.json}' ({error.strerror})") from None
    if args.plots is not None:
        try:
            from fsr_estimation.cli.estimate_plots import write_plots
        except ModuleNotFoundError as error:
            raise UsageError(f"--plots needs '{error.name}', which is not installed: pip install "
                             "'fsr_estimation[cli]'") from None
        try:
            args.plots.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise UsageError(f"--plots: cannot create '{args.plots}' ({error.strerror})") from None
        write_plots(args.plots, log, results, truth, args.settling)
    return format_tables(results, truth, args.settling, args.after)


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        print(run(args), end="")
    except (UsageError, FlightLogError) as error:
        print(f"fsr-estimate: error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    return EXIT_OK


if __name__ == "__main__":
    raise SystemExit(main())
