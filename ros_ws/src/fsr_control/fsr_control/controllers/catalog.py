"""The control laws a scenario can name (``controller.type``): what each needs, its gains and how it is packed.

A law's per-step function lives in the compiled core (:mod:`fsr_control.core.laws`, selected by its kind);
this table is everything else the configuration and the controller need to know of it. A new law adds one
entry (``docs/extending.md``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from fsr_control.controllers import geometric, indi, voliro
from fsr_control.core import geometric_law, indi_law, laws, voliro_law
from fsr_control.design.gain_design import design_gains
from fsr_sim.model.vehicle import Vehicle

if TYPE_CHECKING:
    from fsr_control.config.controller_config import ControllerConfig


@dataclass(frozen=True)
class LawType:
    """A control law of the compiled core.

    Attributes
    ----------
    kind : int
        Its kind in :func:`fsr_control.core.laws.control_law` (the index of its field of
        :class:`~fsr_control.core.laws.LawParams`).
    default_gains : dict
        Gain name -> (3, 3) array: the report's gains (``controller.profile: report``); a scenario's
        ``controller.gains`` takes these names (and ``optional_gains``).
    designed_gains : callable
        ``designed_gains(vehicle, imu) -> dict`` of the same names: the gains of ``controller.profile: flight``,
        designed from the nominal vehicle (:mod:`fsr_control.design.gain_design`); ``imu``: the law flies on the
        IMU (``controller.use_imu``: no odometry delay in its loops).
    pack : callable
        ``pack(vehicle, config) -> params``: the law's own parameters (its field of ``LawParams``) from the
        validated configuration (:class:`~fsr_control.config.controller_config.ControllerConfig`).
    fully_actuated : bool
        The law commands a whole body wrench (a vehicle whose rotors produce any wrench, allocated to rotors);
        False: thrust along ``-z_b`` and a torque (a vehicle that is not fully actuated).
    optional_gains : tuple of str
        Gains a scenario may give beyond ``default_gains`` (zero in the report's profile).
    horizon_steps, horizon_dt : int, float
        The reference ahead the law reads: ``horizon_steps`` samples ``horizon_dt`` [s] apart (0: none).
    needs_imu : bool
        The law reads the IMU (``imu``: the vehicle needs ``sensors.imu``; the controller node subscribes it).
    needs_rotor_state : bool
        The law reads the rotors' measured speeds (``rotor_state``, subscribed where the simulator publishes it).
    """

    kind: int
    default_gains: dict[str, np.ndarray]
    designed_gains: Callable[[Vehicle, bool], dict[str, np.ndarray]]
    pack: Callable[[Vehicle, ControllerConfig], NamedTuple]
    fully_actuated: bool
    optional_gains: tuple[str, ...] = ()
    horizon_steps: int = 0
    horizon_dt: float = 0.0
    needs_imu: bool = False
    needs_rotor_state: bool = False


def _pack_geometric(vehicle: Vehicle, config: ControllerConfig) -> geometric_law.GeometricParams:
    return geometric.pack_geometric(vehicle, config.gains, config.feedforward, config.acceleration_filter_hz,
                                    config.integral_limit, config.use_imu, config.control_period,
                                    config.odometry_measured, config.odometry_delay_steps)


def _pack_voliro(vehicle: Vehicle, config: ControllerConfig) -> voliro_law.VoliroParams:
    return voliro.pack_voliro(vehicle, config.gains, config.angular_feedforward)


def _pack_indi(vehicle: Vehicle, config: ControllerConfig) -> indi_law.IndiParams:
    return indi.pack_indi(vehicle, config.gains, config.filter_hz, config.control_period, config.rotor_state,
                          config.integral_limit, config.odometry_measured, config.odometry_delay_steps)


LAWS: dict[str, LawType] = {
    "geometric": LawType(laws.GEOMETRIC, geometric.DEFAULT_GAINS,
                         lambda vehicle, imu: design_gains(vehicle, imu=imu).wrench_gains(),
                         _pack_geometric, fully_actuated=False,
                         optional_gains=geometric.OPTIONAL_GAINS),
    "voliro": LawType(laws.VOLIRO, voliro.DEFAULT_GAINS,
                      lambda vehicle, imu: design_gains(vehicle).acceleration_gains(),
                      _pack_voliro, fully_actuated=True),
    "indi": LawType(laws.INDI, geometric.DEFAULT_GAINS, lambda vehicle, imu: indi.designed_gains(vehicle),
                    _pack_indi, fully_actuated=False, optional_gains=geometric.OPTIONAL_GAINS,
                    needs_imu=True, needs_rotor_state=True),
}
