"""What the control laws share: their interface and their Python shell around the compiled core.

The interface (:class:`ControlLaw`): ``compute(reference, position, rotation, velocity_world,
angular_velocity_body, compensation, horizon) -> WrenchCommand``, the body wrench to produce and the
attitude it commands; allocation (fsr_control.allocation) turns the wrench into rotor speeds and tilts. The
laws themselves are written once, in the compiled core (:mod:`fsr_control.core.laws`); :class:`CompiledLaw`
packs a law's gains and nominal model once and calls it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from fsr_control.core import imu_bridge, laws
from fsr_control.core.flatness import ATTITUDE_ERRORS, ATTITUDE_OK
from fsr_control.core.imu_bridge import BridgeParams
from fsr_control.core.law_terms import INERTIA
from fsr_control.core.reference import HORIZON_WIDTH, ReferenceSample
from fsr_control.planning.trajectory import Reference
from fsr_sim.core.so3 import Vec3, matrix_rows
from fsr_sim.model.so3 import vector3
from fsr_sim.model.vehicle import Vehicle

Compensation = tuple[Vec3, Vec3, Vec3, Vec3]
"""The estimated external wrench a law cancels (:mod:`fsr_control.compensation`): ``(f_hat, tau_hat, f_hat_dot,
f_hat_ddot)``: force [N] world NED, torque [N m] body FRD, the force's first and second time differences
[N/s, N/s^2] (world; the geometric law turns ``R_d`` with them)."""
BRIDGE_CORRECTION = 0.2  # the share of the difference to a new odom sample the IMU-bridged estimate takes


@dataclass
class WrenchCommand:
    """What a control law asks for at one state.

    Attributes
    ----------
    force_body : numpy.ndarray, shape (3,)
        Body force [N], FRD (a fixed-rotor vehicle: ``[0, 0, -u_T]``).
    torque_body : numpy.ndarray, shape (3,)
        Body torque [N m], FRD.
    rotation_commanded : numpy.ndarray, shape (3, 3)
        The attitude the law steers to, body FRD -> world NED (geometric: ``R_d`` built from the thrust
        direction; Voliro: the reference attitude).
    """

    force_body: np.ndarray
    torque_body: np.ndarray
    rotation_commanded: np.ndarray

    @property
    def thrust(self) -> float:
        """``u_T = -f_z`` [N] (thrust along ``-z_b``)."""
        return -float(self.force_body[2])


class ControlLaw(Protocol):
    """A control law on the nominal vehicle model (frames: position and velocity world NED [m, m/s],
    ``rotation`` body FRD -> world NED, angular velocity body FRD [rad/s])."""

    def compute(self, reference: Reference, position: np.ndarray, rotation: np.ndarray, velocity_world: np.ndarray,
                angular_velocity_body: np.ndarray, compensation: Compensation | None = None,
                horizon: np.ndarray | None = None) -> WrenchCommand:
        """The body wrench for this state and reference.

        Parameters
        ----------
        reference : Reference
            The planner's desired state at this time.
        position, velocity_world : numpy.ndarray, shape (3,)
            [m], [m/s], world NED.
        rotation : numpy.ndarray, shape (3, 3)
            Body FRD -> world NED.
        angular_velocity_body : numpy.ndarray, shape (3,)
            [rad/s], body FRD.
        compensation : Compensation, optional
            The estimated external wrench to cancel (:data:`Compensation`; None: uncompensated, bit for bit
            the law as written). How each law uses it: its own ``compute``.
        horizon : numpy.ndarray, shape (N, HORIZON_WIDTH), optional
            The reference ahead, for a law that reads it (rows of :mod:`fsr_control.core.reference`).

        Returns
        -------
        WrenchCommand
        """


def compensation_of(compensation: Compensation | None) -> laws.Compensation:
    """The core's :class:`~fsr_control.core.laws.Compensation` of ``(f_hat, tau_hat, f_hat_dot, f_hat_ddot)``."""
    if compensation is None:
        return laws.NO_COMPENSATION
    force, torque, rate, acceleration = (tuple(float(v) for v in part) for part in compensation)
    return laws.Compensation(True, force, torque, rate, acceleration)


def law_matrices(vehicle: Vehicle, gains: dict[str, np.ndarray], names: tuple[str, ...],
                 optional: tuple[str, ...] = ()) -> np.ndarray:
    """A law's matrices (:mod:`fsr_control.core.law_terms`): the nominal inertia [kg m^2], then ``gains[name]``
    for each of ``names`` (an ``optional`` name that is missing: zeros), one contiguous (1 + len(names), 3, 3)
    float array. Raises ValueError naming a missing gain."""
    missing = [name for name in names if name not in gains and name not in optional]
    if missing:
        raise ValueError(f"gains {missing} missing (got {sorted(gains)})")
    matrices = [vehicle.inertia, *(gains.get(name, np.zeros((3, 3))) for name in names)]
    return np.ascontiguousarray([np.asarray(matrix, dtype=float).reshape(3, 3) for matrix in matrices])


def diagonal_gains(**diagonals: tuple[float, float, float]) -> dict[str, np.ndarray]:
    """Gain name -> the (3, 3) diagonal matrix of its values about x, y and z (a law's report gains)."""
    return {name: np.diag(values) for name, values in diagonals.items()}


