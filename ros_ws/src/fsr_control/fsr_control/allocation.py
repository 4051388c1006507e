"""From the controller's body wrench to actuator commands: what the allocation does and what gives way.

The per-step arithmetic is the compiled core's (:mod:`fsr_control.core.allocation`); this module packs its
parameters from a checked :class:`~fsr_sim.model.vehicle.Vehicle` (:func:`pack_allocation`) and offers the
three actuations as Python objects with one interface, ``allocate(time, force_body, torque_body) -> Actuated``:

* :class:`WrenchActuation` (``actuation: wrench``): the plant takes ``u_T = -f_z`` and ``tau_b`` directly.
* :class:`FixedRotorActuation`: ``u_w = G^+ [f_z, tau]`` (the exact inverse for a quadrotor, the minimum-norm
  pseudo-inverse for the octocopter; rows the rotors cannot produce, e.g. ``f_x``, ``f_y``, are left out).
* :class:`TiltingActuation`: ``u = G_static^+ wrench (+ N z, the secondary objective of
  :mod:`fsr_control.nullspace`)``, then eq. 5: ``u_w,i = |(u_v,i, u_l,i)| / c_f``, ``alpha_i = atan2(u_l,i, u_v,i)``.

Saturation (``controller.allocation``, ``controller.air_mode``). With ``clamp`` rotor speeds ``w_i = sqrt(u_w,i)``
[rad/s] are clamped to ``[w_min, w_max]`` one by one (tilts to ``+-tilt_angle_max``). With ``priority``
(default) a command beyond the speed limits is reallocated so that the axes that hold the vehicle in the air
are kept and the others give way in a fixed order, like PX4's sequential desaturation. The wrench is linear in
the squared speeds ``u_w``, so the speed limits are box constraints on ``u_w`` and along any straight line
``u_w(s) = a + s d`` the feasible ``s`` form an interval with a closed form.

Fixed rotors (rows ``f_z, tau_x, tau_y, tau_z`` of ``G``, ``P = G^+``, ``g = -P e_fz`` the squared-speed change per
newton of thrust, ``v_rp = P [0, tau_x, tau_y, 0]``, ``v_yaw = P [0, 0, 0, tau_z]``, box ``B = [w_min^2,
w_max^2]^n``); priority, highest first: roll/pitch torque (the thrust direction, i.e. the attitude), then
collective thrust ``u_T``, then yaw torque:

1. ``u_w = P w`` in ``B``: returned as it is (the clamp path, bit-identical).
2. ``u_T g + v_rp`` in ``B``: yaw gives way, ``u_w = u_T g + v_rp + s* v_yaw`` with ``s* = max {s in [0, 1] :
   u_w(s) in B}``; thrust and roll/pitch torque are exact.
3. Otherwise yaw is dropped and, for a roll/pitch scale ``r`` and a thrust ``T``, rotor ``i`` needs
   ``T in [(lo_i - r v_rp,i)/g_i, (hi_i - r v_rp,i)/g_i]``. The largest ``r in [0, 1]`` for which these
   intervals intersect is the minimum over rotor pairs of ``(b_j - a_i)/(k_j - k_i)`` (``a = lo/g``, ``b = hi/g``,
   ``k = v_rp/g``, pairs with ``k_j > k_i``): roll/pitch torque keeps its direction and is scaled by ``r*`` only
   if it cannot be met at any thrust. Then ``T*`` is the commanded thrust clipped to the intersection (the
   closest reachable thrust: it may rise above the command to make room for the torque, as PX4's air mode
   does, or fall), and the yaw step of 2 adds back what yaw still fits.

Without air mode (``controller.air_mode: false``) the thrust comes first: ``u_w = u_T g + r* v_rp + s* v_yaw``
with ``r* = max {r in [0, 1] : u_T g + r v_rp in B}``, then the yaw step; the commanded thrust is kept exactly
(steps 2-3 only if ``u_T g`` alone is outside ``B``). Step 3 needs ``g_i > 0`` (more thrust asks every rotor
for more; true for every multirotor layout) and a uniform thrust inside ``B``; otherwise the command is
clamped rotor by rotor. The result is inside ``B`` up to rounding (a final clamp removes that).

Tilting rotors (``P_s = G_s^+``): rotor ``i``'s thrust vector ``t_i = (u_v,i, u_l,i)`` must satisfy
``|t_i| <= c_f w_max^2``, a disc (convex). Priority, highest first: body force, then roll/pitch torque, then
yaw torque; starting from ``u = 0`` each group in turn is added at the largest scale in ``[0, 1]`` that keeps
every ``t_i`` in its disc (the root of a quadratic per rotor): yaw gives way first, then roll/pitch, then
force, each keeping its direction. The minimum speed and the tilt limit (not convex sets) are then clamped.
The secondary objective is not applied on a reallocated step.

A command within the limits is the same with either strategy (bit for bit). Every saturated command is
recorded in a :class:`SaturationReport` (count, first time, worst rotor, and per wrench axis the steps it
gave way and the largest shortfall) and flagged in the result, never clipped silently. ``force_body`` /
``torque_body`` of the result are what the final command produces through the nominal allocation (what the
plant applies, ground effect aside): that is the ``wrench_cmd`` the controller publishes; ``shortfall`` is
the demanded minus that wrench (``wrench_shortfall``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_control.core import allocation as core
from fsr_control.nullspace import null_space_gram
from fsr_sim.contract import body_force_of_thrust
from fsr_sim.model.rotors import SaturationReport, static_tilting_allocation, wrench_from_rotor_speed_sq
from fsr_sim.model.vehicle import Vehicle

ALLOCATION_STRATEGIES = ("clamp", "priority")
SECONDARY_OBJECTIVES = ("none", "min_peak_speed")


@dataclass
class Actuated:
    """One allocated command: rotor speeds [rad/s] (None in wrench actuation), tilts [rad] (None for fixed
    rotors), the wrench it produces (body FRD, N / N m), whether anything saturated, and the shortfall
    ``[f; tau]_demanded - [f; tau]_produced`` (shape (6,), body FRD, N / N m)."""

    rotor_speeds: np.ndarray | None
    tilt_angles: np.ndarray | None
    force_body: np.ndarray
    torque_body: np.ndarray
    saturated: bool
    shortfall: np.ndarray


class FixedRotorAllocator:
    """The pseudo-inverse allocation of fixed (untilted) rotors: wrench -> squared rotor speeds.

    For a coplanar vehicle only ``[f_z, tau_x, tau_y, tau_z]`` can be produced (:attr:`rows`); the
    pseudo-inverse of that 4 x n block gives the minimum-norm ``u_w`` (exact inverse for a quadrotor). The
    compiled allocation (:mod:`fsr_control.core.allocation`) is packed from :attr:`inverse_6`.
    """

    def __init__(self, vehicle: Vehicle) -> None:
        if vehicle.has_servos:
            raise ValueError(f"FixedRotorAllocator needs fixed rotors; '{vehicle.name}' has rotors on servos")
        self.vehicle = vehicle
        self.allocation = wrench_from_rotor_speed_sq(vehicle)
        self.rows = np.flatnonzero(np.any(np.abs(self.allocation) > 1e-15, axis=1))
        self.inverse = np.linalg.pinv(self.allocation[self.rows])

    @property
    def inverse_6(self) -> np.ndarray:
        """:attr:`inverse` as an n x 6 matrix over all wrench rows (zero columns for those not produced)."""
        full = np.zeros((self.vehicle.rotor_count, 6))
        full[:, self.rows] = self.inverse
        return full

    def rotor_speed_sq(self, thrust: float, torque_body: np.ndarray) -> np.ndarray:
        """Squared speeds for a thrust ``u_T`` [N] along ``-z_b`` and a body torque [N m] (unclamped)."""
        wrench = np.array((*body_force_of_thrust(thrust), *torque_body[:3]))
        return self.inverse @ wrench[self.rows]


def _checked_strategy(strategy: str) -> str:
    if strategy not in ALLOCATION_STRATEGIES:
        raise ValueError(f"unknown allocation strategy '{strategy}' ({', '.join(ALLOCATION_STRATEGIES)})")
    return strategy


def pack_allocation(vehicle: Vehicle, actuation: str, strategy: str = "priority", air_mode: bool = True,
                    objective: str = "none", exponent: int = 8, iterations: int = 3) -> core.AllocationParams:
    """The core's :class:`~fsr_control.core.allocation.AllocationParams` for ``vehicle`` (module docstring)."""
    _checked_strategy(strategy)
    if objective not in SECONDARY_OBJECTIVES:
        raise ValueError(f"unknown secondary objective '{objective}' ({', '.join(SECONDARY_OBJECTIVES)})")
    if objective != "none" and (exponent < 4 or exponent % 2):
        raise ValueError(f"exponent must be an even integer >= 4, got {exponent}")
    if iterations < 1:
        raise ValueError(f"iterations must be >= 1, got {iterations}")
    n = vehicle.rotor_count
    thrust_ok = False
    null_basis = np.zeros((2 * n, 0))
    if actuation == "wrench":
        mode, allocation, inverse = core.WRENCH, np.zeros((6, n)), np.zeros((n, 6))
    elif vehicle.has_servos:
        import scipy.linalg  # here, not at the top: fixed-rotor controllers and fsr-fly never need it

        mode = core.TILTING
        allocation = static_tilting_allocation(vehicle)
        inverse = np.linalg.pinv(allocation)
        null_basis = scipy.linalg.null_space(allocation)
    else:
        if vehicle.fully_actuated and strategy == "priority":
            raise ValueError(f"'{vehicle.name}' is fully actuated with fixed rotors: its commands are clamped rotor by "
                             "rotor (allocation 'clamp'); the priority rules are for thrust-and-torque vehicles")
        mode = core.FIXED
        allocator = FixedRotorAllocator(vehicle)
        if core.FORCE_Z_ROW not in allocator.rows:
            raise ValueError(f"the allocation rows {allocator.rows.tolist()} have no f_z row: fixed rotors "
                             "without thrust")
        allocation, inverse = allocator.allocation, allocator.inverse_6
        g = -inverse[:, core.FORCE_Z_ROW]
        low, high = vehicle.rotor_speed_min**2, vehicle.rotor_speed_max**2
        thrust_ok = bool(np.all(g > 0.0) and max(low / g) <= min(high / g))
    return core.AllocationParams(
        mode=mode, priority=strategy == "priority", air_mode=bool(air_mode),
        speed_min=float(vehicle.rotor_speed_min), speed_max=float(vehicle.rotor_speed_max), c_f=float(vehicle.c_f),
        tilt_max=float(vehicle.tilt_angle_max), allocation=np.ascontiguousarray(allocation),
        inverse=np.ascontiguousarray(inverse), thrust_ok=thrust_ok, null_basis=np.ascontiguousarray(null_basis),
        null_gram=null_space_gram(null_basis), objective=objective == "min_peak_speed", exponent=int(exponent),
        iterations=int(iterations),
    )


