"""Priority allocation (fsr_control.core.allocation) on hand-made wrenches: what gives way, and by how much."""

from dataclasses import replace

import numpy as np
import pytest

from fsr_control.allocation import FixedRotorActuation, FixedRotorAllocator, TiltingActuation
from fsr_control.core.allocation import max_scale_in_box, max_scale_in_discs
from fsr_sim.model.rotors import (
    SHORTFALL_TOLERANCE,
    SaturationReport,
    static_tilting_allocation,
    wrench_from_rotor_speed_sq,
)
from fsr_sim.model.vehicle import load_vehicle


class FixedDesaturation:
    """The core's priority allocation of fixed rotors, with and without air mode."""

    def __init__(self, vehicle):
        self.air_mode = FixedRotorActuation(vehicle, "priority", air_mode=True)
        self.keeping_thrust = FixedRotorActuation(vehicle, "priority", air_mode=False)

    def allocate(self, thrust, torque):
        return self.air_mode.desaturated(thrust, torque)

    def allocate_keeping_thrust(self, thrust, torque):
        """The thrust exact and the torque scaled; None when the thrust alone does not fit."""
        u_g = thrust * -self.keeping_thrust.inverse[:, 2]
        low, high = self.keeping_thrust.params.speed_min ** 2, self.keeping_thrust.params.speed_max ** 2
        if not np.all((low <= u_g) & (u_g <= high)):
            return None
        return self.keeping_thrust.desaturated(thrust, torque)


def fixed(name: str, speed_min: float | None = None):
    vehicle = load_vehicle(name)
    if speed_min is not None:
        vehicle = replace(vehicle, rotor_speed_min=speed_min)
    allocator = FixedRotorAllocator(vehicle)
    return vehicle, allocator, FixedDesaturation(vehicle), (vehicle.rotor_speed_min**2, vehicle.rotor_speed_max**2)


def produced(vehicle, u_w) -> np.ndarray:
    """[u_T, tau_x, tau_y, tau_z] of squared speeds u_w."""
    wrench = wrench_from_rotor_speed_sq(vehicle) @ np.asarray(u_w)
    return np.array((-wrench[2], *wrench[3:]))


def assert_in_box(u_w, box, rel=1e-12):
    u_w = np.asarray(u_w)
    assert np.all(u_w >= box[0] - rel * box[1]) and np.all(u_w <= box[1] * (1 + rel))


def test_max_scale_in_box_and_discs_closed_form():
    # base 0.5 in [0, 1]: direction +1 reaches the top at s = 0.5, direction -2 the bottom at s = 0.25.
    a = np.array
    assert max_scale_in_box(a([0.5, 0.5]), a([1.0, -2.0]), 0.0, 1.0) == 0.25
    assert max_scale_in_box(a([0.5]), a([0.1]), 0.0, 1.0) == 1.0  # fits entirely
    assert max_scale_in_box(a([1.0 + 1e-15]), a([1.0]), 0.0, 1.0) == 0.0  # rounding outside: no room
    # Disc of radius 5 from (3, 0) along (0, 8): |(3, 8 s)| = 5 at s = 0.5.
    assert max_scale_in_discs(a([3.0, 0.0]), a([0.0, 8.0]), 25.0) == pytest.approx(0.5, rel=1e-15)
    assert max_scale_in_discs(a([0.0, 0.0, 1.0, 0.0]), a([1.0, 0.0, 0.0, 0.0]), 4.0) == 1.0


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_infeasible_yaw_keeps_thrust_and_roll_pitch_exactly_and_yaw_is_the_largest_that_fits(name):
    vehicle, allocator, desaturation, box = fixed(name)
    thrust, torque = 1.3 * vehicle.weight, (0.08, -0.05, 2.0)  # far more yaw torque than the drag can give
    unconstrained = allocator.rotor_speed_sq(thrust, np.array(torque))
    assert unconstrained.max() > box[1] or unconstrained.min() < box[0]
    u_w = desaturation.allocate(thrust, torque)
    assert_in_box(u_w, box)
    achieved = produced(vehicle, u_w)
    np.testing.assert_allclose(achieved[:3], (thrust, *torque[:2]), rtol=1e-12, atol=1e-12)
    assert 0.0 < achieved[3] < torque[2]  # reduced, same sign
    # Largest: a rotor is at a limit, and a little more yaw leaves the box.
    scale = achieved[3] / torque[2]
    more = allocator.rotor_speed_sq(thrust, np.array((*torque[:2], (scale + 1e-6) * torque[2])))
    assert more.max() > box[1] or more.min() < box[0]


def test_feasible_wrench_is_returned_unchanged_by_the_yaw_step():
    vehicle, allocator, desaturation, box = fixed("quadrotor_ex4")
    thrust, torque = vehicle.weight, (0.05, -0.03, 0.01)
    u_w = desaturation.allocate(thrust, torque)
    np.testing.assert_allclose(u_w, allocator.rotor_speed_sq(thrust, np.array(torque)), rtol=1e-14)


