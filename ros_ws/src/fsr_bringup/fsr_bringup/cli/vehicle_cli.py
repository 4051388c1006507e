"""``fsr-vehicle NAME [--json]``: a vehicle's parameters and its allocation matrices.

Markdown by default; ``--json`` prints an object with ``mass``, ``inertia`` (3x3), ``c_f``, ``c_m``,
``arm_length``, ``rotor_radius``, ``contact_height`` (landing gear below the centre of mass), rotor limits,
``rotor_time_constant`` [s], ``drag_coefficients`` [N s^2/m^2] and the rotors' aerodynamic coefficients
(``rotor_drag_coefficient``, ... : docs/vehicles.md), ``rotors`` (position, spin, tilt axis), ``allocation``
(6 x n, squared rotor speeds -> body wrench, rows f_x f_y f_z tau_x tau_y tau_z), for a coplanar vehicle
also ``allocation_4xn`` (the report's G_q rows f_z tau_x tau_y tau_z), and for a tilting vehicle
``allocation_static`` (6 x 2n, docs/model.md §3.2); ``authority`` is what the rotors give at hover at margin 1
(the model's limits, :mod:`fsr_control.design.authority`): ``thrust_min``, ``thrust_max`` [N], ``roll_torque``,
``pitch_torque``, ``yaw_torque`` [N m], ``roll_acceleration``, ``pitch_acceleration``, ``yaw_acceleration``
[rad/s^2] and ``tilt_max`` [rad] (null unless fully actuated); null, with the reason in ``authority_error``, for a
vehicle that cannot hover. ``designed_gains`` are the loop bandwidths [rad/s] and gains of ``controller.profile:
flight`` (:mod:`fsr_control.design.gain_design`): ``attitude``, ``yaw``, ``horizontal``, ``vertical``, what set each
(``limits``), the lag designed for (``lag_s``), ``wrench_gains`` (the geometric law's, N/m ... N m s/rad) and
``acceleration_gains`` (the Voliro law's, 1/s^2 and 1/s); null when the authority is. ``designed_gains_imu``: the
same for the geometric law flying on the IMU (``controller.use_imu``, the flight profile's default where the
scenario has an IMU: no odometry delay in its lag); null for a fully actuated vehicle (its law has no such mode).
"""

from __future__ import annotations

import json
import sys

import numpy as np

from fsr_control.design.authority import Authority, authority
from fsr_control.design.gain_design import CASCADE_RATIO, GainDesign, design_gains
from fsr_sim.cli.arguments import ArgumentParser
from fsr_sim.config.validation import ConfigError, builtin_names
from fsr_sim.contract import EXIT_CONFIG_ERROR, EXIT_OK
from fsr_sim.model.rotors import (
    octocopter_allocation_4x8,
    static_tilting_allocation,
    wrench_from_rotor_speed_sq,
)
from fsr_sim.model.vehicle import ROTOR_AERODYNAMICS, Vehicle, load_vehicle

WRENCH_ROWS = ("f_x", "f_y", "f_z", "tau_x", "tau_y", "tau_z")


def vehicle_summary(vehicle: Vehicle) -> dict:
    """Everything ``--json`` prints, as plain Python data."""
    rotors = []
    for i in range(vehicle.rotor_count):
        rotors.append(
            {
                "index": i + 1,
                "position": vehicle.positions[i].tolist(),
                "spin": int(vehicle.spins[i]),
                "axis": vehicle.thrust_axes[i].tolist(),
                "tilt_axis": None if vehicle.tilt_axes is None else vehicle.tilt_axes[i].tolist(),
            }
        )
    summary = {
        "name": vehicle.name,
        "description": vehicle.description,
        "mass": vehicle.mass,
        "inertia": vehicle.inertia.tolist(),
        "c_f": vehicle.c_f,
        "c_m": vehicle.c_m,
        "arm_length": vehicle.arm_length,
        "rotor_radius": vehicle.rotor_radius,
        "contact_height": vehicle.contact_height,
        "rotor_speed_min": vehicle.rotor_speed_min,
        "rotor_speed_max": vehicle.rotor_speed_max,
        "hover_rotor_speed": float(np.sqrt(vehicle.weight / (vehicle.c_f * np.sum(-vehicle.thrust_axes[:, 2])))),
        "rotor_time_constant": vehicle.rotor_time_constant,
        "drag_coefficients": vehicle.drag_coefficients.tolist(),
        **{name: getattr(vehicle, name) for name in ROTOR_AERODYNAMICS},
        "rotors": rotors,
        "fully_actuated": vehicle.fully_actuated,
        "allocation_rows": list(WRENCH_ROWS),
        "allocation": wrench_from_rotor_speed_sq(vehicle).tolist(),
    }
    try:
        model_authority = authority(vehicle, margin=1.0)
    except ValueError as error:  # a vehicle that cannot hover: the rest still printed
        summary["authority"], summary["authority_error"], summary["designed_gains"] = None, str(error), None
        summary["designed_gains_imu"] = None
    else:
        summary["authority"] = model_authority.as_dict()
        summary["designed_gains"] = design_gains(vehicle, model_authority).as_dict()
        summary["designed_gains_imu"] = None if vehicle.fully_actuated else \
            design_gains(vehicle, model_authority, imu=True).as_dict()
    if vehicle.has_servos:
        summary["tilt_angle_max"] = vehicle.tilt_angle_max
        summary["allocation_static"] = static_tilting_allocation(vehicle).tolist()
    elif not vehicle.fully_actuated:
        summary["allocation_4xn"] = octocopter_allocation_4x8(vehicle).tolist()
    return summary


