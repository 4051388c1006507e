"""In-process cost per 1 kHz step (us): controller, physics and estimator alone, the full closed loop, and
the loop with its recording.

    .venv/bin/python benchmarks/bench_in_process.py [--seconds 3]

For ex4 (geometric, wrench actuation), ex5 (Voliro, rotor actuation, with and without the null-space
objective) and the octocopter with ground effect. The controller is timed on the states of an in-process
flight; the physics step with the flight's commands replayed; the estimator on the flight's states and
commands; the full loop is ``fly_in_process`` (controller, plant, estimator and the bookkeeping between
them), without and with its MCAP recording (wall time per step, one run each: the breakdown of issue 11's
in-process figures; ``run_all.py`` gives the min and median of the loop with recording).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_control.config.controller_config import controller_config
from fsr_control.flight_controller import FlightController
from fsr_estimation.core.stamped import StampedEstimator
from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
from fsr_sim.model.so3 import rotation_from_quaternion

SCENARIOS = Path(__file__).resolve().parents[1] / "ros_ws/src/fsr_control/test/scenarios"
CASES = {
    "ex4 geometric (wrench)": ("ex4_wrench.yaml", []),
    "ex5 voliro (rotors)": ("ex5_voliro.yaml", []),
    "ex5 voliro + min_peak_speed": ("ex5_voliro.yaml", ["controller.secondary_objective.type=min_peak_speed"]),
    "octocopter + ground effect": ("octo_ground_effect", []),
}


def bench(file: str, overrides: list[str], seconds: float) -> tuple[float, ...]:
    source = SCENARIOS / file if file.endswith(".yaml") else file  # a test scenario or a built-in one
    scenario = load_scenario(source, [*overrides, f"duration={seconds}", "estimator.enabled=true"])
    result = fly_in_process(scenario)
    steps = len(result.time)
    full = result.wall_time / steps * 1e6
    with tempfile.TemporaryDirectory() as tmp:
        recorded = fly_in_process(scenario, Path(tmp) / "bench.mcap").wall_time / steps * 1e6
    sim = simulation_config(scenario)
    controller = FlightController(controller_config(scenario), sim.vehicle, sim.actuation,
                                  sim.initial.position, sim.initial.rotation)
    rotations = [rotation_from_quaternion(q) for q in result.state[:, 6:10]]
    start = time.perf_counter()
    for k in range(steps):
        s = result.state[k]
        controller.command(result.time[k], s[0:3], rotations[k], s[3:6], s[10:13])
    control = (time.perf_counter() - start) / steps * 1e6
    plant = plant_from_config(sim)
    start = time.perf_counter()
    for k in range(steps - 1):
        if sim.actuation == "rotors":
            tilts = None if result.tilt_angles is None else result.tilt_angles[k]
            plant.set_rotor_command(result.rotor_speeds[k], tilts)
        else:
            plant.set_wrench_command(result.thrust[k], result.torque_cmd[k])
        plant.step()
    physics = (time.perf_counter() - start) / (steps - 1) * 1e6
    estimator = StampedEstimator(sim.vehicle.mass, sim.vehicle.inertia, 10.0, 1, sim.control_period)
    start = time.perf_counter()
    for k in range(steps):
        s = result.state[k]
        stamp = int(round(result.time[k] * 1e9))
        estimator.add_state(stamp, rotations[k], s[3:6], s[10:13])
        estimator.add_command(stamp, result.force_cmd[k], result.torque_cmd[k])
    estimation = (time.perf_counter() - start) / steps * 1e6
    return control, physics, estimation, full, recorded


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds per case")
    args = parser.parse_args()
    print(f"{'case':32s} {'controller':>10s} {'physics':>8s} {'estimator':>9s} {'full loop':>9s} "
          f"{'+ recording':>11s}   [us per 1 kHz step]")
    for name, (file, overrides) in CASES.items():
        control, physics, estimation, full, recorded = bench(file, overrides, args.seconds)
        print(f"{name:32s} {control:10.1f} {physics:8.1f} {estimation:9.1f} {full:9.1f} {recorded:11.1f}")


if __name__ == "__main__":
    main()
