"""Vehicle descriptions: mass, inertia and rotor geometry, read from YAML and validated.

Frames: rotor positions ``p_i`` are in the body frame (FRD, metres, from the centre of mass). A rotor's
thrust acts along its axis ``z_i = Rot(a_i, alpha_i) z_0,i``: ``z_0,i`` its fixed thrust axis (``-z_b`` unless
the rotor is mounted canted), turned by its servo's tilt ``alpha_i`` about ``a_i`` if it has one. ``spin``
is ``k_i``: +1 counter-clockwise, -1 clockwise seen from above (docs/model.md §3.2).

The actuation is this data, not a vehicle kind: :attr:`Vehicle.has_servos` says whether ``rotor_cmd`` carries
tilt angles, :attr:`Vehicle.fully_actuated` whether the rotors can produce any body wrench (canted fixed rotors,
or rotors on servos), which is what the controllers and the planner ask.

A :class:`Vehicle` is built from plain Python values (arrays are checked and copied) or read from a
YAML file by :func:`load_vehicle` (the file format: :mod:`fsr_sim.config.vehicle_file`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.checks import InvalidValueError, finite_array, symmetric_positive_definite

UNCANTED_THRUST_AXIS = (0.0, 0.0, -1.0)  # body FRD: thrust along -z_b
ROTOR_AERODYNAMICS = ("rotor_drag_coefficient", "induced_inflow_coefficient", "translational_lift_coefficient",
                      "flapping_coefficient")  # the rotors' aerodynamic coefficients (docs/model.md §3.4)


def _unit_rows(rows: np.ndarray, name: str, what: str) -> np.ndarray:
    norms = np.linalg.norm(rows, axis=1)
    if np.any(norms < 1e-9):
        raise InvalidValueError(name, f"every {what} must be a non-zero vector")
    return rows / norms[:, None]


@dataclass(frozen=True)
class Vehicle:
    """A multirotor's physical description (SI units; arrays are checked, copied and made read-only).

    Parameters
    ----------
    name : str
    mass : float
        [kg], > 0.
    inertia : array-like, shape (3,) or (3, 3)
        [kg m^2] about the centre of mass, body FRD; 3 numbers are the diagonal. Symmetric positive definite.
    c_f, c_m : float
        Thrust [N s^2] and drag-torque [N m s^2] coefficients: a rotor at ``w`` rad/s gives ``c_f w^2`` and
        ``c_m w^2``.
    rotor_radius : float
        [m], for the ground and ceiling effect.
    rotor_speed_min, rotor_speed_max : float
        [rad/s], ``0 <= min < max``.
    positions : array-like, shape (n, 3)
        Rotor centres in body FRD [m], ``n >= 3``.
    spins : array-like, shape (n,)
        ``k_i``: +1 counter-clockwise, -1 clockwise seen from above.
    tilt_axes : array-like, shape (n, 3), optional
        Servo tilt axes ``a_i`` (normalised; each normal to its rotor's thrust axis), or None without servos.
    tilt_angle_max : float
        [rad], tilt limits ``+-tilt_angle_max``.
    contact_height : float
        [m], distance from the centre of mass down to the landing gear's feet (ground contact).
    top_height : float
        [m], distance from the centre of mass up to the top of the vehicle (ceiling contact).
    thrust_axes : array-like, shape (n, 3), optional
        Each rotor's fixed thrust axis ``z_0,i`` (body FRD, normalised), at servo tilt 0; None: ``-z_b`` for all.
    rotor_time_constant : float
        [s], >= 0: each rotor's speed follows its command through a first-order lag ``w' = (w_c - w) / tau``
        (0: at once).
    tilt_time_constant : float
        [s], >= 0: the same for each servo's tilt (0: at once).
    tilt_rate_max : float
        [rad/s], > 0: the servos' rate limit (inf: none).
    drag_coefficients : array-like, shape (3,)
        ``C = diag(c_x, c_y, c_z)`` [N s^2/m^2] >= 0, the airframe's parasitic drag: with the air velocity
        ``v_a`` (body, the vehicle's minus the wind) it pushes with ``-|v_a| C v_a`` (docs/model.md §3.4).
    rotor_drag_coefficient, induced_inflow_coefficient : float
        ``k_d``, ``k_z`` [kg/rad] >= 0: each rotor's drag (H-force) ``-w_i k_d v_i,p`` against its in-plane air
        velocity and the induced inflow ``-w_i k_z v_i,z z_i`` against its axial one.
    translational_lift_coefficient : float
        ``k_h`` [kg/m] >= 0: each rotor's extra thrust ``k_h |v_i,p|^2`` along its axis.
    flapping_coefficient : float
        ``k_flap`` [kg m/rad] >= 0: each rotor's blade-flapping moment ``-k_flap w_i (v_i x z_i)``.

    Raises
    ------
    ValueError
        (:class:`fsr_sim.model.checks.InvalidValueError`) naming the field for any invalid value.
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
    thrust_axes: np.ndarray | None = None  # (n, 3) unit; None -> -z_b for every rotor
    rotor_time_constant: float = 0.0  # [s] first-order lag of the rotor speeds (0: they follow at once)
    tilt_time_constant: float = 0.0  # [s] first-order lag of the tilts (rotors on servos; 0: none)
    tilt_rate_max: float = np.inf  # [rad/s] servo rate limit (inf: none)
    drag_coefficients: np.ndarray = field(default_factory=lambda: np.zeros(3))  # [N s^2/m^2] per body axis
    rotor_drag_coefficient: float = 0.0  # k_d [kg/rad]
    induced_inflow_coefficient: float = 0.0  # k_z [kg/rad]
    translational_lift_coefficient: float = 0.0  # k_h [kg/m]
    flapping_coefficient: float = 0.0  # k_flap [kg m/rad]

    def __post_init__(self) -> None:
        def put(name: str, value: object) -> None:
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(self, name, value)

        for name in ("mass", "c_f", "rotor_radius", "rotor_speed_max", "tilt_angle_max"):
            value = float(getattr(self, name))
            if not value > 0.0 or not np.isfinite(value):
                raise InvalidValueError(name, f"must be > 0, got {value}")
            put(name, value)
        for name in ("c_m", "rotor_speed_min", "contact_height", "top_height", "rotor_time_constant",
                     "tilt_time_constant", *ROTOR_AERODYNAMICS):
            value = float(getattr(self, name))
            if not value >= 0.0 or not np.isfinite(value):
                raise InvalidValueError(name, f"must be >= 0, got {value}")
            put(name, value)
        rate = float(self.tilt_rate_max)
        if not rate > 0.0 or np.isnan(rate):
            raise InvalidValueError("tilt_rate_max", f"must be > 0 (inf: no limit), got {rate}")
        put("tilt_rate_max", rate)
        if self.rotor_speed_max <= self.rotor_speed_min:
            raise InvalidValueError("rotor_speed_max", f"must be > rotor_speed_min ({self.rotor_speed_min}), got "
                                                  f"{self.rotor_speed_max}")
        put("inertia", symmetric_positive_definite(self.inertia, "inertia"))
        drag = finite_array(self.drag_coefficients, (3,), "drag_coefficients")
        if np.any(drag < 0.0):
            raise InvalidValueError("drag_coefficients", f"must be >= 0, got {drag.tolist()}")
        put("drag_coefficients", drag)
        positions = np.array(self.positions, dtype=float)
        if positions.ndim != 2 or positions.shape[0] < 3:
            raise InvalidValueError("positions", f"expected shape (n, 3) with n >= 3, got {positions.shape}")
        n = positions.shape[0]
        put("positions", finite_array(positions, (n, 3), "positions"))
        spins = finite_array(self.spins, (n,), "spins")
        if not np.all(np.abs(spins) == 1.0):
            raise InvalidValueError("spins", f"each must be +1 (CCW) or -1 (CW), got {spins.tolist()}")
        put("spins", spins)
        if self.thrust_axes is None:
            thrust_axes = np.tile(UNCANTED_THRUST_AXIS, (n, 1))
        else:
            thrust_axes = _unit_rows(finite_array(self.thrust_axes, (n, 3), "thrust_axes"), "thrust_axes",
                                     "thrust axis")
        put("thrust_axes", thrust_axes)
        if self.tilt_axes is not None:
            axes = _unit_rows(finite_array(self.tilt_axes, (n, 3), "tilt_axes"), "tilt_axes", "tilt axis")
            # The static (linear) tilting allocation needs each tilt axis normal to the untilted thrust axis.
            if np.any(np.abs(np.sum(axes * thrust_axes, axis=1)) > 1e-9):
                raise InvalidValueError("tilt_axes", "each tilt axis must be normal to its rotor's thrust axis (in "
                                                     "the body x-y plane for uncanted rotors)")
            put("tilt_axes", axes)

    @property
    def has_aerodynamics(self) -> bool:
        """Some parasitic-drag or rotor aerodynamic coefficient is not zero."""
        return bool(np.any(self.drag_coefficients > 0.0)) or any(getattr(self, name) > 0.0
                                                                  for name in ROTOR_AERODYNAMICS)

    @property
    def rotor_count(self) -> int:
        return int(self.positions.shape[0])

    @property
    def has_servos(self) -> bool:
        """The rotors tilt on servos: ``rotor_cmd`` carries a tilt angle per rotor."""
        return self.tilt_axes is not None

    @functools.cached_property
    def fully_actuated(self) -> bool:
        """The rotors can produce any body wrench (the allocation has rank 6): canted fixed rotors or servos. Such
        a vehicle can hold any attitude (the Voliro controller); the others produce thrust along ``-z_b`` and a
        torque (the geometric controller). Worked out once per object (it is frozen)."""
        from fsr_sim.model.rotors import actuation_matrix  # allocation imports this module

        return bool(np.linalg.matrix_rank(actuation_matrix(self), tol=1e-9) == 6)

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
    """Load a built-in vehicle (``octocopter``, ``quadrotor_ex4``, ``tilting_quadrotor_ex5``) or a YAML file.

    Parameters
    ----------
    name_or_path : str or Path
        A built-in name or the path of a vehicle YAML file (format: :mod:`fsr_sim.config.vehicle_file`).

    Raises
    ------
    fsr_sim.config.validation.ConfigError
        A ``ValueError`` naming the file and the key of any invalid value.
    """
    from fsr_sim.config.vehicle_file import load_vehicle_file  # YAML is read only when a file is loaded

    return load_vehicle_file(name_or_path)
