"""``fsr-compile``: compile the flight core once, so that no flight and no node pays a compilation.

    fsr-compile            # fill numba's cache (scripts/setup.sh runs it); a second run only loads it

The core (:mod:`fsr_sim.core.jit`) is compiled by numba on first use and cached on disk in a folder keyed by
its sources; this command uses every entry point the nodes, the in-process loop, the analysis and the Python
API call -- a short flight of every built-in scenario, recorded and analysed, and the node-side calls -- so
that each is compiled (or found in the cache) here.

It also prunes the cache folders of other versions of the core's sources (each edit of a core file, each
release, makes a new one): a folder is removed when nothing in it was written for :data:`KEEP_DAYS` days, or
when :data:`KEEP_MOST` newer ones are kept and it was last written over an hour ago (another checkout flying
right now keeps its folder). A removed version only costs a compilation, once, if it is ever used again.
"""

from __future__ import annotations

import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from fsr_sim.cli.arguments import ArgumentParser
from fsr_sim.config.validation import builtin_names
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_OK

BUILT_IN = tuple(builtin_names("scenarios"))
KEEP_DAYS = 7.0  # a cache folder not written for this long is removed
KEEP_MOST = 8  # cache folders of other source versions kept at most (the newest)
RECENT_S = 3600.0  # s: a folder written this recently is kept whatever the count
KEY_PATTERN = re.compile(r"[0-9a-f]{16}")  # fsr_sim.core.jit.core_key's folder names


def prune_cache(base: Path, current: Path, now: float | None = None) -> list[Path]:
    """Remove the cache folders of other source versions under ``base`` (module docstring); ``current`` is
    kept. Only fsr's folders are touched (a key's name holding ``fsr_*`` module folders), so a numba cache
    shared with other projects (``NUMBA_CACHE_DIR``) loses nothing of theirs. Returns the removed folders."""
    now = time.time() if now is None else now
    others = []
    for folder in base.iterdir() if base.is_dir() else ():
        if folder == current or not KEY_PATTERN.fullmatch(folder.name) or not folder.is_dir():
            continue
        if not any(child.name.startswith("fsr_") for child in folder.iterdir()):
            continue
        written = max((path.stat().st_mtime for path in folder.rglob("*")), default=folder.stat().st_mtime)
        others.append((written, folder))
    removed = []
    for rank, (written, folder) in enumerate(sorted(others, reverse=True)):
        age = now - written
        if age > KEEP_DAYS * 86400.0 or (rank >= KEEP_MOST and age > RECENT_S):
            shutil.rmtree(folder, ignore_errors=True)
            removed.append(folder)
    return removed


def tour(folder: Path) -> None:
    """Call every entry point of the core once (module docstring)."""
    from fsr_bringup import simulate
    from fsr_bringup.analysis.load import load_flight
    from fsr_bringup.analysis.metrics import flight_metrics

    for name in BUILT_IN:
        path = folder / f"{name}.mcap"
        simulate(name, duration=0.02, record=path)
        flight_metrics(load_flight(path))
    simulate("ex4_geometric", set={"actuation": "rotors"}, duration=0.02)
    _paths()
    _sweep_flights()
    _node_calls()
    _python_api()


def _paths() -> None:
    """A path that faces its motion (``trajectory.yaw: velocity``, the only calls the built-in scenarios do not
    make: the heading of the motion along the path), planned and checked."""
    from fsr_bringup import simulate

    simulate("ex4_geometric", duration=0.02, set={"actuation": "rotors", "trajectory": {
        "kind": "circle", "centre": [0.0, 0.0, -2.0], "radius": 1.0, "speed": 0.5, "yaw": "velocity"}})


def _sweep_flights() -> None:
    """A sweep's flights measured in the loop (:mod:`fsr_bringup.sweeps.measured`), of every built-in scenario,
    with and without the estimator; one of each actuation measured from its arrays (a flight that ends early)."""
    from fsr_bringup.sweeps.batch import fly_one, packed_sweep
    from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M
    from fsr_sim.config.scenario import load_scenario

    flights = [(name, {}) for name in BUILT_IN] + [("ex4_geometric", {"actuation": "rotors"})]
    for name, fixed in flights:
        for enabled in (True, False):
            fly_one(load_scenario(name, values={**fixed, "duration": 0.02, "estimator.enabled": enabled}), {})
    for fixed in ({}, {"actuation": "rotors"}):
        base = load_scenario("ex4_geometric", values={**fixed, "duration": 0.02})
        fly_one(base, {}, measured=False)
        # set up from the sweep's packed scenario, a swept inertia (arrays of its own, other types)
        fly_one(base, {"plant.inertia": [0.03, 0.03, 0.06]}, packed=packed_sweep(base, DEFAULT_BAND_M))


