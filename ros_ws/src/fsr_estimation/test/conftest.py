"""Shared fixtures: the report's flight log (its .mat where it is, else the shipped MCAP conversion) and a
synthetic one."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from fsr_estimation.io.flight_log import FlightLog, body_force_from_thrust, load_flight_log, load_mat

REPO = Path(__file__).resolve().parents[4]
REPORT_MAT = REPO.parent / "shared" / "data" / "ws_homework_3_2025.mat"
EXAMPLE_MCAP = REPO / "examples" / "ex3_flight_log.mcap"
MASS = 1.5
INERTIA = np.diag([1.2416, 1.2416, 2.4832])
TRUTH = np.array([1.0, 1.0, 0.0, 0.0, 0.0, -0.4])

# docs/model.md §5 (the report's Tables 3 and 4, c0 = 10): r -> (settle f_x, f_y, tau_z [s], MAE f_x, f_y, tau_z)
REPORT_TABLE = {
    1: (3.751, 3.753, 2.545, 0.0077, 0.0077, 0.0040),
    2: (3.845, 3.847, 2.680, 0.0107, 0.0107, 0.0053),
    3: (3.937, 3.940, 2.826, 0.0139, 0.0139, 0.0067),
    4: (4.028, 4.031, 2.970, 0.0170, 0.0170, 0.0080),
    5: (4.117, 4.120, 3.110, 0.0202, 0.0202, 0.0093),
}
# The report's Table 4 max errors after 25 s (f_x, f_y, tau_z), printed with 6 and 13 significant digits.
REPORT_MAX_ERROR = {
    1: (0.132517e-6, 0.131980e-6, 0.002633880761213),
    2: (0.164746e-6, 0.164600e-6, 0.002633880615723),
    3: (0.168812e-6, 0.168662e-6, 0.002633880483493),
    4: (0.153803e-6, 0.153426e-6, 0.002633880363335),
    5: (0.139914e-6, 0.139336e-6, 0.002633880254139),
}


REF = SimpleNamespace(
    REPO=REPO, REPORT_MAT=REPORT_MAT, EXAMPLE_MCAP=EXAMPLE_MCAP, MASS=MASS, INERTIA=INERTIA, TRUTH=TRUTH,
    REPORT_TABLE=REPORT_TABLE, REPORT_MAX_ERROR=REPORT_MAX_ERROR,
)


@pytest.fixture(scope="session")
def ref() -> SimpleNamespace:
    """Reference values (docs/model.md §5) and paths; test modules cannot import conftest (importlib mode)."""
    return REF


@pytest.fixture(scope="session")
def synthetic():
    """:func:`synthetic_log` as a fixture."""
    return synthetic_log


@pytest.fixture(scope="session")
def report_mat() -> Path:
    """The report's own .mat log, for the tests of the .mat reader: it is the course's data, not shipped
    with fsr (the same flight, converted, is ``examples/ex3_flight_log.mcap``)."""
    if not REPORT_MAT.is_file():
        pytest.skip(f"the report's .mat log is not in this checkout ({REPORT_MAT}: the course's data, not shipped; "
                    f"the same flight converted to MCAP, {EXAMPLE_MCAP.name}, is tested instead)")
    return REPORT_MAT


@pytest.fixture(scope="session")
def report_log() -> FlightLog:
    """The report's exercise-3 flight: its .mat log where it is, else the shipped MCAP conversion of it."""
    return load_mat(REPORT_MAT) if REPORT_MAT.is_file() else load_flight_log(EXAMPLE_MCAP)


def synthetic_log(n: int = 4000, sample_time: float = 0.001, mass: float = MASS,
                  force_world: np.ndarray | None = None, seed: int = 0) -> tuple[FlightLog, np.ndarray]:
    """A hovering-ish log whose translational momentum obeys the discrete model exactly with a constant
    external world force: ``m (v[k+1] - v[k]) = T_s (m g e3 + R f_b + f_ext)``; attitude held constant."""
    rng = np.random.default_rng(seed)
    force_world = np.array([0.3, -0.2, -0.5]) if force_world is None else force_world
    eta = np.tile([0.05, -0.03, 0.4], (n, 1))
    from fsr_sim.model.so3 import rotation_from_euler_zyx

    rotation = rotation_from_euler_zyx(eta[0])
    thrust = mass * 9.81 / rotation[2, 2] + 0.05 * rng.standard_normal(n)
    force_body = body_force_from_thrust(thrust)
    acceleration = (mass * 9.81 * np.array([0, 0, 1.0]) + force_body @ rotation.T + force_world) / mass
    velocity = np.zeros((n, 3))
    velocity[1:] = np.cumsum(sample_time * acceleration[:-1], axis=0)
    log = FlightLog(time=np.arange(n) * sample_time, eta=eta, eta_dot=np.zeros((n, 3)), velocity_world=velocity,
                    force_body=force_body, torque_body=np.zeros((n, 3)), source="synthetic")
    return log, force_world
