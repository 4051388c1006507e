"""Secondary objective of the tilting-rotor allocation: lower the peak rotor speed through the null space.

The static allocation ``G u = wrench`` (6 x 2n, ``u = [u_v1, u_l1, ..., u_vn, u_ln]`` [N]) of a tilting
quadrotor has a 2-dimensional null space ``N`` (orthonormal columns). Every ``u = u_p + N z`` produces the
same wrench. The report chose ``z = -N^T u_p`` with ``u_p = A^+ y``; but ``A^+ y`` is the minimum-norm
solution and already orthogonal to the null space, so ``N^T u_p = 0`` and that step changes nothing
(``ros_ws/src/fsr_control/test/test_nullspace.py`` checks it).

What we do instead (``secondary_objective: {type: min_peak_speed}``): choose ``z`` to minimise

    J(z) = sum_i |t_i(z)|^p,   t_i = (u_v,i, u_l,i) + N_i z,   p even (default 8),

i.e. a smooth stand-in for the largest rotor thrust ``max_i |t_i| = c_f max_i w_i^2``: the rotor that
limits the vehicle (the first to saturate) is unloaded by the ones with headroom, and rotor speeds are
equalised. ``J`` is convex in ``z``; a few Newton steps per control step (warm-started from the previous
step's ``z``) solve it, with

    grad = p sum_i |t_i|^(p-2) N_i^T t_i,
    hess = p sum_i (|t_i|^(p-2) N_i^T N_i + (p - 2) |t_i|^(p-4) (N_i^T t_i)(N_i^T t_i)^T).

Thrusts are scaled by their mean before the steps so that the powers stay near 1. The constant
``N_i^T N_i`` is precomputed once (:func:`null_space_gram`) and the Newton steps run in the compiled core
(:func:`fsr_control.core.allocation.null_space_correction`; the 2 x 2 system of the tilting quadrotor in
closed form). The wrench is unchanged
(to rounding): tracking is the same, only the rotor speeds and tilt angles change. Over the exercise-5
flight it lowers the peak rotor speed while the vehicle holds roll = pitch = 45 deg (numbers in docs/differences.md,
"Voliro secondary objective", checked by ``tests/flights/test_flight_ex5.py``).
"""

from __future__ import annotations

import numpy as np


def null_space_gram(null_basis: np.ndarray) -> np.ndarray:
    """``N_i^T N_i`` of every rotor ``i`` (rows ``2i, 2i + 1`` of the null basis (2n, k)), flattened: (n, k * k)."""
    rows, k = null_basis.shape
    per_rotor = null_basis.reshape(rows // 2, 2, k)
    return np.ascontiguousarray(np.einsum("ijk,ijl->ikl", per_rotor, per_rotor).reshape(rows // 2, k * k))