def _markdown_matrix(matrix: np.ndarray, rows: tuple[str, ...], columns: list[str]) -> str:
    lines = ["| | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    for name, row in zip(rows, matrix, strict=True):
        lines.append(f"| {name} | " + " | ".join(f"{v:.6g}" for v in row) + " |")
    return "\n".join(lines)


def _authority_markdown(values: Authority) -> list[str]:
    tilt = "- (hovers level only)" if values.tilt_max is None else f"{np.rad2deg(values.tilt_max):.1f} deg"
    return [
        f"Authority at hover (margin {values.margin:g}: the model's limits; a scenario's "
        "trajectory.authority_margin scales them):",
        "",
        "| axis | value |",
        "|---|---|",
        f"| hover thrust m g | {values.hover_thrust:.4g} N |",
        f"| thrust range (zero torque) | {values.thrust_min:.4g} .. {values.thrust_max:.4g} N |",
        f"| roll torque (+-) | {values.roll_torque:.4g} N m ({values.roll_acceleration:.4g} rad/s^2) |",
        f"| pitch torque (+-) | {values.pitch_torque:.4g} N m ({values.pitch_acceleration:.4g} rad/s^2) |",
        f"| yaw torque (+-) | {values.yaw_torque:.4g} N m ({values.yaw_acceleration:.4g} rad/s^2) |",
        f"| hover tilt (roll or pitch) | {tilt} |",
    ]


def _gain_text(gain: np.ndarray) -> str:
    """A gain's diagonal (or the whole matrix when it is not diagonal), 4 digits."""
    gain = np.asarray(gain)
    values = np.diag(gain) if np.count_nonzero(gain - np.diag(np.diag(gain))) == 0 else gain
    return str(np.vectorize(lambda v: float(f"{v:.4g}"))(values).tolist())


def _design_markdown(design: GainDesign, fully_actuated: bool, imu: bool = False) -> list[str]:
    settings = {"lag": "the lag", "authority": "the authority", "cascade": f"attitude / {CASCADE_RATIO:g}"}
    lag = "motor and half an IMU sample: the law flies on the IMU, `controller.use_imu`" if imu else \
        "motor, onboard odometry's delay and rate"
    lines = [
        f"Gains designed from the vehicle (`controller.profile: flight`, docs/control.md) for "
        f"{design.lag * 1e3:.1f} ms of lag ({lag}; every loop below "
        f"{design.lag_bandwidth:.3g} rad/s), damping {design.damping:g}:",
        "",
        "| loop | bandwidth | set by |",
        "|---|---|---|",
    ]
    for name, label in (("attitude", "roll / pitch"), ("yaw", "yaw"), ("horizontal", "position x / y"),
                        ("vertical", "position z")):
        lines.append(f"| {label} | {getattr(design, name):.3g} rad/s | {settings[design.limits[name]]} |")
    if fully_actuated:
        law, gains = "voliro (1/s^2, 1/s)", design.acceleration_gains()
    else:
        law, gains = "geometric (N/m, N s/m, N/(m s), N m/rad, N m s/rad)", design.wrench_gains()
    lines += ["", f"| gain, {law} | value |", "|---|---|"]
    lines += [f"| {name} | {_gain_text(value)} |" for name, value in gains.items()]
    if not fully_actuated:
        lines.append(f"| integral_limit | {design.integral_limit:.4g} N |")
    return lines


def vehicle_markdown(vehicle: Vehicle) -> str:
    s = vehicle_summary(vehicle)
    out = [
        f"# {vehicle.name}",
        "",
        vehicle.description,
        "",
        "| parameter | value |",
        "|---|---|",
        f"| mass | {vehicle.mass} kg |",
        f"| inertia (body FRD) | {vehicle.inertia.tolist()} kg m^2 |",
        f"| c_f | {vehicle.c_f:.6g} N/(rad/s)^2 |",
        f"| c_m | {vehicle.c_m:.6g} N m/(rad/s)^2 |",
        f"| arm length | {s['arm_length']:.4g} m |",
        f"| rotor radius | {vehicle.rotor_radius} m |",
        f"| contact height (feet below the CoM) | {vehicle.contact_height} m |",
        f"| rotor speed | {vehicle.rotor_speed_min} .. {vehicle.rotor_speed_max} rad/s |",
        f"| hover rotor speed | {s['hover_rotor_speed']:.1f} rad/s |",
        f"| fully actuated | {'yes' if vehicle.fully_actuated else 'no'} |",
        f"| rotor time constant | {vehicle.rotor_time_constant:g} s |",
        f"| parasitic drag c_x, c_y, c_z | {vehicle.drag_coefficients.tolist()} N s^2/m^2 |",
        f"| rotor drag k_d, inflow k_z | {vehicle.rotor_drag_coefficient:.6g}, "
        f"{vehicle.induced_inflow_coefficient:.6g} kg/rad |",
        f"| translational lift k_h | {vehicle.translational_lift_coefficient:.6g} kg/m |",
        f"| blade flapping k_flap | {vehicle.flapping_coefficient:.6g} kg m/rad |",
        "",
        "| rotor | position [m] | spin k_i | thrust axis | tilt axis |",
        "|---|---|---|---|---|",
    ]
    for rotor in s["rotors"]:
        axis = "-" if rotor["tilt_axis"] is None else np.round(rotor["tilt_axis"], 4).tolist()
        out.append(f"| {rotor['index']} | {np.round(rotor['position'], 4).tolist()} | {rotor['spin']:+d} | "
                   f"{np.round(rotor['axis'], 4).tolist()} | {axis} |")
    n = vehicle.rotor_count
    out += ["", "Allocation (body wrench from squared rotor speeds u_w,i):", ""]
    out.append(_markdown_matrix(np.array(s["allocation"]), WRENCH_ROWS, [f"u_w{i + 1}" for i in range(n)]))
    if vehicle.has_servos:
        columns = [f"u_{kind}{i + 1}" for i in range(n) for kind in ("v", "l")]
        out += ["", "Static allocation (body wrench from u = [u_v1, u_l1, ...], N):", ""]
        out.append(_markdown_matrix(np.array(s["allocation_static"]), WRENCH_ROWS, columns))
    elif not vehicle.fully_actuated:
        out += ["", "G_q (rows f_z, tau_x, tau_y, tau_z):", ""]
        out.append(
            _markdown_matrix(np.array(s["allocation_4xn"]), WRENCH_ROWS[2:], [f"u_w{i + 1}" for i in range(n)])
        )
    if s["authority"] is None:
        out += ["", f"Authority at hover: none ({s['authority_error']})."]
    else:
        out += ["", *_authority_markdown(Authority(**s["authority"]))]
        model_authority = Authority(**s["authority"])
        out += ["", *_design_markdown(design_gains(vehicle, model_authority), vehicle.fully_actuated)]
        if not vehicle.fully_actuated:
            on_imu, design = design_gains(vehicle, model_authority, imu=True), design_gains(vehicle, model_authority)
            if all(np.array_equal(a, b) for a, b in zip(on_imu.wrench_gains().values(),
                                                        design.wrench_gains().values(), strict=True)):
                out += ["", f"On the IMU (`controller.use_imu`: {on_imu.lag * 1e3:.1f} ms of lag) the same gains: "
                        "no loop is set by the lag."]
            else:
                out += ["", *_design_markdown(on_imu, False, imu=True)]
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = ArgumentParser(prog="fsr-vehicle", doc=__doc__, exit_codes={
        EXIT_OK: "done", EXIT_CONFIG_ERROR: "unknown vehicle, invalid vehicle file or argument"})
    parser.add_argument("vehicle", help=f"built-in name ({', '.join(builtin_names('vehicles'))}) or YAML path")
    parser.add_argument("--json", action="store_true", help="print JSON instead of Markdown")
    args = parser.parse_args(argv)
    try:
        vehicle = load_vehicle(args.vehicle)
    except ConfigError as error:
        print(f"fsr-vehicle: error: {error}", file=sys.stderr)
        return EXIT_CONFIG_ERROR
    if args.json:
        print(json.dumps(vehicle_summary(vehicle), indent=2))
    else:
        print(vehicle_markdown(vehicle), end="")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
