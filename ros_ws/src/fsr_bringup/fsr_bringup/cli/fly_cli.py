"""``fsr-fly SCENARIO``: fly a scenario with the whole node graph, record it, analyse it.

    fsr-fly ex3_estimation                          # built-in scenario, recording under runs/
    fsr-fly my_flight.yaml --out runs/a.mcap --set disturbances.0.force=[0.5,0,0] --duration 10
    fsr-fly ex4_geometric --in-process              # same modules, no DDS: fastest
    fsr-fly ex4_geometric --in-process --live       # watch it in Foxglove (ws://localhost:8765), at real time
    fsr-fly three_vehicles                          # a fleet: /uav1../uav3 in one domain (runner/fleet.py)
    fsr-fly ex4_geometric --network --domain-id 42 --nodes simulator,recorder    # host A of a flight over
    fsr-fly ex4_geometric --network --domain-id 42 --nodes controller,estimator  # two hosts (runner/remote.py)

Starts the simulator, controller, estimator and recorder as separate processes in a ROS domain of their
own (localhost-only discovery), streams their logs with a prefix per node, shows progress on a terminal,
stops every process it started, then writes figures and ``metrics.json`` next to the recording and prints
a summary. Exit codes: ``fsr-fly --help``.
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import yaml

from fsr_bringup.analysis.figure_options import NO_ANALYSIS
from fsr_bringup.cli.analyze_cli import add_figure_arguments, figure_options
from fsr_bringup.live.endpoint import add_live_arguments, endpoint_of, reserve
from fsr_bringup.runner.domains import acquire_domain, fixed_domain
from fsr_bringup.runner.fleet import FleetMember, builtin_fleet_names, fleet_path, load_fleet
from fsr_bringup.runner.flight import Console, VehicleLaunch, fly_graph, node_commands
from fsr_bringup.runner.remote import parse_node_selection
from fsr_bringup.runner.scenario_check import check_scenario
from fsr_sim.cli.arguments import ArgumentParser, argument_type
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.contract import (
    EXIT_CODES,
    EXIT_CONFIG_ERROR,
    EXIT_DIVERGED,
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
    recording_selection,
)

REMOTE_STARTUP_TIMEOUT = 300.0  # s: with --nodes the other hosts' nodes may be started by hand, later


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = ArgumentParser(prog="fsr-fly", doc=__doc__, exit_codes={
        EXIT_OK: "the flight finished", EXIT_FAILURE: "a node failed (named in the message)",
        EXIT_CONFIG_ERROR: EXIT_CODES[EXIT_CONFIG_ERROR], EXIT_DIVERGED: EXIT_CODES[EXIT_DIVERGED],
        EXIT_INTERRUPTED: EXIT_CODES[EXIT_INTERRUPTED]})
    parser.add_argument(
        "scenario",
        help=f"built-in scenario ({', '.join(builtin_names('scenarios'))}), built-in fleet "
        f"({', '.join(builtin_fleet_names())}) or a YAML path",
    )
    parser.add_argument("--out", type=Path, help="recording path (default runs/<scenario>_<time>.mcap)")
    parser.add_argument("--duration", type=float, help="override the scenario's duration [s]")
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
        help="override a scenario key by dotted path with a YAML value (repeatable)",
    )
    parser.add_argument("--in-process", action="store_true", help="run without DDS (same modules, one process)")
    parser.add_argument("--domain-id", type=int, help="ROS domain id to use (default: a free one, 150..232)")
    parser.add_argument("--network", action="store_true", help="allow DDS discovery beyond localhost")
    parser.add_argument(
        "--nodes", metavar="LIST",
        help="start only these nodes here (comma-separated roles simulator,controller,estimator,recorder or "
        "process names like uav2/controller); the others run on other hosts: needs --domain-id",
    )
    parser.add_argument(
        "--startup-timeout", type=float, metavar="S",
        help="how long the simulator waits for the other nodes (default 20 s; 300 s with --nodes)",
    )
    parser.add_argument(NO_ANALYSIS, action="store_true", help="skip figures and metrics")
    parser.add_argument("--record-topics", metavar="LIST", type=argument_type(recording_selection),
                        help="record only these topics, comma-separated (e.g. odom,reference,clock: a long flight "
                             "in a smaller file); sim_status is always recorded; the analysis skips what is "
                             "missing, with a note (default: every topic)")
    parser.add_argument("--quiet", action="store_true", help="do not stream node logs (the progress is still shown)")
    add_live_arguments(parser, "every recorded topic (the graph as it runs; --in-process paced at the scenario's "
                               "lockstep.real_time_factor, 1 by default)")
    add_figure_arguments(parser)
    return parser.parse_args(argv)


def default_recording_path(name: str) -> Path:
    return Path("runs") / f"{name}_{time.strftime('%Y%m%d-%H%M%S')}.mcap"


def load_members(args: argparse.Namespace) -> tuple[str, list[FleetMember]]:
    """The run's name and its vehicles (one, or a fleet), every scenario validated."""
    overrides = list(args.overrides)
    if args.duration is not None:
        overrides.append(f"duration={args.duration!r}")
    path = fleet_path(args.scenario)
    if path is not None:
        fleet = load_fleet(path, overrides)
        return fleet.name, fleet.members
    checked = check_scenario(load_scenario(args.scenario, overrides))
    return checked.scenario.name, [FleetMember("", checked)]


