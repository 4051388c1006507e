"""In-process cost per 1 kHz step (us): the compiled core's parts alone (controller tick, plant step, observer
sample), the compiled closed loop, the loop with its MCAP recording, and the whole ``fly_in_process`` call
(min and median of ``--repeat`` runs).

    .venv/bin/python benchmarks/bench_in_process.py [--seconds 3] [--repeat 3]

For ex4 (geometric, wrench actuation), ex5 (Voliro, rotor actuation, with and without the null-space
objective, and with a noisy IMU: its specific force and stage per step) and the octocopter with ground effect.
The parts are timed by a compiled loop calling each one on the flight's first state (what it costs inside the
loop, without Python); "loop" is the time spent in the compiled flight loop
(:func:`fsr_bringup.core.flight_loop.fly`), "+ recording" the whole ``fly_in_process`` with its
recording, per step (wall). ``run_all.py`` reports the loop's CPU time.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from fsr_bringup.core import flight_loop
from fsr_bringup.runner.in_process_flight import fly_in_process
from fsr_control.config.controller_config import controller_config
from fsr_control.core.controller import controller_tick
from fsr_control.core.law_terms import Measured, VehicleState
from fsr_control.flight_controller import FlightController
from fsr_estimation.core import observer_step
from fsr_estimation.estimator.observer import MomentumObserver
from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
from fsr_sim.core import lockstep
from fsr_sim.core.jit import numba
from fsr_sim.core.odometry import IMU_ANGULAR_VELOCITY, PUBLISHED_SIZE, read_odometry
from fsr_sim.core.plant import plant_step

SCENARIOS = Path(__file__).resolve().parents[1] / "ros_ws/src/fsr_control/test/scenarios"
CASES = {
    "ex4 geometric (wrench)": ("ex4_wrench.yaml", []),
    "ex5 voliro (rotors)": ("ex5_voliro.yaml", []),
    "ex5 voliro + min_peak_speed": ("ex5_voliro.yaml", ["controller.secondary_objective.type=min_peak_speed"]),
    "octocopter + ground effect": ("octo_ground_effect", []),
    "ex5 voliro + IMU (BMI088)": ("ex5_voliro.yaml", [f"sensors.imu.{key}" for key in (  # the onboard preset's IMU
        "gyro_noise_density=0.000244", "accelerometer_noise_density=0.00172", "gyro_bias_walk=0.000022",
        "accelerometer_bias_walk=0.00086")]),
}
PART_STEPS = 20_000


@numba.njit  # not cached: a benchmark writes nothing next to its source
def _ticks(params, state, row, rotors, out, n):  # noqa: ANN001, ANN202
    position, rotation, velocity, omega = read_odometry(row)
    vehicle = VehicleState(position, rotation, velocity, omega)
    measured = Measured(row[IMU_ANGULAR_VELOCITY:IMU_ANGULAR_VELOCITY + 6], rotors, rotors)
    for k in range(n):
        controller_tick(params, state, k * 1e-3, vehicle, measured, out)


@numba.njit
def _plant_steps(params, state, n):  # noqa: ANN001, ANN202
    x = state.x.copy()
    for _ in range(n):
        state.x[:] = x  # the same state each time (no drift over the run)
        plant_step(params, state)


@numba.njit
def _samples(params, state, row, out, n):  # noqa: ANN001, ANN202
    _, rotation, velocity, omega = read_odometry(row)
    for _ in range(n):
        observer_step.estimate_from_state(params, state, rotation, velocity, omega, (0.0, 0.0, -11.0),
                                          (0.0, 0.0, 0.0), out)


def _per_step(function, *args) -> float:  # noqa: ANN001
    function(*args, 10)
    start = time.perf_counter()
    function(*args, PART_STEPS)
    return (time.perf_counter() - start) / PART_STEPS * 1e6


def parts(scenario) -> tuple[float, float, float]:  # noqa: ANN001
    """(controller tick, plant step, observer sample) [us], each in a compiled loop."""
    sim = simulation_config(scenario)
    plant = plant_from_config(sim)
    controller = FlightController(controller_config(scenario), sim.vehicle, sim.actuation, sim.initial.position,
                                  sim.initial.rotation)
    row = np.zeros(PUBLISHED_SIZE)
    lockstep.publish(plant.params, plant.core_state, row)
    observer = MomentumObserver(sim.vehicle.mass, sim.vehicle.inertia, 10.0, 1, sim.control_period)
    rotors = np.zeros(sim.vehicle.rotor_count)  # rotor_state (read only by a law or an observer that needs it)
    return (_per_step(_ticks, controller.params, controller.state, row, rotors, controller.output),
            _per_step(_plant_steps, plant.params, plant.core_state),
            _per_step(_samples, observer.params, observer.state, row, np.zeros(7)))


def flights(scenario, repeat: int) -> tuple[list[float], list[float]]:  # noqa: ANN001
    """(compiled loop, whole call with recording) [us per step] of ``repeat`` flights."""
    loop_seconds = [0.0]
    original = flight_loop.fly

    def timed(*args):  # noqa: ANN002, ANN202
        start = time.perf_counter()
        result = original(*args)
        loop_seconds[0] += time.perf_counter() - start
        return result

    loops, recorded = [], []
    flight_loop.fly = timed
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for _ in range(repeat):
                loop_seconds[0] = 0.0
                run = fly_in_process(scenario)
                loops.append(loop_seconds[0] / len(run.time) * 1e6)
                start = time.perf_counter()
                fly_in_process(scenario, Path(tmp) / "bench.mcap")
                recorded.append((time.perf_counter() - start) / len(run.time) * 1e6)
    finally:
        flight_loop.fly = original
    return loops, recorded


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds per flight")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    print(f"{'case':30s} {'tick':>6s} {'plant':>6s} {'observer':>8s} {'loop min/med':>13s} "
          f"{'+ recording min/med':>20s}   [us per 1 kHz step]")
    for name, (file, overrides) in CASES.items():
        source = SCENARIOS / file if file.endswith(".yaml") else file  # a test scenario or a built-in one
        scenario = load_scenario(source, [*overrides, f"duration={args.seconds}", "estimator.enabled=true"])
        tick, plant, sample = parts(scenario)
        loops, recorded = flights(scenario, args.repeat)
        print(f"{name:30s} {tick:6.2f} {plant:6.2f} {sample:8.2f} {min(loops):6.2f}/{statistics.median(loops):6.2f} "
              f"{min(recorded):9.2f}/{statistics.median(recorded):9.2f}")


if __name__ == "__main__":
    main()
