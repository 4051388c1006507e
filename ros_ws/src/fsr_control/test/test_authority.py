"""The authority numbers (fsr_control.design.authority) against hand calculations from the vehicles' parameters.

Notation: hover squared speed ``u_h = m g / (n c_f)``, limits ``u_min = w_min^2``, ``u_max = w_max^2``, the room
for a differential ``d = min(u_max - u_h, u_h - u_min)``, arm length ``L``. Body FRD: a rotor at ``p`` pushing
along ``-z_b`` gives ``tau_x = -c_f p_y u``, ``tau_y = c_f p_x u`` and drag ``tau_z = k c_m u`` (docs/model.md §3.2).
"""

from dataclasses import replace

import numpy as np
import pytest

from fsr_control.design.authority import authority, force_directions, force_set, largest_along, rotor_inputs
from fsr_sim.core.rigid_body import GRAVITY
from fsr_sim.model.rotors import wrench_from_rotor_speed_sq
from fsr_sim.model.vehicle import load_vehicle

TORQUES = ("roll_torque", "pitch_torque", "yaw_torque")
ACCELERATIONS = ("roll_acceleration", "pitch_acceleration", "yaw_acceleration")


def quadrotor_variants():
    v = load_vehicle("quadrotor_ex4")
    return {
        "as built": v,
        "w_min binds": replace(v, rotor_speed_min=300.0),  # u_h - u_min < u_max - u_h
        "w_max binds": v.with_mass_properties(mass=4.0),  # u_max - u_h < u_h - u_min
    }


@pytest.mark.parametrize("variant", ["as built", "w_min binds", "w_max binds"])
def test_plus_quadrotor_against_the_hand_calculation(variant):
    # '+' layout: rotors 1, 3 on the x axis (k = -1), 2, 4 on the y axis (k = +1). Thrust m g shared equally;
    # yaw: pair (2, 4) at u_h + d, pair (1, 3) at u_h - d -> tau_z = 4 c_m d, the other rows unchanged (and the
    # 4 x 4 allocation is invertible, so this is the only way). Roll: u_4 = u_h + d, u_2 = u_h - d (u_1 = u_3 = u_h)
    # -> tau_x = c_f L (u_4 - u_2) = 2 c_f L d; pitch likewise with rotors 1 and 3.
    v = quadrotor_variants()[variant]
    np.testing.assert_allclose(v.positions, [[v.arm_length, 0, 0], [0, v.arm_length, 0], [-v.arm_length, 0, 0],
                                             [0, -v.arm_length, 0]], atol=1e-12)
    assert v.spins.tolist() == [-1, 1, -1, 1]
    u_h = v.mass * GRAVITY / (4 * v.c_f)
    d = min(v.rotor_speed_max**2 - u_h, u_h - v.rotor_speed_min**2)
    a = authority(v)
    assert a.margin == 1.0 and a.tilt_max is None and a.hover_thrust == pytest.approx(v.mass * GRAVITY)
    assert a.yaw_torque == pytest.approx(4 * v.c_m * d, rel=1e-7)
    assert a.roll_torque == pytest.approx(2 * v.c_f * v.arm_length * d, rel=1e-7)
    assert a.pitch_torque == pytest.approx(2 * v.c_f * v.arm_length * d, rel=1e-7)
    assert a.thrust_min == pytest.approx(4 * v.c_f * v.rotor_speed_min**2, abs=1e-9)
    assert a.thrust_max == pytest.approx(4 * v.c_f * v.rotor_speed_max**2, rel=1e-9)
    for torque, acceleration, k in zip(TORQUES, ACCELERATIONS, range(3), strict=True):
        assert getattr(a, acceleration) == pytest.approx(getattr(a, torque) / v.inertia[k, k], rel=1e-7)


def test_quadrotor_ex4_gives_the_issues_numbers():
    v = load_vehicle("quadrotor_ex4")
    assert v.c_m / v.c_f == pytest.approx(0.013, abs=2e-4)  # 1.3 cm
    a = authority(v)
    assert a.yaw_torque == pytest.approx(0.155, abs=1e-3)
    assert a.roll_torque == pytest.approx(2.65, abs=5e-3) and a.pitch_torque == pytest.approx(2.65, abs=5e-3)


