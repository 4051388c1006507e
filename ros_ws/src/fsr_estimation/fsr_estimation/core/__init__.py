"""The momentum observer's compiled step (numba; :mod:`fsr_estimation.core.observer_step`)."""