def check_actuation(law: str, fully_actuated: bool, vehicle: Vehicle,
                    error: Callable[[str], Exception] = ValueError) -> None:
    """Raises ``error(reason)`` where ``law`` cannot fly ``vehicle`` (``fully_actuated``: the law commands a whole
    body wrench, else thrust along ``-z_b`` and a torque)."""
    if fully_actuated and not vehicle.fully_actuated:
        raise error(f"{law} needs a fully actuated vehicle (rotors on servos or canted); '{vehicle.name}' produces "
                    f"thrust along -z_b only (use geometric)")
    if vehicle.fully_actuated and not fully_actuated:
        raise error(f"{law} is for vehicles with thrust along -z_b; '{vehicle.name}' is fully actuated (use voliro)")


def integrates(matrices: np.ndarray, k_i: int, integral_limit: float) -> bool:
    """Whether a law with ``matrices`` (:func:`law_matrices`) integrates its position error: its integral gain
    ``matrices[k_i]`` is not zero. Raises ValueError when it is and ``integral_limit`` (the bound [N] on the
    integral's force) is not positive."""
    integral = bool(np.any(matrices[k_i] != 0.0))
    if integral and not integral_limit > 0.0:
        raise ValueError(f"an integral gain k_i needs an integral_limit > 0 N, got {integral_limit}")
    return integral


def pack_bridge(enabled: bool, period: float, delay_steps: int) -> BridgeParams:
    """The IMU bridge's parameters (:mod:`fsr_control.core.imu_bridge`): ``enabled`` where ``odom`` is a
    measurement, the control ``period`` [s] it integrates the IMU over and the steps ``delay_steps`` odom's samples
    are late by, each new sample taking :data:`BRIDGE_CORRECTION` of its difference to the estimate."""
    if not 0 <= delay_steps < imu_bridge.HISTORY:
        raise ValueError(f"the IMU-bridged estimate bridges an odometry delay of at most {imu_bridge.HISTORY - 1} "
                         f"steps, got {delay_steps}")
    return BridgeParams(bool(enabled), float(period), int(delay_steps), BRIDGE_CORRECTION)


class CompiledLaw:
    """A law of the compiled core on a nominal vehicle: its packed parameters (:attr:`params`, the law's own in
    its field of :class:`~fsr_control.core.laws.LawParams`) and the laws' memory
    (:class:`~fsr_control.core.laws.LawMemory`)."""

    def __init__(self, params: laws.LawParams) -> None:
        self.params = params
        self.memory = laws.new_law_memory()
        own = getattr(params, laws.LAW_FIELDS[params.kind])  # the law's own parameters
        self.mass = own.mass
        self.inertia = own.matrices[INERTIA]

    def reset(self) -> None:
        """Forget the previous sample (the geometric law's measured acceleration restarts from the model's, its
        integral from zero)."""
        laws.reset_law_memory(self.memory)

    def compute(self, reference: Reference, position: np.ndarray, rotation: np.ndarray, velocity_world: np.ndarray,
                angular_velocity_body: np.ndarray, compensation: Compensation | None = None,
                horizon: np.ndarray | None = None, imu: np.ndarray | None = None,
                speeds: np.ndarray | None = None, tilts: np.ndarray | None = None) -> WrenchCommand:
        """The body wrench for this state and reference (:meth:`ControlLaw.compute`); ``horizon``: the reference
        ahead, (``params.horizon_steps``, ``HORIZON_WIDTH``) rows of :mod:`fsr_control.core.reference` (needed
        only by a law that looks ahead); ``imu`` (6,): the IMU's angular velocity [rad/s] and specific force
        [m/s^2], body FRD, and ``speeds``, ``tilts`` (n,): the rotors' measured state (needed only by a law that
        reads them; None: zeros). Raises ValueError when no attitude can be commanded (a zero thrust
        vector, or one horizontal along the heading) or the horizon does not have the law's shape."""
        steps = self.params.horizon_steps
        horizon = np.zeros((0, HORIZON_WIDTH)) if horizon is None and steps == 0 else horizon
        if horizon is None or np.shape(horizon) != (steps, HORIZON_WIDTH):
            raise ValueError(f"this law reads the reference {steps} samples ahead: horizon must have shape "
                             f"({steps}, {HORIZON_WIDTH}), got {None if horizon is None else np.shape(horizon)}")
        state = laws.VehicleState(vector3(position), matrix_rows(np.ascontiguousarray(rotation, dtype=float)),
                                  vector3(velocity_world), vector3(angular_velocity_body))
        status, force, torque, rotation_commanded = laws.control_law(
            self.params, self.memory, np.ascontiguousarray(horizon, dtype=float), float(reference.time),
            reference_sample(reference), state, compensation_of(compensation),
            laws.Measured(_array(imu, 6), _array(speeds, 0), _array(tilts, 0)))
        if status != ATTITUDE_OK:
            raise ValueError(ATTITUDE_ERRORS[status])
        return WrenchCommand(np.array(force), np.array(torque), np.array(rotation_commanded))


def _array(values: np.ndarray | None, size: int) -> np.ndarray:
    """``values`` as a contiguous float array (None: ``size`` zeros)."""
    return np.zeros(size) if values is None else np.ascontiguousarray(values, dtype=float)


def reference_sample(reference: Reference) -> ReferenceSample:
    """The core's :class:`~fsr_control.core.reference.ReferenceSample` of a :class:`Reference`."""
    return ReferenceSample(
        vector3(reference.position), vector3(reference.velocity), vector3(reference.acceleration),
        vector3(reference.jerk), vector3(reference.snap), matrix_rows(np.ascontiguousarray(reference.rotation)),
        vector3(reference.angular_velocity), vector3(reference.angular_acceleration), float(reference.yaw),
        float(reference.yaw_rate), float(reference.yaw_acceleration),
    )
