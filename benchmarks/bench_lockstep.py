"""Lockstep speed of the simulator node: steps per second and real-time factor at 1 kHz.

Starts the ``simulator`` console script and a minimal controller process (this file with ``--controller``:
answers every ``odom`` with a constant hover ``rotor_cmd``, waiting on a raw rcl wait set) in a leased ROS
domain, and prints:

* steps/s and the real-time factor (simulated seconds per wall second) over the stepping phase;
* the cycle as seen by the controller, from publishing the command for ``t_k`` to receiving the state
  ``t_{k+1}`` (two transports + the simulator's step work): median, p99 and max;
* the simulator's own per-step work measured in this process (plant step + message fill), for reference.

Usage: ``.venv/bin/python benchmarks/bench_lockstep.py [--duration 3] [--vehicle quadrotor_ex4] [--ground]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from fsr_sim.contract import EXIT_FAILURE


def write_scenario(directory: Path, vehicle: str, duration: float, ground: bool) -> Path:
    scenario = {
        "name": "bench_lockstep",
        "vehicle": vehicle,
        "duration": duration,
        "initial_state": {"position": [0.0, 0.0, -1.0 if ground else -10.0]},
        "environment": {"ground": {"enabled": ground}},
        "lockstep": {"timeout": 2.0},
    }
    path = directory / "bench_lockstep.yaml"
    path.write_text(yaml.safe_dump(scenario), encoding="utf-8")
    return path


def hover_speeds(vehicle_name: str) -> np.ndarray:
    from fsr_sim.model.vehicle import load_vehicle

    v = load_vehicle(vehicle_name)
    return np.full(v.rotor_count, math.sqrt(v.weight / (v.rotor_count * v.c_f)))


def run_controller(vehicle: str, steps: int, out: Path) -> None:
    """Child process: answer ``steps + 1`` states, then write the timings to ``out`` (JSON)."""
    from fsr_sim.ros.runtime import configure_environment

    configure_environment()
    import rclpy
    from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy

    from fsr_sim.contract import ODOM, ROTOR_CMD
    from fsr_sim.ros.conversions import rotor_command
    from fsr_sim.ros.endpoints import publisher as topic_publisher
    from fsr_sim.ros.endpoints import subscription

    rclpy.init()
    node = rclpy.create_node("bench_controller")
    publisher = topic_publisher(node, ROTOR_CMD)
    sub = subscription(node, ODOM, lambda _m: None)
    wait_set = _rclpy.WaitSet(1, 0, 0, 0, 0, 0, node.context.handle)
    command = rotor_command(0, hover_speeds(vehicle))
    received: list[float] = []  # wall time of each new state
    sent: list[float] = []  # wall time of each command
    last_stamp = -1
    deadline = time.monotonic() + 60.0
    try:
        with sub.handle:
            while len(received) < steps + 1 and time.monotonic() < deadline:
                wait_set.clear_entities()
                wait_set.add_subscription(sub.handle)
                wait_set.wait(100_000_000)
                if not wait_set.get_ready_entities("subscription"):
                    continue
                while (taken := sub.handle.take_message(sub.msg_type, False)) is not None:
                    stamp = taken[0].header.stamp
                    stamp_ns = stamp.sec * 1_000_000_000 + stamp.nanosec
                    if stamp_ns == last_stamp:
                        continue  # the handshake repeats t_0
                    now = time.perf_counter()
                    received.append(now)
                    last_stamp = stamp_ns
                    if len(received) <= steps:
                        command.header.stamp = stamp
                        publisher.publish(command)
                        sent.append(time.perf_counter())
    finally:
        out.write_text(json.dumps({"received": received, "sent": sent}), encoding="utf-8")
        node.destroy_node()
        rclpy.try_shutdown()


def in_process_step_cost(scenario_path: Path, vehicle: str, repeats: int = 2000) -> tuple[float, float]:
    """Mean plant step and message fill time [s] (no ROS transport)."""
    from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
    from fsr_sim.nodes.state_messages import StateMessages

    config = simulation_config(load_scenario(scenario_path))
    config.duration = repeats * config.control_period
    plant = plant_from_config(config)
    plant.set_rotor_command(hover_speeds(vehicle))
    messages = StateMessages(plant)
    start = time.perf_counter()
    for _ in range(repeats):
        plant.step()
    step = (time.perf_counter() - start) / repeats
    start = time.perf_counter()
    for _ in range(repeats):
        messages.fill()
    fill = (time.perf_counter() - start) / repeats
    return step, fill


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=3.0, help="simulated seconds (1 kHz steps)")
    parser.add_argument("--vehicle", default="quadrotor_ex4")
    parser.add_argument("--ground", action="store_true", help="hover 1 m above the ground (ground effect on)")
    parser.add_argument("--controller", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--steps", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.controller:
        run_controller(args.vehicle, args.steps, args.out)
        return 0

    from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
    from fsr_bringup.runner.flight import TEARDOWN_HUNG
    from fsr_bringup.runner.processes import executable
    from fsr_sim.contract import FINISHED
    from fsr_sim.ros.runtime import configure_environment

    configure_environment()
    steps = int(round(args.duration * 1000))
    with tempfile.TemporaryDirectory() as tmp, acquire_domain(TEST_RANGE) as lease:
        tmp_path = Path(tmp)
        scenario = write_scenario(tmp_path, args.vehicle, args.duration, args.ground)
        env = dict(os.environ, ROS_DOMAIN_ID=str(lease.domain_id), PYTHONUNBUFFERED="1")
        timings = tmp_path / "timings.json"
        sim_log = tmp_path / "simulator.log"
        with open(sim_log, "w", encoding="utf-8") as log:
            sim = subprocess.Popen(
                [executable("simulator"), "--ros-args", "-p", f"scenario:={scenario}"],
                env=env, stdout=log, stderr=subprocess.STDOUT,
            )
            ctl = subprocess.Popen(
                [sys.executable, __file__, "--controller", "--vehicle", args.vehicle, "--steps", str(steps),
                 "--out", str(timings)],
                env=env,
            )
            try:
                ctl.wait(120)
                sim_code = sim.wait(30)
            finally:
                for process in (sim, ctl):
                    if process.poll() is None:
                        process.kill()
        if sim_code == TEARDOWN_HUNG and f"{FINISHED}: " in sim_log.read_text():
            # Its flight was done; only the rcl/DDS teardown hung (fsr_bringup/runner/watcher_node.py says when)
            # and its watchdog ended it: the timings are whole.
            print("note: the simulator's rcl/DDS teardown hung after its flight and its watchdog ended it",
                  file=sys.stderr)
        elif sim_code != 0:
            print(sim_log.read_text(), file=sys.stderr)
            print(f"simulator exited with {sim_code}", file=sys.stderr)
            return EXIT_FAILURE
        data = json.loads(timings.read_text())
        step_cost, fill_cost = in_process_step_cost(scenario, args.vehicle)

    received = np.array(data["received"])
    sent = np.array(data["sent"])
    n = len(received) - 1
    wall = received[-1] - received[0]  # states t_0 .. t_N, after the handshake
    cycle = (received[1:] - sent[: len(received) - 1]) * 1e6  # us: command t_k -> state t_{k+1}
    rate = n / wall
    print(f"vehicle {args.vehicle}, {n} steps of 1 ms, ground {'on' if args.ground else 'off'}")
    print(f"steps/s              {rate:10.0f}")
    print(f"real-time factor     {rate / 1000.0:10.2f} x real time")
    print(f"cycle median [us]    {np.median(cycle):10.0f}   (command t_k sent -> state t_k+1 received)")
    print(f"cycle p99 [us]       {np.percentile(cycle, 99):10.0f}")
    print(f"cycle max [us]       {cycle.max():10.0f}")
    print(f"plant step [us]      {step_cost * 1e6:10.0f}   (in-process, per 1 ms step)")
    print(f"message fill [us]    {fill_cost * 1e6:10.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