def test_roll_pitch_beyond_reach_at_the_commanded_thrust_keeps_torque_and_moves_thrust():
    vehicle, allocator, desaturation, box = fixed("quadrotor_ex4")
    max_thrust = 4 * vehicle.c_f * box[1]
    thrust, torque = 0.98 * max_thrust, (3.0, 0.0, 0.5)  # roll needs headroom the thrust leaves no room for
    assert allocator.rotor_speed_sq(thrust, np.array((*torque[:2], 0.0))).max() > box[1]
    u_w = desaturation.allocate(thrust, torque)
    assert_in_box(u_w, box)
    achieved = produced(vehicle, u_w)
    np.testing.assert_allclose(achieved[1:3], torque[:2], rtol=1e-12, atol=1e-12)  # roll/pitch exact
    assert achieved[0] < thrust  # thrust gave way ...
    closer = allocator.rotor_speed_sq(achieved[0] + 1e-3, np.array((*torque[:2], 0.0)))
    assert closer.max() > box[1]  # ... by the least it had to
    assert abs(achieved[3]) < 1e-9  # and no yaw fits on top


def test_low_thrust_is_raised_to_make_room_for_roll_pitch_with_a_minimum_speed():
    vehicle, allocator, desaturation, box = fixed("quadrotor_ex4", speed_min=200.0)
    thrust, torque = 4 * vehicle.c_f * box[0] * 1.05, (0.0, 0.5, 0.0)  # near idle: pitch needs more thrust
    u_w = desaturation.allocate(thrust, torque)
    assert_in_box(u_w, box)
    achieved = produced(vehicle, u_w)
    np.testing.assert_allclose(achieved[1:3], torque[:2], rtol=1e-12, atol=1e-12)
    assert achieved[0] > thrust


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_hopeless_wrench_stays_within_limits_and_keeps_the_roll_pitch_direction(name):
    vehicle, allocator, desaturation, box = fixed(name)
    thrust, torque = 10 * vehicle.weight, (30.0, -40.0, 25.0)
    u_w = desaturation.allocate(thrust, torque)
    assert_in_box(u_w, box)
    achieved = produced(vehicle, u_w)
    assert 0.0 < achieved[1] < torque[0] and torque[1] < achieved[2] < 0.0
    assert achieved[1] / achieved[2] == pytest.approx(torque[0] / torque[1], rel=1e-9)  # direction kept


def test_tilting_infeasible_yaw_keeps_force_and_roll_pitch():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    static = static_tilting_allocation(vehicle)
    max_thrust = vehicle.c_f * vehicle.rotor_speed_max**2
    force, torque = np.array((2.0, -1.0, -1.5 * vehicle.weight)), np.array((0.3, -0.2, 40.0))
    u = TiltingActuation(vehicle).desaturated(force, torque)
    thrusts = np.hypot(u[0::2], u[1::2])
    assert thrusts.max() <= max_thrust * (1 + 1e-12)
    assert thrusts.max() == pytest.approx(max_thrust, rel=1e-9)  # yaw took all the room there was
    wrench = static @ u
    np.testing.assert_allclose(wrench[:5], np.concatenate((force, torque[:2])), rtol=1e-10, atol=1e-10)
    assert 0.0 < wrench[5] < torque[2]


def test_tilting_hopeless_force_is_scaled_within_the_discs():
    vehicle = load_vehicle("tilting_quadrotor_ex5")
    static = static_tilting_allocation(vehicle)
    max_thrust = vehicle.c_f * vehicle.rotor_speed_max**2
    u = TiltingActuation(vehicle).desaturated(np.array((0.0, 0.0, -200.0)), np.array((5.0, 0.0, 5.0)))
    assert np.hypot(u[0::2], u[1::2]).max() <= max_thrust * (1 + 1e-12)
    wrench = static @ u
    assert -200.0 < wrench[2] < 0.0 and abs(wrench[0]) < 1e-9 and abs(wrench[3]) < 1e-9  # force first, no room left


def test_saturation_report_counts_the_axes_that_gave_way():
    report = SaturationReport(4)
    report.record_shortfall(np.array((0.0, 0.0, 0.0, 0.0, 0.0, 0.2)))
    report.record_shortfall(np.array((0.0, 0.0, -0.5, 1e-15, 0.0, -0.4)))
    gave_way = report.as_dict()["gave_way"]
    assert gave_way["torque_z"] == {"steps": 2, "max_shortfall": 0.4}
    assert gave_way["force_z"] == {"steps": 1, "max_shortfall": 0.5}
    assert gave_way["torque_x"]["steps"] == 0 and 1e-15 < SHORTFALL_TOLERANCE


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_without_air_mode_the_thrust_is_kept_and_roll_pitch_scaled_to_fit(name):
    """step_disturbance's case: at hover thrust a roll/pitch torque beyond reach is scaled (same direction),
    the thrust stays exact where the air-mode step 3 raises it."""
    vehicle, allocator, desaturation, box = fixed(name)
    thrust, torque = vehicle.weight, (2.0, 12.0, 0.3)
    assert allocator.rotor_speed_sq(thrust, np.array(torque)).min() < box[0]
    u_w = desaturation.allocate_keeping_thrust(thrust, torque)
    assert_in_box(u_w, box)
    achieved = produced(vehicle, u_w)
    assert achieved[0] == pytest.approx(thrust, rel=1e-12)
    scale = achieved[2] / torque[1]
    assert 0.0 < scale < 1.0 and achieved[1] == pytest.approx(scale * torque[0], rel=1e-9)
    more = allocator.rotor_speed_sq(thrust, np.array((*(1.0 + 1e-6) * scale * np.array(torque[:2]), 0.0)))
    assert more.min() < box[0] or more.max() > box[1]  # the largest scale that fits
    assert produced(vehicle, desaturation.allocate(thrust, torque))[0] > thrust  # air mode: the thrust rises
    assert desaturation.allocate_keeping_thrust(10.0 * 4 * vehicle.c_f * box[1], torque) is None  # thrust alone out
