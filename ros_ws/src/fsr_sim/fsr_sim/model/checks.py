"""Checks of model inputs given as plain Python values (the configuration layer adds file and key)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


class InvalidValueError(ValueError):
    """A model input was refused: ``name`` (what it is) and ``reason``; ``str()`` reads ``name: reason``."""

    def __init__(self, name: str, reason: str) -> None:
        self.name = name
        self.reason = reason
        super().__init__(f"{name}: {reason}")


def finite_array(value: ArrayLike, shape: tuple[int, ...], name: str) -> np.ndarray:
    """``value`` as a finite float array of ``shape``.

    Raises
    ------
    InvalidValueError
        A ``ValueError`` naming ``name``, the expected shape and what arrived (wrong shape, NaN or inf).
    """
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidValueError(name, f"expected numbers of shape {shape}, got {value!r}") from None
    if array.shape != shape:
        raise InvalidValueError(name, f"expected shape {shape}, got {array.shape} ({value!r})")
    if not np.all(np.isfinite(array)):
        raise InvalidValueError(name, f"must be finite, got {value!r}")
    return array


def symmetric_positive_definite(value: ArrayLike, name: str, semidefinite: bool = False) -> np.ndarray:
    """A 3x3 symmetric positive-definite matrix (an inertia [kg m^2] or a gain) from 3 numbers or a 3x3
    (``semidefinite``: positive semi-definite, zero eigenvalues allowed).

    Parameters
    ----------
    value : array-like, shape (3,) or (3, 3)
        The diagonal, or the full matrix.
    name : str
        What the value is, for the error message.

    Returns
    -------
    numpy.ndarray, shape (3, 3)

    Raises
    ------
    InvalidValueError
        A ``ValueError``: for another shape, NaN/inf, an asymmetric matrix or a non-positive eigenvalue.
    """
    array = np.asarray(value, dtype=float) if _numeric(value) else None
    if array is None or array.shape not in ((3,), (3, 3)):
        shown = repr(value) if array is None else array.tolist()
        raise InvalidValueError(name, f"must be 3 numbers (the diagonal) or a 3 x 3 matrix, got {shown}")
    matrix = np.diag(finite_array(value, (3,), name)) if array.shape == (3,) else finite_array(value, (3, 3), name)
    if not np.allclose(matrix, matrix.T, rtol=0.0, atol=1e-12 * max(1.0, float(np.abs(matrix).max()))):
        raise InvalidValueError(name, f"must be symmetric, got {matrix.tolist()}")
    eigenvalues = np.linalg.eigvalsh(matrix)
    if semidefinite and eigenvalues.min() < -1e-12 * max(1.0, float(np.abs(matrix).max())):
        raise InvalidValueError(name, f"must be positive semi-definite (>= 0), got eigenvalues {eigenvalues.tolist()}")
    if not semidefinite and eigenvalues.min() <= 0.0:
        raise InvalidValueError(name, f"must be positive definite, got eigenvalues {eigenvalues.tolist()}")
    return matrix


def _numeric(value: ArrayLike) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True