@pytest.mark.parametrize("mass", [2.5, 1.0])
def test_octocopter_against_the_hand_calculation(mass):
    # Rotor i at theta_i = (i - 1) 45 deg, k_i = (-1)^i. Yaw: every CCW rotor at u_h + d, every CW at u_h - d
    # (each spin group is a symmetric square: no roll or pitch) -> tau_z = 8 c_m d. That is the bound even with
    # roll and pitch free: sum k_i u_i <= 8 d when sum u_i = 8 u_h, so it is the maximum.
    # Roll (u_min = 0): thrust and zero yaw make each spin group carry S = 4 u_h; tau_x = c_f L sum(-sin theta_i
    # u_i). CW group (rotors 1, 3, 5, 7; -sin = 0, -1, 0, 1): rotor 7 at min(u_max, S), the rest on rotors 1 and 5
    # equally (no pitch), rotor 3 off. CCW group (2, 4, 6, 8; -sin = -s, -s, s, s, s = sin 45 deg): rotors 6, 8
    # at S / 2 each (no pitch), 2, 4 off. tau_x = c_f L (min(u_max, S) + s S): the best of each group, pitch 0.
    v = load_vehicle("octocopter").with_mass_properties(mass=mass)
    angles = np.deg2rad(45.0 * np.arange(8))
    np.testing.assert_allclose(v.positions[:, :2], v.arm_length * np.column_stack((np.cos(angles), np.sin(angles))),
                               atol=1e-12)
    assert v.spins.tolist() == [(-1) ** i for i in range(1, 9)] and v.rotor_speed_min == 0.0
    u_h, u_max = v.mass * GRAVITY / (8 * v.c_f), v.rotor_speed_max**2
    d = min(u_max - u_h, u_h)
    group = 4 * u_h
    assert group <= 2 * u_max  # the CCW group's two rotors can carry it
    roll = v.c_f * v.arm_length * (min(u_max, group) + np.sin(np.pi / 4) * group)
    a = authority(v)
    assert a.yaw_torque == pytest.approx(8 * v.c_m * d, rel=1e-7)
    assert a.roll_torque == pytest.approx(roll, rel=1e-7) and a.pitch_torque == pytest.approx(roll, rel=1e-7)
    assert a.thrust_min == pytest.approx(0.0, abs=1e-9)
    assert a.thrust_max == pytest.approx(8 * v.c_f * u_max, rel=1e-9)
    for torque, acceleration, k in zip(TORQUES, ACCELERATIONS, range(3), strict=True):
        assert getattr(a, acceleration) == pytest.approx(getattr(a, torque) / v.inertia[k, k], rel=1e-7)
    assert a.tilt_max is None


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter", "tilting_quadrotor_ex5"])
def test_margin_scales_every_number_towards_hover(name):
    v = load_vehicle(name)
    full, kept = authority(v), authority(v, margin=0.7)
    assert kept.margin == 0.7
    for field in (*TORQUES, *ACCELERATIONS):
        assert getattr(kept, field) == pytest.approx(0.7 * getattr(full, field), rel=1e-12)
    weight = v.mass * GRAVITY
    assert kept.thrust_max == pytest.approx(weight + 0.7 * (full.thrust_max - weight), rel=1e-12)
    assert kept.thrust_min == pytest.approx(weight - 0.7 * (weight - full.thrust_min), rel=1e-12, abs=1e-12)
    assert (kept.tilt_max is None) == (full.tilt_max is None)
    if full.tilt_max is not None:
        assert kept.tilt_max == pytest.approx(0.7 * full.tilt_max, rel=1e-12)


@pytest.mark.parametrize("margin", [0.0, -0.5, 1.5, float("nan")])
def test_a_margin_outside_0_1_is_refused(margin):
    with pytest.raises(ValueError, match=r"margin: must be in \(0, 1\]"):
        authority(load_vehicle("quadrotor_ex4"), margin=margin)


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter", "tilting_quadrotor_ex5"])
def test_a_vehicle_too_heavy_to_hover_is_refused_with_its_weight_and_thrust(name):
    v = load_vehicle(name)
    heavy = v.with_mass_properties(mass=2.0 * v.rotor_count * v.c_f * v.rotor_speed_max**2 / GRAVITY)
    with pytest.raises(ValueError, match=rf"vehicle '{name}' cannot hover: its weight m g = .* N is outside"):
        authority(heavy)


def test_a_vehicle_whose_minimum_thrust_exceeds_its_weight_is_refused():
    v = replace(load_vehicle("quadrotor_ex4"), rotor_speed_min=500.0)  # 4 c_f 500^2 = 16.6 N > 11.8 N
    with pytest.raises(ValueError, match="cannot hover"):
        authority(v)


def test_the_tilting_quadrotor_gives_finite_numbers_and_a_hover_tilt():
    v = load_vehicle("tilting_quadrotor_ex5")
    a = authority(v)
    values = a.as_dict()
    assert all(np.isfinite(value) for value in values.values())
    assert 0.0 < a.tilt_max <= np.pi
    assert all(getattr(a, field) > 0.0 for field in (*TORQUES, *ACCELERATIONS))
    # All four rotors vertical at full speed: the polygon has a vertex at tilt 0, so this is exact.
    assert a.thrust_max == pytest.approx(4 * v.c_f * v.rotor_speed_max**2, rel=1e-9)
    assert a.thrust_min <= a.hover_thrust <= a.thrust_max