def _node_calls() -> None:
    """What the simulator, controller and estimator nodes call per message (and at start-up)."""
    from fsr_control.config.controller_config import controller_config
    from fsr_control.flight_controller import FlightController, seconds_from_ns
    from fsr_control.nodes.packets import ControllerPackets
    from fsr_estimation.estimator.stamped import StampedEstimator
    from fsr_sim.config.scenario import load_scenario, plant_from_config, simulation_config
    from fsr_sim.core import lockstep
    from fsr_sim.core.odometry import PUBLISHED_SIZE
    from fsr_sim.nodes.state_packets import StatePackets
    from fsr_sim.ros.conversions import odometry_state_from_bytes, state_from_odometry_bytes

    for name, overrides in (("ex4_geometric", ["actuation=rotors"]), ("ex4_geometric", []), ("ex5_voliro", [])):
        scenario = load_scenario(name, overrides)
        sim = simulation_config(scenario)
        plant = plant_from_config(sim)
        controller = FlightController(controller_config(scenario), sim.vehicle, sim.actuation, sim.initial.position,
                                      sim.initial.rotation)
        estimator = StampedEstimator(1.5, np.ones(3), 10.0, 1, sim.control_period)
        packets, state_packets = ControllerPackets(True, sim.vehicle.rotor_count), StatePackets()
        row = np.zeros(PUBLISHED_SIZE)
        lockstep.publish(plant.params, plant.core_state, row)
        state_packets.fill_from_row(0, row)
        stamp, position, rotation, velocity, omega = odometry_state_from_bytes(state_packets.odom)
        output = controller.command_row(seconds_from_ns(stamp), position, rotation, velocity, omega)
        packets.pack(stamp, output)
        _, _, rotation_array, velocity_array, omega_array = state_from_odometry_bytes(state_packets.odom)
        estimator.add_state(stamp, rotation_array, velocity_array, omega_array)
        estimator.add_command(stamp, output[0:3].copy(), output[3:6].copy())
        plant.set_wrench_command(1.0, np.zeros(3)) if sim.actuation == "wrench" else plant.set_rotor_command(
            np.zeros(sim.vehicle.rotor_count), np.zeros(sim.vehicle.rotor_count))
        plant.set_rotor_command(np.zeros(sim.vehicle.rotor_count))
        plant.cut_thrust()
        lockstep.advance(plant.params, plant.core_state, row)


def _python_api() -> None:
    """The Python API's shells: the plant, the laws, the allocations, the observer, rotations."""
    from fsr_control.allocation import FixedRotorActuation, TiltingActuation, WrenchActuation
    from fsr_control.planning.flatness import flat_attitude_rates
    from fsr_estimation.estimator.observer import MomentumObserver
    from fsr_sim.model import Plant, load_vehicle, so3
    from fsr_sim.model.disturbances import constant
    from fsr_sim.model.rotors import SaturationReport, clamp_rotor_speeds

    quad, tilting = load_vehicle("quadrotor_ex4"), load_vehicle("tilting_quadrotor_ex5")
    plant = Plant(quad, disturbances=[constant((1.0, 0.0, 0.0))], attitude_rpy_deg=(1.0, 2.0, 3.0))
    plant.step()
    plant.divergence()
    plant.external_wrench()
    plant.specific_force()
    plant.thrust_ratios()
    force, torque = np.array((0.0, 0.0, -12.0)), np.array((0.01, 0.0, 0.0))
    for actuation in (FixedRotorActuation(quad), TiltingActuation(tilting, objective="min_peak_speed"),
                      WrenchActuation(quad)):
        actuation.allocate(0.0, force, torque)
    FixedRotorActuation(quad).desaturated(12.0, (0.0, 0.0, 1.0))
    TiltingActuation(tilting).desaturated(force, torque)
    TiltingActuation(tilting, objective="min_peak_speed").null_space_correction(np.ones(8))
    observer = MomentumObserver(1.5, np.ones(3), 10.0, 2, 0.001)
    observer.update(np.zeros(3), np.zeros(3), np.zeros(3), force, torque)
    observer.wrench_body()
    _ = observer.mass_estimate
    report = SaturationReport(4)
    report.record(0.0, np.ones(4))
    report.record_shortfall(np.ones(6))
    clamp_rotor_speeds(quad, np.ones(4))
    rotation = so3.rotation_from_euler_zyx(np.array((0.1, 0.2, 0.3)))
    so3.euler_zyx_from_rotation(rotation)
    so3.euler_rate_matrix(np.zeros(3))
    so3.euler_rate_matrix_derivative(np.zeros(3), np.zeros(3))
    so3.attitude_error(rotation, np.eye(3))
    so3.quaternion_from_rotation(rotation)
    flat_attitude_rates(np.zeros(3), np.zeros(3), np.zeros(3), 0.0, 0.0, 0.0)


def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="fsr-compile", doc=__doc__,
                            exit_codes={EXIT_OK: "done", EXIT_CONFIG_ERROR: "invalid arguments"})
    parser.parse_args(argv)
    from fsr_sim.core.jit import CACHE_FOLDER, numba

    if numba.config.DISABLE_JIT:
        print("fsr-compile: NUMBA_DISABLE_JIT is set: nothing to compile", file=sys.stderr)
        return 0
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        tour(Path(folder))
    print(f"fsr-compile: flight core compiled in {time.perf_counter() - start:.1f} s (cache: {CACHE_FOLDER})",
          file=sys.stderr)
    removed = prune_cache(CACHE_FOLDER.parent, CACHE_FOLDER)
    if removed:
        print(f"fsr-compile: removed {len(removed)} cache folder(s) of other versions of the core from "
              f"{CACHE_FOLDER.parent}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
