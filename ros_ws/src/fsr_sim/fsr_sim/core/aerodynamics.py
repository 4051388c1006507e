"""Aerodynamics at speed (compiled core): the airframe's parasitic drag and each rotor's drag (H-force), induced
inflow, translational lift and blade flapping, as RotorPy's ``Multirotor`` models them (docs/model.md §3.4,
*Aerodynamics*). All in the body frame FRD, SI units.

The air velocity is the vehicle's relative to the air, ``v_a = R^T (v - v_wind)`` [m/s] (``v`` and the wind
world NED); at rotor ``i`` (hub ``p_i``, unit thrust axis ``z_i``, speed ``w_i`` [rad/s]) it is
``v_i = v_a + omega x p_i``, with the axial part ``v_i,z = (v_i . z_i)`` and the in-plane part
``v_i,p = v_i - v_i,z z_i``:

    D      = -|v_a| C v_a                                  parasitic drag at the CoM [N], C = diag(c_x, c_y, c_z)
    H_i    = -w_i (k_d v_i,p + k_z v_i,z z_i)              rotor drag (in-plane) and induced inflow (axial) [N]
    L_i    = k_h |v_i,p|^2 z_i                             translational lift [N]
    M_i    = -k_flap w_i (v_i x z_i)                       blade flapping moment [N m]

    f_aero   = D + sum_i (H_i + L_i)
    tau_aero = sum_i (p_i x (H_i + L_i) + M_i)

``k_d``, ``k_z`` [N s / (m rad)] = [kg/rad], ``k_h`` [N s^2/m^2] = [kg/m], ``k_flap`` [N m s / (m rad)] = [kg m/rad]
(RotorPy's names). For rotors along ``-z_b`` this is RotorPy's ``compute_body_wrench`` term by term (its body
frame is FLU: the map to FRD is a proper rotation, so every cross product keeps its form). A tilting rotor's
axis is that of its current columns (force column / ``c_f``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit_inline
from fsr_sim.core.rotors import FORCE_COLUMN


class AeroParams(NamedTuple):
    """The aerodynamic coefficients (module docstring); a term whose coefficients are zero costs nothing."""

    parasitic: bool  # some drag coefficient > 0
    rotor: bool  # some rotor coefficient > 0 (rotor actuation only: in wrench actuation there are no rotors)
    drag: np.ndarray  # (3,) C [N s^2/m^2] per body axis
    rotor_drag: float  # k_d [kg/rad]
    inflow: float  # k_z [kg/rad]
    lift: float  # k_h [kg/m]
    flapping: float  # k_flap [kg m/rad]
    positions: np.ndarray  # (n, 3) rotor hubs, body FRD [m]
    thrust_coefficient: float  # c_f [N s^2]: a rotor's axis is its force column divided by it


@jit_inline
def has_aerodynamics(params: AeroParams) -> bool:
    return params.parasitic or params.rotor


@jit_inline
def aerodynamic_wrench(params: AeroParams, columns, speeds, air: tuple, omega: tuple) -> tuple:  # noqa: ANN001
    """(force [N], torque [N m]), body FRD, of the air velocity ``air`` (``v_a``, body [m/s]) on a vehicle turning
    at ``omega`` (body [rad/s]) with rotors of ``columns`` (n, 9) at ``speeds`` (n,) [rad/s] (module docstring)."""
    ax, ay, az = air
    fx = fy = fz = 0.0
    tx = ty = tz = 0.0
    if params.parasitic:
        speed = math.sqrt(ax * ax + ay * ay + az * az)
        c = params.drag
        fx, fy, fz = -speed * (c[0] * ax), -speed * (c[1] * ay), -speed * (c[2] * az)
    if not params.rotor:
        return (fx, fy, fz), (tx, ty, tz)
    wx, wy, wz = omega
    k_d, k_z, k_h, k_flap = params.rotor_drag, params.inflow, params.lift, params.flapping
    c_f = params.thrust_coefficient
    positions = params.positions
    for i in range(positions.shape[0]):
        px, py, pz = positions[i, 0], positions[i, 1], positions[i, 2]
        vx = ax + (wy * pz - wz * py)  # v_a + omega x p_i
        vy = ay + (wz * px - wx * pz)
        vz = az + (wx * py - wy * px)
        zx = columns[i, FORCE_COLUMN] / c_f
        zy = columns[i, FORCE_COLUMN + 1] / c_f
        zz = columns[i, FORCE_COLUMN + 2] / c_f
        axial = vx * zx + vy * zy + vz * zz
        qx, qy, qz = vx - axial * zx, vy - axial * zy, vz - axial * zz  # in-plane
        w = speeds[i]
        lift = k_h * (qx * qx + qy * qy + qz * qz)
        hx = -w * (k_d * qx + k_z * axial * zx) + lift * zx
        hy = -w * (k_d * qy + k_z * axial * zy) + lift * zy
        hz = -w * (k_d * qz + k_z * axial * zz) + lift * zz
        fx, fy, fz = fx + hx, fy + hy, fz + hz
        flap = -k_flap * w
        tx += (py * hz - pz * hy) + flap * (vy * zz - vz * zy)
        ty += (pz * hx - px * hz) + flap * (vz * zx - vx * zz)
        tz += (px * hy - py * hx) + flap * (vx * zy - vy * zx)
    return (fx, fy, fz), (tx, ty, tz)
