"""Vehicle YAML files: the format, and parsing into a :class:`fsr_sim.model.vehicle.Vehicle`.

A file gives ``name``, ``mass`` [kg], ``inertia`` (3 numbers or 3x3) [kg m^2], ``c_f``, ``c_m``,
``rotor_radius`` [m], ``rotor_speed_min``/``rotor_speed_max`` [rad/s], optional ``tilt_angle_max_deg``,
``contact_height`` and ``top_height`` [m], the actuator dynamics and aerodynamics of :func:`dynamics_and_drag`,
and either a ``layout`` (``count`` rotors on a circle of radius
``arm_length``, rotor ``i`` at angle ``first_angle_deg + (i-1) 360/count``, ``k_i = (-1)^i`` so rotor 1 is CW;
optional ``cant_deg``: each rotor's thrust axis turned about its arm by ``+cant``, ``-cant``, ... alternately
(a fully actuated "tilted-arm" multirotor); optional ``tilting: true`` for a servo tilt axis along each arm)
or an explicit ``rotors`` list of ``{position, spin, axis, tilt_axis}`` (``axis``: the fixed thrust axis,
default ``[0, 0, -1]``; ``tilt_axis``: the servo's, normal to ``axis``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from fsr_sim.config.validation import (
    ConfigError,
    Section,
    checked_array,
    checked_spd,
    load_yaml_file,
    resolve_config_path,
)
from fsr_sim.model.checks import InvalidValueError
from fsr_sim.model.vehicle import ROTOR_AERODYNAMICS, Vehicle


def load_vehicle_file(name_or_path: str | Path) -> Vehicle:
    """A built-in vehicle name or a YAML path -> :class:`Vehicle` (ConfigError naming file and key).

    A file whose text was validated before in this process is not validated again (a run's set-up reads the
    vehicle several times, a sweep once per flight; :class:`Vehicle` is frozen, so the one object is shared)."""
    path = resolve_config_path(str(name_or_path), "vehicles")
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        text = None  # load_yaml_file names the error
    key = (str(path), text)
    vehicle = _VEHICLES.get(key) if text is not None else None
    if vehicle is None:
        vehicle = vehicle_from_mapping(load_yaml_file(path), source=str(path), default_name=path.stem)
        if len(_VEHICLES) >= 64:
            _VEHICLES.clear()
        _VEHICLES[key] = vehicle
    return vehicle


_VEHICLES: dict[tuple[str, str | None], Vehicle] = {}


def vehicle_from_mapping(data: dict[str, Any], source: str = "", default_name: str = "vehicle") -> Vehicle:
    """Build and validate a :class:`Vehicle` from a mapping (the YAML file's content)."""
    root = Section(data, "", source)
    name = root.string("name", default_name)
    description = root.string("description", "")
    mass = root.number("mass", strictly_positive=True)
    inertia = checked_spd(root.raw("inertia"), "inertia", source)
    c_f = root.number("c_f", strictly_positive=True)
    c_m = root.number("c_m", minimum=0.0)
    rotor_radius = root.number("rotor_radius", strictly_positive=True)
    speed_min = root.number("rotor_speed_min", 0.0, minimum=0.0)
    speed_max = root.number("rotor_speed_max", strictly_positive=True)
    if speed_max <= speed_min:
        raise root.error("rotor_speed_max", f"must be > rotor_speed_min ({speed_min}), got {speed_max}")
    tilt_max = np.deg2rad(root.number("tilt_angle_max_deg", 180.0, strictly_positive=True, maximum=180.0))
    contact_height = root.number("contact_height", 0.1, minimum=0.0)
    top_height = root.number("top_height", contact_height, minimum=0.0)  # default: symmetric about the CoM
    dynamics = dynamics_and_drag(root, {"rotor_time_constant": 0.0, "tilt_time_constant": 0.0,
                                        "tilt_rate_max": np.inf, "drag_coefficients": np.zeros(3),
                                        **dict.fromkeys(ROTOR_AERODYNAMICS, 0.0)})

    if root.has("layout") == root.has("rotors"):
        raise root.error("layout", "give exactly one of 'layout' or 'rotors'")
    if root.has("layout"):
        positions, spins, thrust_axes, tilt_axes = _rotors_from_layout(root.section("layout"))
    else:
        positions, spins, thrust_axes, tilt_axes = _rotors_from_list(root.raw("rotors"), source)
    root.reject_unknown()

    try:
        return Vehicle(
            name=name,
            mass=mass,
            inertia=inertia,
            c_f=c_f,
            c_m=c_m,
            rotor_radius=rotor_radius,
            rotor_speed_min=speed_min,
            rotor_speed_max=speed_max,
            positions=positions,
            spins=spins,
            tilt_axes=tilt_axes,
            tilt_angle_max=float(tilt_max),
            contact_height=contact_height,
            top_height=top_height,
            description=description,
            thrust_axes=thrust_axes,
            **dynamics,
        )
    except InvalidValueError as error:  # a check of the model itself (e.g. a tilt axis along the thrust axis)
        key = {"tilt_axes": "rotors.tilt_axis", "positions": "rotors.position",
               "thrust_axes": "rotors.axis"}.get(error.name, error.name)
        raise ConfigError(key, error.reason, source) from None


def dynamics_and_drag(section: Section, defaults: dict[str, Any]) -> dict[str, Any]:
    """The actuator dynamics and the aerodynamics of a vehicle file, or of a scenario's ``plant`` section over
    its vehicle's: ``rotor_time_constant`` [s] >= 0, ``tilt_time_constant`` [s] >= 0, ``tilt_rate_max_deg_s``
    > 0 (absent: ``defaults``'), ``drag_coefficients`` (3 numbers >= 0) and the rotors' aerodynamic
    coefficients (``rotor_drag_coefficient``, ``induced_inflow_coefficient``, ``translational_lift_coefficient``,
    ``flapping_coefficient``, each >= 0) - as :class:`Vehicle` fields (``defaults`` too: ``tilt_rate_max`` in
    rad/s)."""
    drag = section.vector("drag_coefficients", 3, np.asarray(defaults["drag_coefficients"]).tolist())
    if np.any(drag < 0.0):
        raise section.error("drag_coefficients", f"must be >= 0, got {drag.tolist()}")
    return {
        "rotor_time_constant": section.number("rotor_time_constant", defaults["rotor_time_constant"], minimum=0.0),
        "tilt_time_constant": section.number("tilt_time_constant", defaults["tilt_time_constant"], minimum=0.0),
        "tilt_rate_max": float(np.deg2rad(section.number("tilt_rate_max_deg_s", strictly_positive=True)))
        if section.has("tilt_rate_max_deg_s") else defaults["tilt_rate_max"],  # absent: no rate limit (inf)
        "drag_coefficients": drag,
        **{name: section.number(name, defaults[name], minimum=0.0) for name in ROTOR_AERODYNAMICS},
    }


Rotors = tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]  # positions, spins, thrust, tilt axes


