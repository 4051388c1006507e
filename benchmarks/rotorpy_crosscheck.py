"""fsr's plant against RotorPy's, open loop: the ``hummingbird`` flown with the same rotor-speed commands in both
simulators, motor lag and every aerodynamic term on, and the largest differences of position, attitude and body
rates over the flight printed (docs/model.md §3.4, *Cross-check against RotorPy*).

    .venv/bin/python benchmarks/rotorpy_crosscheck.py [--seconds 3] [--dt 0.001] [--venv DIR]

RotorPy is not a dependency of fsr: it is installed here into a throwaway virtual environment (``--venv``: a
folder to keep it in between runs; default a temporary folder removed at the end) from the package registry
(``rotorpy==3.0.0``, about a minute). Its ``Multirotor`` (``rotorpy/vehicles/multirotor.py``) with its own
``hummingbird_params`` is stepped by ``Multirotor.step`` every ``dt`` with the held command
(``cmd_motor_speeds``), integrated by SciPy's ``solve_ivp`` with tight tolerances (DOP853, rtol = atol = 1e-12:
a converged solution, so every difference left is fsr's); fsr's :class:`~fsr_sim.model.plant.Plant` takes the
same commands, RK4 at ``dt``, without surfaces. Both start level at rest, 10 m up, the rotors at the first
command's speeds.

The commands: hover thrust (x 1.05) plus, through the allocation, body torques that would swing roll, pitch and
yaw as ``A (1 - cos(2 pi f t))`` from rest (A = 25, -20, 45 deg at 1.3, 0.9, 0.5 Hz) on the rigid body alone;
the aerodynamics damp them to about 45, 40 and 60 deg, and the mean tilt carries the vehicle to about 5 m/s.

Frames: RotorPy's world and body are z-up (body FLU); fsr's NED and FRD. ``P = diag(1, -1, -1)`` maps one to the
other: positions and velocities ``P x``, attitudes ``P R P``, body rates ``P omega``; a rotor at ``(x, y)`` in
RotorPy is at ``(x, -y)`` in fsr with the opposite spin sign (``ros_ws/src/fsr_sim/fsr_sim/config/vehicles/
hummingbird.yaml``).

Printed, per case (the whole model, without aerodynamics, each term alone, a steady wind, a 0.1 ms motor, and
RotorPy at its default integrator tolerances for scale): the largest position [m], attitude [deg] and body-rate
[rad/s] difference over the flight, and the motion's envelope (peak tilt, yaw and speed).
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
from rotorpy_side_by_side import rotorpy_python  # the same throwaway environment

FLIP = np.diag([1.0, -1.0, -1.0])  # z-up world / FLU body <-> NED world / FRD body
START_HEIGHT = 10.0  # m
WIND = (2.0, 1.0, 0.5)  # m/s, RotorPy's world (z up): the steady-wind case
FLAPPING = 5e-7  # kg m/rad: the flapping case's coefficient (the Hummingbird's is 0)
NO_ROTOR_TERMS = {"k_d": 0.0, "k_z": 0.0, "k_h": 0.0, "k_flap": 0.0}
NO_DRAG = {"c_Dx": 0.0, "c_Dy": 0.0, "c_Dz": 0.0}
ROTORPY_TERMS = {"c_D": ("drag_coefficients",), "k_d": ("rotor_drag_coefficient",),
                 "k_z": ("induced_inflow_coefficient",), "k_h": ("translational_lift_coefficient",),
                 "k_flap": ("flapping_coefficient",)}
TIGHT = {"method": "DOP853", "rtol": 1e-12, "atol": 1e-12}

# name, RotorPy aero flag, RotorPy parameter changes, wind (RotorPy's frame), RotorPy integrator
CASES = [
    ("every term, 5 ms motor", True, {}, (0.0, 0.0, 0.0), TIGHT),
    ("no aerodynamics", False, {}, (0.0, 0.0, 0.0), TIGHT),
    ("parasitic drag alone", True, NO_ROTOR_TERMS, (0.0, 0.0, 0.0), TIGHT),
    ("rotor drag alone", True, {**NO_DRAG, **NO_ROTOR_TERMS, "k_d": 1.19e-4}, (0.0, 0.0, 0.0), TIGHT),
    ("induced inflow alone", True, {**NO_DRAG, **NO_ROTOR_TERMS, "k_z": 2.32e-4}, (0.0, 0.0, 0.0), TIGHT),
    ("translational lift alone", True, {**NO_DRAG, **NO_ROTOR_TERMS, "k_h": 3.39e-3}, (0.0, 0.0, 0.0), TIGHT),
    (f"blade flapping alone (k_flap {FLAPPING:g})", True, {**NO_DRAG, **NO_ROTOR_TERMS, "k_flap": FLAPPING},
     (0.0, 0.0, 0.0), TIGHT),
    ("every term, steady wind", True, {}, WIND, TIGHT),
    ("every term, 0.1 ms motor", True, {"tau_m": 1e-4}, (0.0, 0.0, 0.0), TIGHT),
    ("every term, RotorPy RK45 default tolerances", True, {}, (0.0, 0.0, 0.0), {"method": "RK45"}),
]

ROTORPY_FLIGHTS = """
import json, sys
import numpy as np
from rotorpy.vehicles.hummingbird_params import quad_params
from rotorpy.vehicles.multirotor import Multirotor
spec = json.load(open(sys.argv[1]))
commands = np.load(spec["commands"])
dt = spec["dt"]
for index, case in enumerate(spec["cases"]):
    params = dict(quad_params)
    params.update(case["params"])
    start = {"x": np.array([0.0, 0.0, spec["height"]]), "v": np.zeros(3), "q": np.array([0.0, 0.0, 0.0, 1.0]),
             "w": np.zeros(3), "wind": np.array(case["wind"]), "rotor_speeds": commands[0].copy()}
    vehicle = Multirotor(params, initial_state=start, control_abstraction="cmd_motor_speeds", aero=case["aero"],
                         integrator_kwargs=case["integrator"])
    state = {key: value.copy() for key, value in start.items()}
    out = np.zeros((len(commands), 13))
    for k in range(len(commands)):
        state = vehicle.step(state, {"cmd_motor_speeds": commands[k]}, dt)
        out[k] = np.concatenate((state["x"], state["v"], state["q"], state["w"]))
    np.save(spec["out"] + f"_{index}.npy", out)
