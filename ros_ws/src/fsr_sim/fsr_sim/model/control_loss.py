"""Loss of control: the scenario's bounds (``divergence``), packed for the compiled check
(:mod:`fsr_sim.core.control_loss`), and the message that says which bound a flight crossed.

``divergence.attitude_error_deg`` (default :data:`DEFAULT_ATTITUDE_ERROR_DEG`, in (0, 180]): the angle between the
thrust axis ``R e_3`` and the commanded one ``R_c e_3`` (the attitude error without yaw) beyond which the flight
has lost control (180: never); ``divergence.position_error_m`` (default :data:`DEFAULT_POSITION_ERROR_M`, > 0):
the same for ``|p - p_d|`` [m] against the reference position. A flight that crosses one ends as ``diverged``
(exit 3) at that state, with the reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_sim.core import control_loss as core

DEFAULT_ATTITUDE_ERROR_DEG = 90.0
DEFAULT_POSITION_ERROR_M = 5.0
SECTION = "divergence"


@dataclass(frozen=True)
class ControlBounds:
    """The ``divergence`` section: how far from its reference a flight may go before it has lost control."""

    attitude_error_deg: float = DEFAULT_ATTITUDE_ERROR_DEG
    position_error_m: float = DEFAULT_POSITION_ERROR_M

    def pack(self) -> tuple[float, float]:
        """``(cos(attitude bound), position bound [m])`` for :func:`fsr_sim.core.control_loss.control_loss` (an
        attitude bound of 180 deg can never be crossed: below any cosine)."""
        bound = math.radians(self.attitude_error_deg)
        return (math.cos(bound) if self.attitude_error_deg < 180.0 else -2.0, float(self.position_error_m))


def loss_reason(code: int, bounds: ControlBounds, state_vector: np.ndarray, position_d: np.ndarray,
                quaternion_c: np.ndarray, time_s: float) -> str:
    """The message of a :func:`fsr_sim.core.control_loss.control_loss` code at ``time_s`` [s]: which error, how
    large, the bound and the scenario key that sets it."""
    x = np.asarray(state_vector, float)
    if code == core.ATTITUDE_LOST:
        c = [float(v) for v in quaternion_c]
        cosine = max(-1.0, min(1.0, core.thrust_axes_cosine(*(float(v) for v in x[6:10]), *c)))
        return (f"lost control at t = {time_s:.4f} s: thrust axis {math.degrees(math.acos(cosine)):.2f} deg from the "
                f"commanded one beyond {bounds.attitude_error_deg:g} deg ({SECTION}.attitude_error_deg)")
    error = float(np.linalg.norm(x[0:3] - np.asarray(position_d, float)))
    return (f"lost control at t = {time_s:.4f} s: position error {error:.4g} m from the reference beyond "
            f"{bounds.position_error_m:g} m ({SECTION}.position_error_m)")