@pytest.mark.parametrize("changes", [{}, {"tilt_angle_max": np.deg2rad(30.0)}, {"rotor_speed_min": 200.0},
                                     {"tilt_angle_max": np.deg2rad(120.0), "rotor_speed_min": 150.0}])
def test_tilting_solutions_are_rotor_commands_within_the_limits(changes):
    # The LP's inputs for the tilting quadrotor (an inner approximation): every optimum, turned into rotor speeds
    # and tilts by eq. 5, respects w_min, w_max and the servo limit and produces the wrench the LP claims.
    v = replace(load_vehicle("tilting_quadrotor_ex5"), **changes)
    inputs = rotor_inputs(v)
    hover = np.array((0.0, 0.0, -v.mass * GRAVITY, 0.0, 0.0, 0.0))
    for k in range(6):
        for sign in (1.0, -1.0):
            base = np.zeros(6) if k == 2 else hover
            value, x = largest_along(inputs, base, sign * np.eye(6)[k])
            speed_sq, tilt = inputs.rotor_commands(x)
            assert np.all(speed_sq >= v.rotor_speed_min**2 * (1 - 1e-7) - 1e-6)
            assert np.all(speed_sq <= v.rotor_speed_max**2 * (1 + 1e-7))
            spinning = speed_sq > 1e-6 * v.rotor_speed_max**2  # a stopped rotor's tilt is arbitrary
            assert np.all(np.abs(tilt[spinning]) <= v.tilt_angle_max + 1e-7)
            wrench = wrench_from_rotor_speed_sq(v, tilt) @ speed_sq
            np.testing.assert_allclose(wrench, base + sign * value * np.eye(6)[k], atol=1e-6)
    a = authority(v)
    assert 0.0 < a.tilt_max <= np.pi and np.isfinite(a.yaw_torque)


def test_a_narrower_servo_range_gives_less_hover_tilt():
    v = load_vehicle("tilting_quadrotor_ex5")
    narrow = authority(replace(v, tilt_angle_max=np.deg2rad(30.0)))
    assert narrow.tilt_max < authority(v).tilt_max


def test_fixed_rotor_solutions_are_within_the_speed_limits():
    v = load_vehicle("octocopter")
    inputs = rotor_inputs(v)
    hover = np.array((0.0, 0.0, -v.mass * GRAVITY, 0.0, 0.0, 0.0))
    value, x = largest_along(inputs, hover, np.eye(6)[3])
    speed_sq, tilt = inputs.rotor_commands(x)
    assert tilt is None and np.all(speed_sq >= -1e-6) and np.all(speed_sq <= v.rotor_speed_max**2 * (1 + 1e-9))
    np.testing.assert_allclose(wrench_from_rotor_speed_sq(v) @ speed_sq, hover + value * np.eye(6)[3], atol=1e-6)


def test_the_force_set_of_the_tilting_quadrotor_against_the_hand_calculation():
    # Along -z_b all four rotors vertical at full speed (a direction of the set: exact); along x_b only rotors 2
    # and 4 (on the y arm) push sideways, tilted +-90 deg, so at most 2 c_f w_max^2 - a little less, as zero
    # tau_x needs them to share a small vertical part against their drag torque; likewise along y_b.
    v = load_vehicle("tilting_quadrotor_ex5")
    forces = force_set(v)
    rotor = v.c_f * v.rotor_speed_max**2
    assert forces.reach(np.array([[0.0, 0.0, -1.0]]))[0] == pytest.approx(4.0 * rotor, rel=1e-9)
    for axis in np.vstack((np.eye(2, 3), -np.eye(2, 3))):
        assert 0.99 * 2.0 * rotor <= forces.reach(axis)[0] <= 2.0 * rotor
    # supporting planes: hover is inside, with the margin too; a force beyond the support along -z is not
    hover = np.array([[0.0, 0.0, -v.weight]])
    assert forces.contains(hover)[0] and forces.contains(hover, margin=0.1)[0]
    kept = forces.reach(np.array([[0.0, 0.0, -1.0]]), margin=0.7)[0]
    assert kept == pytest.approx(authority(v, margin=0.7).thrust_max, rel=1e-9)  # shrunk towards hover alike
    assert not forces.contains(np.array([[0.0, 0.0, -1.01 * 4.0 * rotor]]))[0]
    directions = force_directions()
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, rtol=1e-12)
    with pytest.raises(ValueError, match="not fully actuated"):
        force_set(load_vehicle("quadrotor_ex4"))
