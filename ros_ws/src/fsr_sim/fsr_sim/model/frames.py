"""Frames: the one place where fsr states them (docs/model.md §2); gravity's ``g`` is declared once, with the
compiled core (:data:`fsr_sim.core.rigid_body.GRAVITY`).

World frame NED (``world_ned``: x north, y east, z down), body frame FRD (``base_link_frd``: x forward,
y right, z down). Gravity acts along ``+e3`` of the world frame with ``g = 9.81`` m/s^2, so the weight of
a mass ``m`` is ``m g e3`` [N] (world).
"""

from __future__ import annotations

import numpy as np

E3 = np.array((0.0, 0.0, 1.0))  # world down axis (NED) / body down axis (FRD)
E3.flags.writeable = False