def write_scenarios(members: list[FleetMember], run_dir: Path) -> tuple[Path, list[VehicleLaunch]]:
    """Write each member's merged scenario into the run folder (what the nodes read and the recording keeps)."""
    launches = []
    for member in members:
        stem = member.namespace.strip("/") or "scenario"
        path = (run_dir / f"{stem}.yaml").resolve()
        path.write_text(member.checked.scenario.dump(), encoding="utf-8")
        launches.append(VehicleLaunch(member.namespace, path, member.checked.estimator_enabled))
    if len(members) == 1 and not members[0].namespace:
        return launches[0].scenario_path, launches
    combined = (run_dir / "fleet.yaml").resolve()
    fleet = [
        {"namespace": m.namespace, "scenario": yaml.safe_load(m.checked.scenario.dump())} for m in members
    ]
    combined.write_text(yaml.safe_dump({"fleet": fleet}, sort_keys=False), encoding="utf-8")
    return combined, launches


def local_nodes(text: str | None, members: list[VehicleLaunch], recording: Path, scenario_path: Path
                ) -> set[str] | None:
    """The process names ``--nodes`` selects for this host (None: the whole graph)."""
    if text is None:
        return None
    names = [name for name, _command in node_commands(members, recording, scenario_path)]
    return parse_node_selection(text, names)