def new_allocation_state(params: core.AllocationParams, rotor_count: int) -> core.AllocationState:
    """A fresh :class:`~fsr_control.core.allocation.AllocationState` (empty saturation records)."""
    k = params.null_basis.shape[1]
    return core.AllocationState(
        saturation=SaturationReport(rotor_count).array, tilt_saturation=SaturationReport(rotor_count).array,
        null_z=np.zeros(k), null_hessian=np.zeros((k, k)), null_terms=np.zeros((rotor_count, k + 2)),
        scratch=np.zeros((8, max(2 * rotor_count, 6))),
    )


class Actuation:
    """One actuation (``WRENCH``, ``FIXED`` or ``TILTING``) with its saturation records; :meth:`allocate` runs the
    core's :func:`~fsr_control.core.allocation.allocate`."""

    def __init__(self, vehicle: Vehicle, params: core.AllocationParams) -> None:
        self.vehicle = vehicle
        self.params = params
        self.state = new_allocation_state(params, vehicle.rotor_count)
        self.saturation = SaturationReport(record=self.state.saturation)
        self.tilt_saturation = SaturationReport(record=self.state.tilt_saturation)

    @property
    def allocation(self) -> np.ndarray:
        """The nominal allocation: 6 x n (fixed rotors, per squared speed) or 6 x 2n (tilting, static)."""
        return self.params.allocation

    @property
    def inverse(self) -> np.ndarray:
        """Its pseudo-inverse (n x 6 or 2n x 6)."""
        return self.params.inverse

    def allocate(self, time: float, force_body: np.ndarray, torque_body: np.ndarray) -> Actuated:
        """Actuator commands for a body force [N] and torque [N m] (FRD) at ``time`` [s] (module docstring)."""
        n = self.vehicle.rotor_count
        speeds, tilts, shortfall = np.zeros(n), np.zeros(n), np.zeros(6)
        force = tuple(float(v) for v in np.asarray(force_body, dtype=float).reshape(3))
        torque = tuple(float(v) for v in np.asarray(torque_body, dtype=float).reshape(3))
        actuated = core.allocate(self.params, self.state, float(time), force, torque, speeds, tilts, shortfall)
        mode = self.params.mode
        return Actuated(None if mode == core.WRENCH else speeds, tilts if mode == core.TILTING else None,
                        np.array(actuated.force), np.array(actuated.torque), bool(actuated.saturated), shortfall)