def _rotors_from_layout(layout: Section) -> Rotors:
    count = layout.integer("count", minimum=3)
    arm = layout.number("arm_length", strictly_positive=True)
    first = np.deg2rad(layout.number("first_angle_deg", 0.0))
    first_spin = layout.string("first_spin", "cw", choices=("cw", "ccw"))
    cant = np.deg2rad(layout.number("cant_deg", 0.0, minimum=-90.0, maximum=90.0))
    tilting = layout.boolean("tilting", False)
    layout.reject_unknown()
    angles = first + 2.0 * np.pi * np.arange(count) / count
    radial = np.column_stack((np.cos(angles), np.sin(angles), np.zeros(count)))
    radial[np.abs(radial) < 1e-12] = 0.0  # exact zeros where cos/sin of multiples of 90 deg are 0
    sign = -1.0 if first_spin == "cw" else 1.0
    spins = sign * (-1.0) ** np.arange(count)  # k_i = (-1)^i with rotor 1 CW
    thrust_axes = None
    if cant != 0.0:  # -e3 turned about the arm r_i by +-cant: cos(c) (-e3) + sin(c) (r_i x -e3)
        signed = cant * (-1.0) ** np.arange(count)
        lateral = np.cross(radial, (0.0, 0.0, -1.0))
        thrust_axes = np.sin(signed)[:, None] * lateral + np.cos(signed)[:, None] * np.array((0.0, 0.0, -1.0))
    return arm * radial, spins, thrust_axes, (radial.copy() if tilting else None)


def _rotors_from_list(value: Any, source: str) -> Rotors:
    if not isinstance(value, list) or len(value) < 3:
        raise ConfigError("rotors", "must be a list of at least 3 rotors", source)
    positions, spins, axes, thrust_axes = [], [], [], []
    for index, entry in enumerate(value):
        rotor = Section(entry, f"rotors[{index}]", source)
        positions.append(rotor.vector("position", 3))
        spin = rotor.integer("spin")
        if spin not in (-1, 1):
            raise rotor.error("spin", f"must be +1 (CCW) or -1 (CW), got {spin}")
        spins.append(float(spin))
        thrust_axis = rotor.raw("axis")
        if thrust_axis is not None:
            thrust_axis = checked_array(thrust_axis, (3,), rotor.key("axis"), source)
            if np.linalg.norm(thrust_axis) < 1e-9:
                raise rotor.error("axis", "must be a non-zero vector")
        thrust_axes.append((0.0, 0.0, -1.0) if thrust_axis is None else thrust_axis)
        axis = rotor.raw("tilt_axis")
        if axis is not None:
            axis = checked_array(axis, (3,), rotor.key("tilt_axis"), source)
            if np.linalg.norm(axis) < 1e-9:
                raise rotor.error("tilt_axis", "must be a non-zero vector")
            axis = axis / np.linalg.norm(axis)
        axes.append(axis)
        rotor.reject_unknown()
    if any(a is None for a in axes) and not all(a is None for a in axes):
        raise ConfigError("rotors", "either every rotor has a tilt_axis or none has", source)
    tilt_axes = None if axes[0] is None else np.array(axes)
    return np.array(positions), np.array(spins), np.array(thrust_axes, dtype=float), tilt_axes
