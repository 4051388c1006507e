"""Vehicle descriptions: mass, inertia and rotor geometry, read from YAML and validated.

Frames: rotor positions ``p_i`` are in the body frame (FRD, metres, from the centre of mass). A rotor's
thrust acts along its axis ``z_i = Rot(a_i, alpha_i) [0, 0, -1]`` (``-z_b`` when untilted). ``spin``
is ``k_i``: +1 counter-clockwise, -1 clockwise seen from above (SPEC §3.2).

A YAML file gives either a ``layout`` (``count`` rotors on a circle of radius ``arm_length``, rotor ``i``
at angle ``first_angle_deg + (i-1) 360/count``, ``k_i = (-1)^i`` so rotor 1 is CW, optional
``tilting: true`` for a tilt axis along each arm) or an explicit ``rotors`` list.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from fsr_sim.config.validation import (
    ConfigError,
    Section,
    checked_array,
    diagonal_or_matrix,
    load_yaml_file,
    resolve_config_path,
)

GRAVITY = 9.81  # m/s^2, along +z of the NED world frame


@dataclass(frozen=True)
class Vehicle:
    """A multirotor's physical description (SI units; arrays are read-only by convention).

    positions: shape (n, 3), rotor centres in body FRD [m].
    spins: shape (n,), ``k_i`` (+1 CCW, -1 CW).
    tilt_axes: shape (n, 3) unit vectors in body FRD, or None for fixed rotors.
    """

    name: str
    mass: float
    inertia: np.ndarray
    c_f: float
    c_m: float
    rotor_radius: float
    rotor_speed_min: float
    rotor_speed_max: float
    positions: np.ndarray
    spins: np.ndarray
    tilt_axes: np.ndarray | None = None
    tilt_angle_max: float = np.pi
    contact_height: float = 0.1  # [m] centre of mass above the landing gear's feet (ground contact)
    top_height: float = 0.1  # [m] top of the vehicle above the centre of mass (ceiling contact)
    description: str = ""

    @property
    def rotor_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def is_tilting(self) -> bool:
        return self.tilt_axes is not None

    @property
    def arm_length(self) -> float:
        """Mean distance of the rotor centres from the centre of mass [m]."""
        return float(np.mean(np.linalg.norm(self.positions, axis=1)))

    @property
    def weight(self) -> float:
        """``m g`` [N]."""
        return self.mass * GRAVITY

    def with_mass_properties(self, mass: float | None = None, inertia: np.ndarray | None = None) -> Vehicle:
        """A copy with another mass [kg] and/or inertia [kg m^2] (the true plant vs the nominal model)."""
        return replace(
            self,
            mass=self.mass if mass is None else float(mass),
            inertia=self.inertia if inertia is None else np.array(inertia, dtype=float),
        )


def load_vehicle(name_or_path: str | Path) -> Vehicle:
    """Load a built-in vehicle by name (``octocopter``, ``quadrotor_ex4``, ``tilting_quadrotor_ex5``) or
    from a YAML file path. Raises :class:`ConfigError` naming the file and key of any invalid value."""
    path = resolve_config_path(str(name_or_path), "vehicles")
    return vehicle_from_mapping(load_yaml_file(path), source=str(path), default_name=path.stem)


def vehicle_from_mapping(data: dict[str, Any], source: str = "", default_name: str = "vehicle") -> Vehicle:
    """Build and validate a :class:`Vehicle` from a mapping (the YAML file's content)."""
    root = Section(data, "", source)
    name = root.string("name", default_name)
    description = root.string("description", "")
    mass = root.number("mass", strictly_positive=True)
    inertia = checked_inertia(root.raw("inertia"), "inertia", source)
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

    if root.has("layout") == root.has("rotors"):
        raise root.error("layout", "give exactly one of 'layout' or 'rotors'")
    if root.has("layout"):
        positions, spins, tilt_axes = _rotors_from_layout(root.section("layout"))
    else:
        positions, spins, tilt_axes = _rotors_from_list(root.raw("rotors"), source)
    root.reject_unknown()

    if tilt_axes is not None:
        # The static (linear) tilting allocation needs each tilt axis normal to the untilted thrust axis.
        if np.any(np.abs(tilt_axes[:, 2]) > 1e-9):
            raise ConfigError("rotors.tilt_axis", "tilt axes must lie in the body x-y plane", source)
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
    )


def checked_inertia(value: Any, key: str, source: str = "") -> np.ndarray:
    """A diagonal (3 numbers) or a full 3x3 inertia [kg m^2], symmetric and positive definite."""
    if value is None:
        raise ConfigError(key, "is required", source)
    inertia = diagonal_or_matrix(value, key, source)
    if not np.allclose(inertia, inertia.T, rtol=0.0, atol=1e-12 * max(1.0, np.abs(inertia).max())):
        raise ConfigError(key, f"must be symmetric, got {inertia.tolist()}", source)
    eigenvalues = np.linalg.eigvalsh(inertia)
    if eigenvalues.min() <= 0.0:
        raise ConfigError(key, f"must be positive definite, got eigenvalues {eigenvalues.tolist()}", source)
    return inertia


def _rotors_from_layout(layout: Section) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    count = layout.integer("count", minimum=3)
    arm = layout.number("arm_length", strictly_positive=True)
    first = np.deg2rad(layout.number("first_angle_deg", 0.0))
    first_spin = layout.string("first_spin", "cw", choices=("cw", "ccw"))
    tilting = layout.boolean("tilting", False)
    layout.reject_unknown()
    angles = first + 2.0 * np.pi * np.arange(count) / count
    radial = np.column_stack((np.cos(angles), np.sin(angles), np.zeros(count)))
    radial[np.abs(radial) < 1e-12] = 0.0  # exact zeros where cos/sin of multiples of 90 deg are 0
    sign = -1.0 if first_spin == "cw" else 1.0
    spins = sign * (-1.0) ** np.arange(count)  # k_i = (-1)^i with rotor 1 CW
    return arm * radial, spins, (radial.copy() if tilting else None)


def _rotors_from_list(value: Any, source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    if not isinstance(value, list) or len(value) < 3:
        raise ConfigError("rotors", "must be a list of at least 3 rotors", source)
    positions, spins, axes = [], [], []
    for index, entry in enumerate(value):
        rotor = Section(entry, f"rotors[{index}]", source)
        positions.append(rotor.vector("position", 3))
        spin = rotor.integer("spin")
        if spin not in (-1, 1):
            raise rotor.error("spin", f"must be +1 (CCW) or -1 (CW), got {spin}")
        spins.append(float(spin))
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
    return np.array(positions), np.array(spins), tilt_axes
