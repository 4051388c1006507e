"""The estimator on a stream of stamped samples: pairs each state with the command of the same stamp.

The estimator node receives ``odom`` (the state at ``t_k``) and ``wrench_cmd`` (the actuator wrench the
controller commanded for ``t_k``) as two topics, in any order; the in-process flight hands both over
directly. Both go through :class:`StampedEstimator`, so they run the observer on the same sample sequence:

* a sample is processed when both halves of stamp ``t_k`` have arrived; a half older than (or equal to) the
  last processed stamp can never be paired in order and is dropped (with a warning);
* unpaired halves are kept for at most ``max_pending`` stamps per stream (oldest dropped first);
* the sample time is the stamp difference, which must be the control period (relative tolerance
  ``period_tolerance``); a gap or a jump resets the observer, so that sample becomes ``k = 0`` again;
* without a known control period, the first two paired stamps give it (the first sample is held until then).

No ROS here: stamps are integer nanoseconds, the state is (``R`` body -> world, velocity world [m/s],
angular velocity body [rad/s]), the command (force [N], torque [N m]) in the body frame.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fsr_estimation.core.observer_step import euler_inputs
from fsr_estimation.estimator.observer import MomentumObserver, _vector
from fsr_sim.core.so3 import matrix_rows

MAX_PENDING = 1000  # unpaired stamps kept per stream (about 1 s at 1 kHz; the node keeps a whole stream queue)
PERIOD_TOLERANCE = 0.01  # relative deviation of a stamp difference from the control period that is accepted


@dataclass(frozen=True)
class Estimate:
    """The observer's output for the sample stamped ``stamp_ns``: force [N] and torque [N m] in the body frame
    (``R_b^T f_e``, ``Q^-T tau_e``: comparable with the true external wrench) and the mass estimate [kg]."""

    stamp_ns: int
    force_body: np.ndarray
    torque_body: np.ndarray
    mass: float


class StampedEstimator:
    """Pairs stamped states and commands and runs a :class:`MomentumObserver` on each pair in stamp order.

    Parameters
    ----------
    mass : float
        Model mass [kg].
    inertia : array-like, shape (3,) or (3, 3)
        Model inertia [kg m^2], body frame.
    c0 : float
        Filter bandwidth [rad/s].
    r : int
        Filter order.
    control_period : float, optional
        Sample time [s]; None: taken from the first two paired stamps.
    warn : callable, optional
        Receives one line per dropped or inconsistent sample.
    """

    def __init__(self, mass: float, inertia: np.ndarray, c0: float, r: int, control_period: float | None = None,
                 warn: Callable[[str], None] | None = None, max_pending: int = MAX_PENDING) -> None:
        self.model = (mass, inertia, c0, r)
        self.control_period = control_period
        self.warn = warn if warn is not None else _ignore
        self.max_pending = max_pending
        self.observer = None if control_period is None else MomentumObserver(mass, inertia, c0, r, control_period)
        self._states: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._commands: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._last_stamp: int | None = None
        self._first_sample: tuple | None = None  # held until the period is known

    def warm_up(self) -> None:
        """Load the compiled observer now (numba's start-up and its cache, ~0.3 s), on a throwaway observer:
        a node calls this before it subscribes, so that the first samples do not wait for it."""
        mass, inertia, c0, r = self.model
        scratch = StampedEstimator(mass, inertia, c0, r, self.control_period or 1.0 / c0)
        scratch.add_state(0, np.eye(3), np.zeros(3), np.zeros(3))
        scratch.add_command(0, np.zeros(3), np.zeros(3))

    @property
    def last_stamp(self) -> int | None:
        """Stamp [ns] of the last processed pair (None before the first)."""
        return self._last_stamp

    def add_state(self, stamp_ns: int, rotation: np.ndarray, velocity_world: np.ndarray,
                  angular_velocity_body: np.ndarray) -> Estimate | None:
        """The state stamped ``stamp_ns``; returns the estimate if this completes a pair."""
        eta, eta_dot = euler_inputs(matrix_rows(np.ascontiguousarray(rotation, dtype=float)),
                                    _vector(angular_velocity_body))
        return self._store(self._states, stamp_ns, (velocity_world, eta, eta_dot))

    def add_command(self, stamp_ns: int, force_body: np.ndarray, torque_body: np.ndarray) -> Estimate | None:
        """The actuator wrench commanded for the state stamped ``stamp_ns``; the estimate if a pair is complete."""
        return self._store(self._commands, stamp_ns, (force_body, torque_body))

    def reset(self) -> None:
        """Forget everything: the next paired sample starts a new estimate from zero."""
        if self.observer is not None:
            self.observer.reset()
        self._states.clear()
        self._commands.clear()
        self._first_sample = None
        self._last_stamp = None

    def _store(self, pending: dict, stamp: int, value: tuple) -> Estimate | None:
        if self._last_stamp is not None and stamp <= self._last_stamp:
            self.warn(f"sample at {stamp} ns is not newer than the last one processed: dropped")
            return None
        pending[stamp] = value
        estimate = None
        if stamp in self._states and stamp in self._commands:
            estimate = self._process(stamp, *self._states.pop(stamp), *self._commands.pop(stamp))
        for table in (self._states, self._commands):
            while len(table) > self.max_pending:
                del table[next(iter(table))]  # oldest first (insertion order)
        return estimate

    def _process(self, stamp: int, velocity_world: np.ndarray, eta: np.ndarray, eta_dot: np.ndarray,
                 force_body: np.ndarray, torque_body: np.ndarray) -> Estimate | None:
        sample = (velocity_world, eta, eta_dot, force_body, torque_body)
        previous, self._last_stamp = self._last_stamp, stamp
        for table in (self._states, self._commands):  # anything older can never be paired in order any more
            for old in [s for s in table if s < stamp]:
                del table[old]
        if previous is not None and not self._period_ok(stamp - previous) and self.observer is not None:
            self.observer.reset()  # this sample becomes k = 0 of a new estimate
        if self.observer is None:
            if self._first_sample is None or previous is None:
                self._first_sample = sample
                return None
            self.control_period = (stamp - previous) * 1e-9
            self.observer = MomentumObserver(*self.model, self.control_period)  # ValueError if c0 T >= 2
            self.observer.update(*self._first_sample)
            self._first_sample = None
        self.observer.update(*sample)
        force, torque = self.observer.wrench_body()
        return Estimate(stamp, force, torque, self.observer.mass_estimate)

    def _period_ok(self, step_ns: int) -> bool:
        """True if the stamp difference is one control period; else warn (the caller resets)."""
        if self.control_period is None:
            return True
        expected_ns = self.control_period * 1e9
        if abs(step_ns - expected_ns) <= PERIOD_TOLERANCE * expected_ns:
            return True
        self.warn(f"stamp step {step_ns * 1e-9:.6f} s differs from the control period "
                  f"{self.control_period:.6f} s (gap or dropped sample): observer reset")
        return False


def _ignore(_message: str) -> None:
    """Default ``warn``: drop the message."""
