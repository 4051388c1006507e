"""The control laws, the null-space objective and goal replanning on closed-form cases."""

import numpy as np
import pytest

from fsr_control.allocation import TiltingActuation
from fsr_control.config.controller_config import controller_config
from fsr_control.controllers.geometric import DEFAULT_GAINS as GEOMETRIC_GAINS
from fsr_control.controllers.geometric import GeometricController
from fsr_control.controllers.voliro import DEFAULT_GAINS as VOLIRO_GAINS
from fsr_control.controllers.voliro import VoliroController
from fsr_control.flight_controller import FlightController
from fsr_control.planning.trajectory import Trajectory, Waypoint
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.rotors import static_tilting_allocation
from fsr_sim.model.so3 import rotation_from_euler_zyx, vee
from fsr_sim.model.vehicle import load_vehicle

HOVER = np.array((0.5, -1.0, -2.0))


def hover_reference(full_attitude=False, rotation=None, time=3.0):
    """The reference of a trajectory that holds its start pose (no waypoints)."""
    rotation = np.eye(3) if rotation is None else rotation
    return Trajectory([], HOVER, rotation, full_attitude=full_attitude).evaluate(time)


def test_geometric_hover_is_the_weight_along_minus_z_and_no_torque():
    vehicle = load_vehicle("quadrotor_ex4")
    law = GeometricController(vehicle, GEOMETRIC_GAINS)
    command = law.compute(hover_reference(), HOVER, np.eye(3), np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(command.force_body, [0.0, 0.0, -vehicle.mass * GRAVITY], atol=1e-12)
    np.testing.assert_allclose(command.torque_body, 0.0, atol=1e-12)
    np.testing.assert_allclose(command.rotation_commanded, np.eye(3), atol=1e-12)


@pytest.mark.parametrize("rpy_deg", [(5.0, 0.0, 0.0), (0.0, -4.0, 0.0), (0.0, 0.0, 10.0), (3.0, 2.0, -6.0)])
def test_geometric_torque_opposes_a_known_attitude_error(rpy_deg):
    """At rest (second call: the measured acceleration is 0, so w_d = w_dot_d = 0) tau = -K_R e_R exactly,
    with e_R = vee(R_d^T R - R^T R_d)/2 and R_d level: the torque turns the vehicle back."""
    vehicle = load_vehicle("quadrotor_ex4")
    law = GeometricController(vehicle, GEOMETRIC_GAINS)
    rotation = rotation_from_euler_zyx(np.deg2rad(rpy_deg))
    reference = hover_reference()
    law.compute(reference, HOVER, rotation, np.zeros(3), np.zeros(3))
    later = hover_reference(time=reference.time + 0.001)
    command = law.compute(later, HOVER, rotation, np.zeros(3), np.zeros(3))
    r_d = command.rotation_commanded
    e_r = vee(r_d.T @ rotation - rotation.T @ r_d) / 2.0
    np.testing.assert_allclose(command.torque_body, -GEOMETRIC_GAINS["k_r"] @ e_r, atol=1e-12)
    assert np.dot(command.torque_body, e_r) < 0.0  # restoring
    np.testing.assert_allclose(r_d[:, 2], [0.0, 0.0, 1.0], atol=1e-12)  # level: the thrust holds the weight


def test_voliro_hover_at_any_attitude_is_the_weight_in_the_body_frame():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    rotation = rotation_from_euler_zyx(np.deg2rad((45.0, 45.0, 0.0)))
    law = VoliroController(vehicle, VOLIRO_GAINS)
    command = law.compute(hover_reference(True, rotation), HOVER, rotation, np.zeros(3), np.zeros(3))
    np.testing.assert_allclose(command.force_body, rotation.T @ [0.0, 0.0, -vehicle.mass * GRAVITY], atol=1e-12)
    np.testing.assert_allclose(command.torque_body, 0.0, atol=1e-12)
    np.testing.assert_allclose(command.rotation_commanded, rotation, atol=1e-15)


def test_laws_refuse_the_wrong_vehicle():
    with pytest.raises(ValueError, match="is fully actuated"):
        GeometricController(load_vehicle("tilting_quadrotor_ex5"), GEOMETRIC_GAINS)
    with pytest.raises(ValueError, match="needs a fully actuated vehicle"):
        VoliroController(load_vehicle("quadrotor_ex4"), VOLIRO_GAINS)


def test_null_space_objective_keeps_the_wrench_and_lowers_the_peak_thrust():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    allocation = static_tilting_allocation(vehicle)
    plain = TiltingActuation.with_objective(vehicle, "none")
    ours = TiltingActuation.with_objective(vehicle, "min_peak_speed", exponent=8, iterations=50)
    wrench = np.array((6.0, -4.5, -4.5, 0.01, -0.02, 0.003))  # roughly the 45/45 deg hover
    u_p = plain.inverse @ wrench
    correction = ours.null_space_correction(u_p)
    np.testing.assert_allclose(allocation @ correction, 0.0, atol=1e-12)  # in the null space: same wrench
    thrust = np.linalg.norm((u_p + correction).reshape(4, 2), axis=1)
    assert thrust.max() < np.linalg.norm(u_p.reshape(4, 2), axis=1).max() - 0.01
    # Converged: the gradient of sum |t_i|^8 along the null space vanishes at the solution.
    per_rotor = ours.null_basis.reshape(4, 2, -1)
    t = (u_p + correction).reshape(4, 2)
    grad = sum(np.linalg.norm(ti) ** 6 * ni.T @ ti for ti, ni in zip(t, per_rotor, strict=True))
    assert np.linalg.norm(grad) < 1e-9 * np.linalg.norm(t) ** 7


def test_set_goal_replans_from_the_current_reference():
    scenario = load_scenario("ex4_geometric")
    sim = simulation_config(scenario)
    controller = FlightController(controller_config(scenario), sim.vehicle, sim.actuation, sim.initial.position,
                                  sim.initial.rotation)
    now = 5.0
    before = controller.reference(now)
    goal = np.array((-2.0, 3.0, -5.0))
    controller.set_goal(goal, rotation_from_euler_zyx(np.deg2rad((0.0, 0.0, -30.0))), now=now, duration=4.0)
    after = controller.reference(now)
    for name in ("position", "velocity", "acceleration"):  # continuous at the replanning time
        np.testing.assert_allclose(getattr(after, name), getattr(before, name), atol=1e-12)
    arrived = controller.reference(now + 4.0)
    np.testing.assert_allclose(arrived.position, goal, atol=1e-12)
    np.testing.assert_allclose(arrived.velocity, 0.0, atol=1e-12)
    assert arrived.yaw == pytest.approx(np.deg2rad(-30.0), abs=1e-12)
    with pytest.raises(ValueError, match="only yaw"):
        controller.set_goal(goal, rotation_from_euler_zyx(np.deg2rad((10.0, 0.0, 0.0))), now=now)


def test_waypoint_type_is_the_planner_input():
    assert Waypoint(np.zeros(3), None, 1.0).hold == 0.0


def test_a_law_is_given_the_horizon_it_declares_and_refuses_another():
    """compute(horizon=...): a law that reads no reference ahead takes none (or an empty one), and a horizon
    of another shape is refused naming the shape it needs."""
    from fsr_control.core.reference import HORIZON_WIDTH

    law = GeometricController(load_vehicle("quadrotor_ex4"), GEOMETRIC_GAINS)
    state = (HOVER, np.eye(3), np.zeros(3), np.zeros(3))
    empty = law.compute(hover_reference(), *state, horizon=np.zeros((0, HORIZON_WIDTH)))
    np.testing.assert_array_equal(empty.force_body, law.compute(hover_reference(), *state).force_body)
    with pytest.raises(ValueError, match=rf"reads the reference 0 samples ahead: horizon must have shape \(0, "
                                         rf"{HORIZON_WIDTH}\), got \(5, {HORIZON_WIDTH}\)"):
        law.compute(hover_reference(), *state, horizon=np.zeros((5, HORIZON_WIDTH)))