"""


def rotorpy_changes(vehicle, aero: bool, changes: dict):  # noqa: ANN001, ANN201 - a Vehicle
    """fsr's vehicle with RotorPy's parameter changes of a case (and without aerodynamics where RotorPy has
    ``aero=False``)."""
    values = {}
    if not aero:
        values = {"drag_coefficients": np.zeros(3), **{name[0]: 0.0 for key, name in ROTORPY_TERMS.items()
                                                        if key != "c_D"}}
    for key, value in changes.items():
        if key.startswith("c_D"):
            drag = np.array(values.get("drag_coefficients", vehicle.drag_coefficients), dtype=float)
            drag["xyz".index(key[-1])] = value
            values["drag_coefficients"] = drag
        elif key == "tau_m":
            values["rotor_time_constant"] = value
        else:
            values[ROTORPY_TERMS[key][0]] = value
    return replace(vehicle, **values)


def commands(vehicle, seconds: float, dt: float) -> np.ndarray:  # noqa: ANN001 - a Vehicle
    """Rotor speeds (N, 4) [rad/s], fsr's rotor order (module docstring)."""
    from fsr_sim.model.rotors import wrench_from_rotor_speed_sq

    t = np.arange(int(round(seconds / dt))) * dt
    frequency = 2.0 * math.pi * np.array([1.3, 0.9, 0.5])
    amplitude = np.radians([25.0, -20.0, 45.0])
    torque = (np.diag(vehicle.inertia) * amplitude * frequency**2)[:, None] * np.cos(frequency[:, None] * t)
    thrust = np.full(len(t), -1.05 * vehicle.weight)
    rows = wrench_from_rotor_speed_sq(vehicle)[2:]  # f_z, tau_x, tau_y, tau_z
    squared = np.linalg.solve(rows, np.vstack((thrust, torque))).T
    return np.sqrt(np.clip(squared, 0.0, None))


