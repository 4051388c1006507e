"""The compiled flight core: one source that runs compiled and under CPython with the same numbers, a cache that
no flight or node has to fill, and a cache key that changes with the core's sources."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

FLY = str(Path(sys.executable).parent / "fsr-fly")
REALISM = {"duration": 2.0, "plant.rotor_time_constant": 0.02, "sensors.odometry.position_std": 0.001,
           "sensors.odometry.position_bias_walk": 0.001, "sensors.odometry.delay_steps": 2,
           "sensors.odometry.rate_hz": 500, "controller.acceleration_filter_hz": 20.0,
           "sensors.imu": {"gyro_noise_density": 0.0003, "accelerometer_noise_density": 0.002,
                           "gyro_bias_walk": 0.0001, "accelerometer_bias_walk": 0.001, "delay_steps": 1,
                           "rate_hz": 500, "accelerometer_initial_bias": 0.1, "seed": 4}}
AGILE = {"duration": 2.0, "vehicle": "hummingbird", "actuation": "rotors", "plant.flapping_coefficient": 1e-6,
         "trajectory.waypoints": [{"position": [1.0, -0.5, -1.5], "attitude_rpy_deg": [0, 0, 30], "duration": 1.5}],
         "controller.gains": {"k_p": [8, 8, 8], "k_v": [4, 4, 4], "k_r": [1.46, 1.47, 0.7], "k_w": [0.15, 0.15, 0.14]},
         "disturbances": [{"kind": "dryden", "wind_speed": 4.0, "altitude": 2.0, "mean": [2.0, 1.0, 0.0], "seed": 2}]}
SHORT = {"duration": 6.0}  # the transients, the estimator's settling and the octocopter's ground effect (CPython: slow)
FLIGHTS = (("ex3_estimation", SHORT), ("ex4_geometric", {**SHORT, "actuation": "rotors"}), ("ex5_voliro", SHORT),
           ("octo_ground_effect", SHORT), ("wind_rejection_turbulent", REALISM),  # gusts, rotor lag, sensor stage
           ("ex5_voliro", {"duration": 2.0, "plant.tilt_time_constant": 0.03, "plant.tilt_rate_max_deg_s": 120}),
           ("ex4_geometric", AGILE),  # the Hummingbird: motor lag and every aerodynamic term in a gusty wind
           # the flight profile: reference feed-forward, the integral held by the allocation's shortfall, the
           # compensated estimate's filtered rates; and the report's measured feed-forward with an integral
           ("step_disturbance", {**REALISM, "disturbances.0.start": 0.5, "controller.compensation": "estimate"}),
           ("ex4_geometric", {"duration": 2.0, "actuation": "rotors", "controller.gains.k_i": [1.0, 1.0, 2.0]}),
           # INDI on the noisy IMU and the Hummingbird's measured rotor speeds through a force and torque step;
           # the compensating observer and the estimator on the rotors' measured speeds (estimator.input)
           ("step_disturbance", {**REALISM, "vehicle": "hummingbird", "controller.type": "indi",
                                 "estimator.enabled": False, "disturbances": [
                                     {"kind": "step", "frame": "world", "start": 0.5, "force": [1.0, 0.5, 0.0],
                                      "torque": [0.01, -0.01, 0.005]}]}),
           ("wind_rejection", {"duration": 2.0, "plant.rotor_time_constant": 0.05, "estimator.input": "measured",
                               "controller.compensation": "estimate"}))

FINAL_STATES = """
import json, sys
import numpy as np
from fsr_bringup import simulate
flights = json.loads(sys.argv[1])
runs = [simulate(name, set=values) for name, values in flights]
print(json.dumps([np.concatenate([run.state[-1]] + [values.sum(axis=0) for values in (
    run.imu_angular_velocity_measured, run.imu_specific_force_measured, run.imu_specific_force_true)
    if values is not None]).tolist() for run in runs]))
