"""The control laws a scenario can name (``controller.type``): what each needs and its default gains.

A law's per-step function lives in the compiled core (:mod:`fsr_control.core.laws`, selected by its kind);
this table is everything else the configuration and the controller need to know of it. A new law adds one
entry (``docs/extending.md``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_control.controllers import geometric, voliro
from fsr_control.core import laws


@dataclass(frozen=True)
class LawType:
    """A control law of the compiled core.

    Attributes
    ----------
    kind : int
        Its kind in :func:`fsr_control.core.laws.control_law`.
    default_gains : dict
        Gain name -> (3, 3) array, in the order of the core's four gain slots (``k_p``, ``k_v``, ``k_r``,
        ``k_w`` of :class:`~fsr_control.core.laws.LawParams`); a scenario's ``controller.gains`` takes these names.
    fully_actuated : bool
        The law commands a whole body wrench (a vehicle whose rotors produce any wrench, allocated to rotors);
        False: thrust along ``-z_b`` and a torque (a vehicle that is not fully actuated).
    horizon_steps, horizon_dt : int, float
        The reference ahead the law reads: ``horizon_steps`` samples ``horizon_dt`` [s] apart (0: none).
    """

    kind: int
    default_gains: dict[str, np.ndarray]
    fully_actuated: bool
    horizon_steps: int = 0
    horizon_dt: float = 0.0


LAWS: dict[str, LawType] = {
    "geometric": LawType(laws.GEOMETRIC, geometric.DEFAULT_GAINS, fully_actuated=False),
    "voliro": LawType(laws.VOLIRO, voliro.DEFAULT_GAINS, fully_actuated=True),
}
