"""fsr's in-process loop and RotorPy 3.0 side by side: cost per 1 kHz step of a comparable closed-loop quadrotor
flight, and their ratio, measured in the same run (min and median of ``--repeat`` runs each).

    .venv/bin/python benchmarks/rotorpy_side_by_side.py [--seconds 5] [--repeat 3] [--venv DIR]

RotorPy is not a dependency of fsr: it is installed here into a throwaway virtual environment (``--venv``: a
folder to keep it in between runs; default a temporary folder removed at the end) from the package registry
(``rotorpy==3.0.0`` with its own dependencies; about a minute). Both fly a quadrotor on a smooth trajectory
with a geometric (SE(3)) controller at 1 kHz, no wind, no recording:

* RotorPy: ``Environment(Multirotor(crazyflie), SE3Control, ThreeDCircularTraj(radius 1 m), sim_rate=1000)``,
  ``run(t_final)``, its own per-step loop (SciPy ODE integration of the rigid body and rotor dynamics; its
  default IMU and motion-capture models are evaluated each step, unused by the controller);
* fsr: ``fly_in_process`` of ``ex4_geometric`` with rotor actuation (planner, geometric law with flatness
  rates, allocation, momentum observer, RK4 with ground effect), without recording.

Printed: microseconds per simulated step for each and ``rotorpy / fsr``.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
import venv
from pathlib import Path

ROTORPY = "rotorpy==3.0.0"
ROTORPY_FLIGHT = """
import sys, time
import numpy as np
from rotorpy.controllers.quadrotor_control import SE3Control
from rotorpy.environments import Environment
from rotorpy.trajectories.circular_traj import ThreeDCircularTraj
from rotorpy.vehicles.crazyflie_params import quad_params
from rotorpy.vehicles.multirotor import Multirotor
seconds = float(sys.argv[1])
env = Environment(vehicle=Multirotor(quad_params), controller=SE3Control(quad_params),
                  trajectory=ThreeDCircularTraj(radius=np.array([1.0, 1.0, 0.0])), sim_rate=1000)
start = time.perf_counter()
result = env.run(t_final=seconds, terminate=False, plot=False, animate_bool=False, verbose=False)
wall = time.perf_counter() - start
print(wall / len(result["time"]) * 1e6)
"""


def rotorpy_python(folder: Path) -> Path:
    """A virtual environment in ``folder`` with RotorPy installed (reused if it already has it)."""
    python = folder / "bin" / "python"
    if not python.is_file():
        print(f"installing {ROTORPY} into a throwaway environment in {folder} ...", file=sys.stderr, flush=True)
        venv.create(folder, with_pip=True)
    check = subprocess.run([str(python), "-c", "import rotorpy"], capture_output=True)
    if check.returncode != 0:
        subprocess.run([str(python), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", ROTORPY],
                       check=True)
    return python


def rotorpy_us_per_step(python: Path, seconds: float) -> float:
    done = subprocess.run([str(python), "-c", ROTORPY_FLIGHT, repr(seconds)], capture_output=True, text=True,
                          check=True)
    return float(done.stdout.strip().splitlines()[-1])


def fsr_us_per_step(seconds: float) -> float:
    from fsr_bringup.runner.in_process_flight import fly_in_process
    from fsr_sim.config.scenario import load_scenario

    scenario = load_scenario("ex4_geometric", ["actuation=rotors", f"duration={seconds}"])
    start = time.perf_counter()
    run = fly_in_process(scenario)
    return (time.perf_counter() - start) / len(run.time) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per flight (default 5)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--venv", type=Path, help="keep RotorPy's environment in this folder (default: temporary)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        python = rotorpy_python(args.venv or Path(scratch) / "rotorpy-venv")
        fsr_us_per_step(0.01)  # load the compiled core once (not part of the per-step figure)
        theirs = [rotorpy_us_per_step(python, args.seconds) for _ in range(args.repeat)]
        ours = [fsr_us_per_step(args.seconds) for _ in range(args.repeat)]
    ratio = [t / o for t, o in zip(sorted(theirs), sorted(ours), strict=True)]
    print(f"RotorPy 3.0 [us/step]: min {min(theirs):.0f} median {statistics.median(theirs):.0f}")
    print(f"fsr in-process [us/step]: min {min(ours):.2f} median {statistics.median(ours):.2f}")
    print(f"RotorPy / fsr: min {min(ratio):.0f} median {statistics.median(ratio):.0f} "
          f"({args.repeat} run(s) each, {args.seconds:g} s flights at 1 kHz)")


if __name__ == "__main__":
    main()
