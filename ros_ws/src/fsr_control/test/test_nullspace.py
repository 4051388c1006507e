import numpy as np

from fsr_control.allocation import TiltingActuation
from fsr_sim.model.rotors import static_tilting_allocation
from fsr_sim.model.vehicle import load_vehicle


def test_reports_null_space_step_is_a_no_op_and_ours_keeps_the_wrench():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    allocation = static_tilting_allocation(vehicle)
    plain = TiltingActuation.with_objective(vehicle, "none")
    ours = TiltingActuation.with_objective(vehicle, "min_peak_speed")
    wrench = np.array((6.0, -4.5, -4.5, 0.01, -0.02, 0.003))  # roughly the 45/45 deg hover
    u_p = plain.inverse @ wrench
    assert np.abs(plain.null_basis.T @ u_p).max() < 1e-12  # z = -N^T u_p = 0
    a, b = plain.allocate(0.0, wrench[:3], wrench[3:]), ours.allocate(0.0, wrench[:3], wrench[3:])
    np.testing.assert_allclose(np.concatenate((b.force_body, b.torque_body)), wrench, atol=1e-9)
    np.testing.assert_allclose(allocation @ (plain.inverse @ wrench), wrench, atol=1e-12)
    assert b.rotor_speeds.max() < a.rotor_speeds.max() - 1.0