@contextmanager
def interrupts_end_the_flight() -> Iterator[Callable[[], str | None]]:
    """SIGINT and SIGTERM end an in-process flight between two steps (also where the shell started fsr-fly
    with SIGINT ignored, e.g. in the background): yields the ``stop`` poll for :func:`fsr_bringup.simulate`."""
    received: list[str] = []

    def note(signum: int, _frame: object) -> None:
        received.append(signal.Signals(signum).name)

    previous = {signum: signal.signal(signum, note) for signum in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: received[0] if received else None
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if not args.no_analysis:  # the figures' worker processes get ready while the scenario is read and flown
        from fsr_bringup.analysis.figure_jobs import prepare_workers

        prepare_workers()
    try:
        name, members = load_members(args)
    except ConfigError as error:
        print(f"fsr-fly: invalid scenario: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    recording = args.out or default_recording_path(name)
    if recording.suffix != ".mcap":
        print(f"fsr-fly: --out must end in .mcap, got '{recording}'", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    if args.in_process and len(members) > 1:
        print("fsr-fly: --in-process flies one vehicle; fly a fleet with the node graph", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    try:
        options = None if args.no_analysis else figure_options(args)
    except ValueError as error:
        print(f"fsr-fly: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    if args.nodes is not None and (args.in_process or args.domain_id is None):
        print("fsr-fly: --nodes runs part of a graph: it needs --domain-id (the same on every host) and no "
              "--in-process", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    live = endpoint_of(args)
    if live is not None:  # checked before anything is flown; the graph's recorder is given the port found for 0
        try:
            reserved = reserve(live)
        except ValueError as error:
            print(f"fsr-fly: {error}", file=sys.stderr)
            return EXIT_CONFIG_ERROR
        live = live if args.in_process else reserved
    run_dir = recording.with_suffix("")
    try:
        run_dir.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        print(f"fsr-fly: cannot create '{run_dir}': {error.strerror}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    scenario_path, launches = write_scenarios(members, run_dir)
    for member in members:
        label = f"{member.namespace}: " if member.namespace else ""
        print(f"fsr-fly: {name}: {label}{member.checked.summary_line()}", flush=True)
        for adjustment in member.checked.controller.plan_adjustments:  # the legs beyond the authority
            print(f"fsr-fly: {name}: {label}{adjustment.text()}", flush=True)
        for warning in member.checked.warnings:
            print(f"fsr-fly: {name}: {label}warning: {warning}", flush=True)
        plan_end, flight_end = member.checked.controller.plan_end_time, member.checked.simulation.duration
        if plan_end > flight_end + 1e-9:  # the flight will end mid-path
            print(f"fsr-fly: {name}: {label}WARNING: the plan comes to rest at {plan_end:.3f} s, after the flight's "
                  f"{flight_end:g} s: the flight will end mid-path (raise duration to at least "
                  f"{math.ceil(plan_end * 100) / 100:g} s)", file=sys.stderr, flush=True)
    duration = max(m.checked.simulation.duration for m in members)

    if args.in_process:
        from fsr_bringup.api import simulate

        console = Console(quiet=args.quiet)
        from fsr_bringup.live.server import LiveServer, LiveServerError

        with interrupts_end_the_flight() as stop, ExitStack() as serving:
            server = None if live is None else serving.enter_context(LiveServer(live, name, say=console.notice))
            try:
                result = simulate(members[0].checked.scenario, record=recording, stop=stop,
                                  progress=lambda t, wall: console.flight_progress(t, duration, wall),
                                  record_topics=None if args.record_topics is None else ",".join(
                                      sorted(args.record_topics)), live=server)
            except LiveServerError as error:  # the port was taken since it was checked
                print(f"fsr-fly: {error}", file=sys.stderr)
                return EXIT_CONFIG_ERROR
            finally:
                console.end_progress()
    else:
        try:
            domain = fixed_domain(args.domain_id) if args.domain_id is not None else acquire_domain()
        except (ValueError, RuntimeError) as error:
            print(f"fsr-fly: {error}", file=sys.stderr)
            return EXIT_CONFIG_ERROR
        try:
            nodes = local_nodes(args.nodes, launches, recording, scenario_path)
        except ValueError as error:
            print(f"fsr-fly: {error}", file=sys.stderr)
            return EXIT_CONFIG_ERROR
        if live is not None and nodes is not None and "recorder" not in nodes:
            print("fsr-fly: --live: the recorder serves the flight and it runs on another host: give --live there",
                  file=sys.stderr)
            return EXIT_CONFIG_ERROR
        startup_timeout = args.startup_timeout
        if startup_timeout is None and nodes is not None:
            startup_timeout = REMOTE_STARTUP_TIMEOUT
        with domain:
            here = "" if nodes is None else f", nodes here: {', '.join(sorted(nodes))}"
            print(f"fsr-fly: ROS domain {domain.domain_id}{here}, logs in {run_dir / 'logs'}", flush=True)
            if live is not None:
                print(f"fsr-fly: live: the recorder serves on {live.url} (Foxglove: Open connection -> Foxglove "
                      "WebSocket; layout docs/foxglove/fsr.json)", flush=True)
            result = fly_graph(
                launches, recording, scenario_path, run_dir / "logs", domain, duration,
                Console(quiet=args.quiet), localhost_only=not args.network, nodes=nodes,
                startup_timeout=startup_timeout, record_topics=args.record_topics, live=live,
            )
        for note in result.notes:
            print(f"fsr-fly: WARNING: {note}", file=sys.stderr, flush=True)
        if nodes is not None and "recorder" not in nodes:  # the recording is written on another host
            for failure in result.failures:
                print(f"fsr-fly: ERROR: {failure}", file=sys.stderr, flush=True)
            print(f"fsr-fly: flight {'interrupted' if result.interrupted else 'ended'}: simulated "
                  f"{result.sim_time:.3f} s in {result.wall_time:.2f} s wall; the recording is on the recorder's "
                  "host", flush=True)
            return result.exit_code
    sim_time, opened = result.sim_time, None
    if args.in_process and args.record_topics is None and recording.exists():
        opened = result.trace  # analysed as flown: its recording is not read back
    elif recording.exists():  # the stop time the simulator recorded (what the summary reports), not the last seen
        from fsr_bringup.analysis.load import final_sim_time
        from fsr_sim.recording.reader import RecordingError, open_recording

        try:
            opened = open_recording(recording)  # read once: for the stop time and the analysis
            sim_time = final_sim_time(opened, [m.namespace for m in members]) or sim_time
        except RecordingError:
            pass  # reported by the analysis below
    print(
        f"fsr-fly: flight {'interrupted' if result.interrupted else 'ended'}: simulated {sim_time:.3f} s "
        f"in {result.wall_time:.2f} s wall (real-time factor {result.real_time_factor:.2f})",
        flush=True,
    )
    speed = flight_speed(result) if live is None or not args.in_process else \
        f"paced for watching live at lockstep.real_time_factor {members[0].checked.simulation.real_time_factor:g}"
    if speed:
        print(f"fsr-fly: {speed}", flush=True)
    for failure in result.failures:
        print(f"fsr-fly: ERROR: {failure}", file=sys.stderr, flush=True)
    if not recording.exists():
        print(f"fsr-fly: no recording was written at {recording}", file=sys.stderr)
        return result.exit_code or 1
    if not args.no_analysis:
        from fsr_bringup.runner.report import analyse_and_summarise

        analyse_and_summarise(opened or recording, run_dir, [m.namespace for m in members], options,
                              args.settling, args.after)
    print(f"fsr-fly: recording {recording}", flush=True)
    return result.exit_code


def flight_speed(result: object) -> str:
    """One line on how fast the flight ran: the graph's stepping rate (start-up excluded), or the in-process
    loop's cost per step and its start-up."""
    stepping = getattr(result, "stepping_rate", float("nan"))
    if stepping == stepping:  # not NaN: a graph run
        return f"stepping at {stepping:.2f}x real time (node start-up and handshake excluded)"
    startup = getattr(result, "startup_time", None)
    steps = len(getattr(result, "time", ()))
    if startup is None or not steps:
        return ""
    return (f"in-process loop {1e6 * result.wall_time / steps:.0f} us per step (recording included), "
            f"first step {startup:.2f} s after the process started")


if __name__ == "__main__":
    sys.exit(main())