def fsr_flight(vehicle, speeds: np.ndarray, dt: float, wind: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """fsr's states (N, 13) after each command: position, velocity, quaternion [x, y, z, w], body rates."""
    from fsr_sim.model.environment import Environment, Surface
    from fsr_sim.model.plant import Plant
    from fsr_sim.model.turbulence import DrydenTurbulence

    steady = [DrydenTurbulence(wind_speed=0.0, altitude=START_HEIGHT, mean=wind)] if np.any(wind) else []
    plant = Plant(vehicle, dt, position=(0.0, 0.0, -START_HEIGHT), environment=Environment(ground=Surface(
        enabled=False)), turbulence=steady)
    out = np.zeros((len(speeds), 13))
    for k, command in enumerate(speeds):
        plant.set_rotor_command(command)
        plant.step()
        out[k] = plant.state_vector
    return out


def differences(ours: np.ndarray, theirs: np.ndarray) -> tuple[float, float, float]:
    """Largest position [m], attitude [deg] and body-rate [rad/s] difference, RotorPy's states mapped to NED."""
    from scipy.spatial.transform import Rotation

    position = np.abs(ours[:, :3] - theirs[:, :3] @ FLIP).max()
    flipped = FLIP @ Rotation.from_quat(theirs[:, 6:10]).as_matrix() @ FLIP
    relative = Rotation.from_matrix(np.einsum("kji,kjl->kil", Rotation.from_quat(ours[:, 6:10]).as_matrix(),
                                              flipped))
    attitude = np.degrees(relative.magnitude()).max()
    rates = np.abs(ours[:, 10:13] - theirs[:, 10:13] @ FLIP).max()
    return float(position), float(attitude), float(rates)


def envelope(states: np.ndarray) -> str:
    from scipy.spatial.transform import Rotation

    rotation = Rotation.from_quat(states[:, 6:10]).as_matrix()
    tilt = np.degrees(np.arccos(np.clip(rotation[:, 2, 2], -1.0, 1.0))).max()
    yaw = np.degrees(np.abs(np.arctan2(rotation[:, 1, 0], rotation[:, 0, 0]))).max()
    speed = np.linalg.norm(states[:, 3:6], axis=1).max()
    return f"peak tilt {tilt:.0f} deg, peak yaw {yaw:.0f} deg, peak speed {speed:.1f} m/s"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seconds", type=float, default=3.0, help="simulated seconds (default 3)")
    parser.add_argument("--dt", type=float, default=0.001, help="fsr's RK4 step and the command period [s]")
    parser.add_argument("--venv", type=Path, help="keep RotorPy's environment in this folder (default: temporary)")
    args = parser.parse_args()
    from fsr_sim.model import load_vehicle

    hummingbird = load_vehicle("hummingbird")
    speeds = commands(hummingbird, args.seconds, args.dt)
    with tempfile.TemporaryDirectory() as scratch:
        python = rotorpy_python(args.venv or Path(scratch) / "rotorpy-venv")
        np.save(Path(scratch) / "commands.npy", speeds)
        spec = {"commands": str(Path(scratch) / "commands.npy"), "dt": args.dt, "height": START_HEIGHT,
                "out": str(Path(scratch) / "rotorpy"),
                "cases": [{"aero": aero, "params": changes, "wind": list(wind), "integrator": integrator}
                          for _, aero, changes, wind, integrator in CASES]}
        (Path(scratch) / "spec.json").write_text(json.dumps(spec))
        subprocess.run([str(python), "-c", ROTORPY_FLIGHTS, str(Path(scratch) / "spec.json")], check=True)
        theirs = [np.load(Path(scratch) / f"rotorpy_{index}.npy") for index in range(len(CASES))]
    print(f"hummingbird open loop, {args.seconds:g} s at dt = {args.dt:g} s, fsr RK4 vs RotorPy 3.0.0 "
          f"(solve_ivp DOP853, rtol = atol = 1e-12 unless said)")
    print()
    print("| case | position [m] | attitude [deg] | body rates [rad/s] | motion (fsr) |")
    print("|---|---|---|---|---|")
    for (name, aero, changes, wind, _), reference in zip(CASES, theirs, strict=True):
        vehicle = rotorpy_changes(hummingbird, aero, changes)
        ours = fsr_flight(vehicle, speeds, args.dt, FLIP @ np.array(wind))
        position, attitude, rates = differences(ours, reference)
        print(f"| {name} | {position:.2e} | {attitude:.2e} | {rates:.2e} | {envelope(ours)} |")


if __name__ == "__main__":
    main()