class WrenchActuation(Actuation):
    """``actuation: wrench``: thrust along ``-z_b`` and body torque go to the plant as they are (``f_x``, ``f_y``
    cannot be applied: they are the shortfall)."""

    def __init__(self, vehicle: Vehicle) -> None:
        super().__init__(vehicle, pack_allocation(vehicle, "wrench"))


class FixedRotorActuation(Actuation):
    """Fixed rotors: pseudo-inverse of the producible rows; beyond the limits either clamp rotor by rotor
    (``strategy='clamp'``) or reallocate with priorities (``'priority'``; ``air_mode`` as in the module
    docstring)."""

    def __init__(self, vehicle: Vehicle, strategy: str = "priority", air_mode: bool = True) -> None:
        if vehicle.has_servos:
            raise ValueError(f"FixedRotorActuation needs fixed rotors; '{vehicle.name}' has rotors on servos")
        super().__init__(vehicle, pack_allocation(vehicle, "rotors", strategy, air_mode))

    def desaturated(self, thrust: float, torque_body: tuple[float, float, float]) -> np.ndarray | None:
        """The squared speeds ``u_w`` [(rad/s)^2] the priority allocation gives for thrust ``u_T`` [N] and a body
        torque [N m] (also within the limits), or None when step 3 does not apply and step 2 failed."""
        u_w = np.zeros(self.vehicle.rotor_count)
        torque = tuple(float(v) for v in torque_body)
        found = core.fixed_desaturation(self.params, float(thrust), torque, self.state.scratch, u_w)
        return u_w if found else None


