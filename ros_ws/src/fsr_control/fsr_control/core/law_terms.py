"""What the control laws of the compiled core share: the compensation they are handed and their PD terms."""

from __future__ import annotations

from typing import NamedTuple

from fsr_sim.core.jit import jit
from fsr_sim.core.so3 import Mat3, Vec3


class Compensation(NamedTuple):
    """The estimated external wrench a law cancels: force [N] world NED, torque [N m] body FRD, and the force's
    first and second time differences [N/s, N/s^2] (world); ``active`` False: the law as written."""

    active: bool
    force: Vec3
    torque: Vec3
    force_rate: Vec3
    force_acceleration: Vec3


NO_COMPENSATION = Compensation(False, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


@jit
def linear_feedback(k_a: Mat3, e_a: Vec3, k_b: Mat3, e_b: Vec3, scale: float, feedforward: Vec3) -> Vec3:
    """``-K_a e_a - K_b e_b + scale * feedforward`` (the PD terms of the laws)."""
    (a00, a01, a02), (a10, a11, a12), (a20, a21, a22) = k_a
    (b00, b01, b02), (b10, b11, b12), (b20, b21, b22) = k_b
    x, y, z = e_a
    u, v, w = e_b
    fx, fy, fz = feedforward
    return (
        -(a00 * x + a01 * y + a02 * z) - (b00 * u + b01 * v + b02 * w) + scale * fx,
        -(a10 * x + a11 * y + a12 * z) - (b10 * u + b11 * v + b12 * w) + scale * fy,
        -(a20 * x + a21 * y + a22 * z) - (b20 * u + b21 * v + b22 * w) + scale * fz,
    )
