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
``N_i^T N_i`` is precomputed (the first Hessian term is then one matrix product) and the 2 x 2 Newton
system of the tilting quadrotor is solved in closed form (numpy's per-call overhead dominates at this
size). The wrench is unchanged
(to rounding): tracking is the same, only the rotor speeds and tilt angles change. Over the exercise-5
flight it lowers the peak rotor speed while the vehicle holds roll = pitch = 45 deg (numbers in the README,
"Voliro secondary objective", checked by ``tests/flights/test_flight_ex5.py``).
"""

from __future__ import annotations

import numpy as np


class PeakThrustObjective:
    """Null-space correction ``N z`` that minimises ``sum_i |t_i|^p`` (module docstring)."""

    def __init__(self, null_basis: np.ndarray, exponent: int = 8, iterations: int = 3) -> None:
        if exponent < 4 or exponent % 2:
            raise ValueError(f"exponent must be an even integer >= 4, got {exponent}")
        if iterations < 1:
            raise ValueError(f"iterations must be >= 1, got {iterations}")
        self.basis = np.asarray(null_basis, dtype=float)  # (2n, k)
        rows, self.dimension = self.basis.shape
        self.rotor_count = rows // 2
        self.per_rotor = self.basis.reshape(self.rotor_count, 2, self.dimension)  # N_i: (2, k)
        self.exponent = exponent
        self.iterations = iterations
        self._z = np.zeros(self.dimension)  # previous solution [N], warm start
        # N_i^T N_i per rotor, flattened: sum_i w_i N_i^T N_i = (w @ ntn).reshape(k, k).
        self._ntn = np.einsum("ijk,ijl->ikl", self.per_rotor, self.per_rotor).reshape(self.rotor_count, -1)

    def correction(self, u_p: np.ndarray) -> np.ndarray:
        """``N z`` [N] to add to the minimum-norm solution ``u_p`` (shape (2n,))."""
        if self.dimension == 0:
            return np.zeros_like(u_p)
        pairs = u_p.reshape(self.rotor_count, 2)
        scale = float(np.sqrt(np.einsum("ij,ij->i", pairs, pairs)).sum()) / self.rotor_count  # the mean, as np.mean
        if not scale > 1e-9:
            self._z[:] = 0.0
            return np.zeros_like(u_p)
        half = self.exponent // 2
        k = self.dimension
        u = u_p / scale
        z = self._z / scale
        for _ in range(self.iterations):
            t = (u + self.basis @ z).reshape(self.rotor_count, 2)
            sq = np.einsum("ij,ij->i", t, t)  # |t_i|^2
            nt = np.einsum("ijk,ij->ik", self.per_rotor, t)  # N_i^T t_i, (n, k)
            w1 = sq ** (half - 1)  # |t_i|^(p-2)
            w2 = (self.exponent - 2) * sq ** (half - 2)  # (p-2) |t_i|^(p-4)
            grad = w1 @ nt
            hess = (w1 @ self._ntn).reshape(k, k) + (nt.T * w2) @ nt
            z = z - _solve(hess, grad)
        self._z = z * scale
        return self.basis @ self._z

    def reset(self) -> None:
        self._z[:] = 0.0


def _solve(matrix: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``A^-1 b`` for the small symmetric positive-definite Hessian: closed form for 2 x 2 (the tilting
    quadrotor), LAPACK otherwise."""
    if rhs.shape == (2,):
        (a, b), (c, d) = matrix.tolist()
        r0, r1 = rhs.tolist()
        det = a * d - b * c
        return np.array(((d * r0 - b * r1) / det, (a * r1 - c * r0) / det))
    return np.linalg.solve(matrix, rhs)