class TiltingActuation(Actuation):
    """Tilting rotors: static allocation pseudo-inverse (+ optional null-space objective), eq. 5, clamp."""

    def __init__(self, vehicle: Vehicle, strategy: str = "priority", objective: str = "none", exponent: int = 8,
                 iterations: int = 3) -> None:
        if not vehicle.has_servos:
            raise ValueError(f"TiltingActuation needs rotors on servos; '{vehicle.name}' has fixed rotors")
        super().__init__(vehicle, pack_allocation(vehicle, "rotors", strategy, True, objective, exponent, iterations))

    @classmethod
    def with_objective(cls, vehicle: Vehicle, objective: str, exponent: int = 8, iterations: int = 3,
                       strategy: str = "priority") -> TiltingActuation:
        """``objective``: ``none`` (minimum-norm ``G^+``) or ``min_peak_speed`` (:mod:`fsr_control.nullspace`)."""
        return cls(vehicle, strategy, objective, exponent, iterations)

    @property
    def null_basis(self) -> np.ndarray:
        """Orthonormal null space ``N`` (2n x k) of the static allocation."""
        return self.params.null_basis

    def null_space_correction(self, u_p: np.ndarray) -> np.ndarray:
        """``N z`` [N] the secondary objective adds to ``u_p`` (2n,) (warm-started from the last command)."""
        u = np.array(u_p, dtype=float)
        core.null_space_correction(self.params, self.state, u)
        return u - u_p

    def desaturated(self, force_body: np.ndarray, torque_body: np.ndarray) -> np.ndarray:
        """``u`` [N] (2n,) of the priority allocation: every ``|(u_v,i, u_l,i)| <= c_f w_max^2``."""
        u = np.zeros(2 * self.vehicle.rotor_count)
        wrench = tuple(float(v) for v in np.concatenate((force_body, torque_body)))
        core.tilting_desaturation(self.params, wrench, self.state.scratch, u)
        return u


def make_actuation(vehicle: Vehicle, actuation: str, strategy: str = "priority", air_mode: bool = True,
                   objective: str = "none", exponent: int = 8, iterations: int = 3) -> Actuation:
    """The actuation for a vehicle and ``actuation`` (``rotors`` | ``wrench``)."""
    if actuation == "wrench":
        return WrenchActuation(vehicle)
    if vehicle.has_servos:
        return TiltingActuation(vehicle, strategy, objective, exponent, iterations)
    return FixedRotorActuation(vehicle, strategy, air_mode)