"""


def compiled_and_cpython(script: str, argument: str, timeout: float = 280.0) -> tuple[list, list]:
    """The JSON that ``script`` prints, compiled and under CPython (NUMBA_DISABLE_JIT=1): both processes at once
    (each is one core's work)."""
    processes = [subprocess.Popen([sys.executable, "-c", script, argument], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL,
                                  env={**os.environ, "NUMBA_DISABLE_JIT": disable})
                 for disable in ("0", "1")]
    try:
        outputs = [process.communicate(timeout=timeout) for process in processes]
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait()
    for process, (_, err) in zip(processes, outputs, strict=True):
        assert process.returncode == 0, err
    return json.loads(outputs[0][0]), json.loads(outputs[1][0])


@pytest.mark.slow
def test_compiled_and_cpython_flights_are_bit_identical():
    """The same source, compiled (fastmath off) and under CPython (NUMBA_DISABLE_JIT=1): identical final states
    of whole flights (ex3, ex4 with rotors, ex5, the octocopter through its ground effect; turbulence, actuator
    dynamics and the sensor stages: the sums of an IMU's measured and true samples too; the Hummingbird with
    every aerodynamic term in a gusty wind)."""
    compiled, python = ([np.array(row) for row in rows]
                        for rows in compiled_and_cpython(FINAL_STATES, json.dumps(FLIGHTS)))
    assert len(compiled[4]) == 13 + 9  # the flight with an IMU
    for a, b in zip(compiled, python, strict=True):
        assert np.array_equal(a, b), np.abs(a - b).max()


SWEEP_ROWS = """
import json, sys
from fsr_bringup.sweeps.batch import fly_one
from fsr_sim.config.scenario import load_scenario
flights = json.loads(sys.argv[1])
rows = [fly_one(load_scenario(name, values=fixed), values)[0] for name, fixed, values in flights]
print(json.dumps(rows))
"""
SWEEP_FLIGHTS = (("ex4_geometric", {"duration": 0.3}, {"plant.mass": 1.3}),  # wrench actuation
                 ("octo_ground_effect", {"duration": 0.3}, {"plant.mass": 2.5}),  # rotors, ground effect
                 ("ex5_voliro", {"duration": 0.3, "plant.tilt_time_constant": 0.03}, {}))  # tilts that lag


@pytest.mark.slow
def test_a_sweep_flight_measured_in_the_loop_is_the_same_compiled_and_under_cpython():
    """The loop that measures a sweep's flight as it flies (fsr_bringup.core.flight_measures): the same row
    compiled and under CPython."""
    rows = compiled_and_cpython(SWEEP_ROWS, json.dumps(SWEEP_FLIGHTS))
    for compiled, python in zip(*rows, strict=True):
        assert compiled.keys() == python.keys()
        for key, value in compiled.items():
            assert value == pytest.approx(python[key], rel=1e-12, nan_ok=True) if isinstance(value, float) \
                else value == python[key], key


@pytest.fixture(scope="module")
def compiled() -> None:
    """``fsr-compile`` run once (scripts/setup.sh runs it) for the tests that check that nothing compiles after it
    (a run with the cache filled still flies every built-in scenario: seconds, paid once here)."""
    subprocess.run([str(Path(sys.executable).parent / "fsr-compile")], env={**os.environ, "MPLBACKEND": "Agg"},
                   check=True, capture_output=True, timeout=280)


@pytest.mark.slow
def test_a_sweep_compiles_nothing_with_the_cache_filled(tmp_path, compiled):
    """After fsr-compile, fsr-sweep's flights (measured in the loop, wrench actuation and rotors with the
    estimator) only load compiled code."""
    env = {**os.environ, "NUMBA_DEBUG_CACHE": "1", "MPLBACKEND": "Agg"}
    for scenario in ("ex4_geometric", "wind_rejection"):
        sweep = subprocess.run([str(Path(sys.executable).parent / "fsr-sweep"), scenario, "--sample",
                                "plant.mass=uniform:1.2:1.4", "--n", "3", "--duration", "0.1", "--out", scenario],
                               cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
        assert sweep.returncode == 0, sweep.stderr
        assert "[cache] data loaded" in sweep.stdout
        assert "[cache] data saved" not in sweep.stdout


@pytest.mark.graph
def test_no_flight_and_no_node_compiles_with_the_cache_filled(tmp_path, compiled):
    """After fsr-compile (scripts/setup.sh runs it) an in-process flight and every node of a graph flight only
    load compiled code: numba's cache reports loads, never a save."""
    env = {**os.environ, "NUMBA_DEBUG_CACHE": "1", "MPLBACKEND": "Agg"}
    in_process = subprocess.run([FLY, "ex5_voliro", "--in-process", "--duration", "0.1", "--out", "a.mcap"],
                                cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert in_process.returncode == 0, in_process.stderr
    graph = subprocess.run([FLY, "ex5_voliro", "--duration", "0.05", "--out", "b.mcap", "--no-analysis"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert graph.returncode == 0, graph.stderr
    logs = [in_process.stdout, *(path.read_text() for path in (tmp_path / "b" / "logs").glob("*.log"))]
    assert any("[cache] data loaded" in text for text in logs[1:])  # the nodes use the cache ...
    saved = [line for text in logs for line in text.splitlines() if "[cache] data saved" in line]
    assert not saved  # ... and compile nothing


def test_cache_key_follows_every_core_source(tmp_path, monkeypatch):
    """The cache folder is named by a hash of the core's files: any change to any of them (also a function
    called from another file, which numba's own cache would not notice) gives a new folder."""
    from fsr_sim.core import jit

    sources = jit.core_sources()
    assert {path.parent.parent.name for path in sources} == set(jit.CORE_PACKAGES)
    assert all("@jit" in path.read_text() for path in sources if path.name != "jit.py")
    files = [tmp_path / "a.py", tmp_path / "b.py"]
    for path in files:
        path.write_text("x = 1\n")
    monkeypatch.setattr(jit, "core_sources", lambda: files)
    before = jit.core_key()
    files[1].write_text("x = 2\n")
    assert jit.core_key() != before
    files[1].write_text("x = 1\n")
    assert jit.core_key() == before


def test_unwritable_cache_base_falls_back_to_a_temporary_folder(tmp_path):
    from fsr_sim.core import jit

    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    folder = jit.cache_folder(blocked)
    assert folder.is_dir() and blocked not in folder.parents


@pytest.mark.parametrize("scenario", ["ex4_geometric", "wind_rejection"])  # wrench actuation; rotors that lag
def test_a_flight_set_up_from_the_packed_sweep_is_the_compiled_loop_of_a_full_set_up(scenario):
    """A sweep's flight set up from its packed scenario (fsr_bringup.sweeps.repack) hands the compiled loop
    arguments of the numba types the full set-up hands it (read-only arrays where that packs the vehicle's
    read-only ones): the loop fsr-compile compiled, never a second compilation of it (minutes) in a sweep."""
    from dataclasses import fields

    from numba import typeof

    from fsr_bringup.runner.in_process_flight import prepare_flight
    from fsr_bringup.sweeps.axes import flight_scenario
    from fsr_bringup.sweeps.batch import packed_sweep
    from fsr_bringup.sweeps.measured import loop_flight
    from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M
    from fsr_sim.config.scenario import load_scenario

    base = load_scenario(scenario, values={"duration": 0.1})
    packed = packed_sweep(base, DEFAULT_BAND_M)
    for values in ({"plant.mass": 1.3}, {"plant.inertia": [0.03, 0.03, 0.06]}, {"estimator.c0": 5.0},
                   {"plant.mass": 1.4, "plant.inertia": [[0.03, 0.001, 0.0], [0.001, 0.03, 0.0], [0.0, 0.0, 0.06]]}):
        flight = packed.flight_for(values)
        assert flight is not None, values
        full = loop_flight(prepare_flight(flight_scenario(base, values)), DEFAULT_BAND_M)
        for field in fields(full):
            assert typeof(getattr(flight, field.name)) == typeof(getattr(full, field.name)), (values, field.name)


@pytest.mark.parametrize("scenario, values", [("ex4_geometric", {}), ("ex4_geometric", {"actuation": "rotors"}),
                                              ("wind_rejection", {}), ("ex5_voliro", {})])
def test_a_recorded_flight_and_a_measured_flight_call_the_same_compiled_loop(scenario, values, monkeypatch):
    """The in-process flight (written out, nothing measured: fsr_bringup.core.flight_measures.unmeasured) and a
    sweep's flight measured in the loop hand fsr_bringup.core.flight_loop.fly arguments of the same numba types
    (read-only arrays where the other has read-only ones): one compilation of the loop in fsr-compile, not two."""
    from numba import typeof

    from fsr_bringup.core import flight_loop
    from fsr_bringup.runner.in_process_flight import prepare_flight
    from fsr_bringup.sweeps import measured
    from fsr_bringup.sweeps.metrics import DEFAULT_BAND_M
    from fsr_sim.config.scenario import load_scenario

    calls = []

    def capture(*arguments):  # noqa: ANN002, ANN202 - the loop's arguments
        calls.append(arguments)
        return flight_loop.FINISHED, 0, 0

    monkeypatch.setattr(flight_loop, "fly", capture)
    monkeypatch.setattr(measured, "fly", capture)
    scenario_values = {**values, "duration": 0.1}
    prepare_flight(load_scenario(scenario, values=scenario_values)).fly(0, 1)
    measured.fly_accumulated(measured.loop_flight(prepare_flight(load_scenario(scenario, values=scenario_values)),
                                                  DEFAULT_BAND_M))
    recorded, measuring = calls
    assert len(recorded) == len(measuring)
    for k, (left, right) in enumerate(zip(recorded, measuring, strict=True)):  # `what` differs, an int in both
        assert typeof(left) == typeof(right), (k, typeof(left), typeof(right))
