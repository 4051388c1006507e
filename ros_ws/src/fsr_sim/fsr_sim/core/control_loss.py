"""Loss of control (compiled core): the check that ends a flight whose true state has left what its controller
asked for, the same in the simulator node and in the in-process loop.

A flight has lost control at the state ``t_k`` when, against the controller's answer to that state,

* its thrust axis ``z_b = R e_3`` is further from the commanded one ``z_c = R_c e_3`` (``attitude_cmd``) than
  ``divergence.attitude_error_deg`` (default 90 deg: the rotors push across or against where the law wants
  them to): ``z_b . z_c < cos(bound)``. The attitude error without its yaw: a heading that gives way at the
  rotor limits while the thrust goes where it should is not a loss of control, and neither is a vehicle held by
  the ground or the ceiling (a landed vehicle whose law asks to go lower commands its thrust downwards);
* or its position error ``|p - p_d|`` against the reference position (``reference``) is beyond
  ``divergence.position_error_m`` [m].

The bounds are packed once (:meth:`fsr_sim.model.control_loss.ControlBounds.pack`): ``(cos(attitude bound),
position bound [m])``. The message that names the error is made by :func:`fsr_sim.model.control_loss.loss_reason`.
"""

from __future__ import annotations

import math

from fsr_sim.core.jit import jit
from fsr_sim.core.plant import PlantState
from fsr_sim.core.rigid_body import state_position, state_quaternion

IN_CONTROL, ATTITUDE_LOST, POSITION_LOST = 0, 1, 2


@jit
def thrust_axes_cosine(qx: float, qy: float, qz: float, qw: float, cx: float, cy: float, cz: float,
                       cw: float) -> float:
    """``z . z_c``: the cosine of the angle between the third columns of two rotations given as unit quaternions
    ``[x, y, z, w]`` (``R e_3 = (2 (x z + w y), 2 (y z - w x), 1 - 2 (x^2 + y^2))``)."""
    zx, zy, zz = 2.0 * (qx * qz + qw * qy), 2.0 * (qy * qz - qw * qx), 1.0 - 2.0 * (qx * qx + qy * qy)
    ux, uy, uz = 2.0 * (cx * cz + cw * cy), 2.0 * (cy * cz - cw * cx), 1.0 - 2.0 * (cx * cx + cy * cy)
    return zx * ux + zy * uy + zz * uz


@jit
def held_by_surface(state: PlantState) -> bool:
    """The ground or the ceiling held the vehicle at the end of the last RK4 step."""
    status = state.status[0]
    return status.in_contact or status.at_ceiling


@jit
def control_loss(bounds: tuple, x, position_d, quaternion_c, held: bool) -> int:  # noqa: ANN001
    """``IN_CONTROL``, ``ATTITUDE_LOST`` or ``POSITION_LOST`` for the plant state ``x`` (13,: position world [m],
    velocity, quaternion ``[x, y, z, w]`` body -> world, angular velocity) against the reference position
    ``position_d`` (3,) [m] and the commanded attitude ``quaternion_c`` (4,: ``[x, y, z, w]``), as their messages
    carry them; ``held``: a surface holds the vehicle (its attitude is not checked)."""
    cos_attitude, position_bound = bounds
    qx, qy, qz, qw = state_quaternion(x)
    if not held and thrust_axes_cosine(qx, qy, qz, qw, quaternion_c[0], quaternion_c[1], quaternion_c[2],
                                       quaternion_c[3]) < cos_attitude:
        return ATTITUDE_LOST
    px, py, pz = state_position(x)
    dx, dy, dz = px - position_d[0], py - position_d[1], pz - position_d[2]
    if math.sqrt(dx * dx + dy * dy + dz * dz) > position_bound:
        return POSITION_LOST
    return IN_CONTROL
