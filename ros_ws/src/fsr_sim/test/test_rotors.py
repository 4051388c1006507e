import numpy as np
import pytest

from fsr_sim.model.rotors import (
    SaturationReport,
    clamp_rotor_speeds,
    octocopter_allocation_4x8,
    rotor_commands_from_static,
    static_from_rotor_commands,
    static_tilting_allocation,
    wrench_from_rotor_speed_sq,
)
from fsr_sim.model.vehicle import load_vehicle

VEHICLES = ["octocopter", "quadrotor_ex4", "tilting_quadrotor_ex5"]


def test_octocopter_gq_equals_the_report_entry_by_entry():
    v = load_vehicle("octocopter")
    cf, cm, lc, h = v.c_f, v.c_m, v.arm_length * v.c_f, np.sqrt(2.0) / 2.0
    report = np.array(
        [
            [-cf] * 8,
            [0, -lc * h, -lc, -lc * h, 0, lc * h, lc, lc * h],
            [lc, lc * h, 0, -lc * h, -lc, -lc * h, 0, lc * h],
            [-cm, cm, -cm, cm, -cm, cm, -cm, cm],
        ]
    )
    np.testing.assert_allclose(octocopter_allocation_4x8(v), report, rtol=1e-12, atol=1e-22)
    # Exact zeros where the report has zeros.
    assert np.all(octocopter_allocation_4x8(v)[report == 0] == 0.0)


def test_force_rows_of_a_coplanar_vehicle_are_zero():
    allocation = wrench_from_rotor_speed_sq(load_vehicle("octocopter"))
    assert np.all(allocation[:2] == 0.0)


def test_tilting_round_trip_wrench_static_rotor_commands_wrench():
    v = load_vehicle("tilting_quadrotor_ex5")
    static = static_tilting_allocation(v)
    wrench = np.array((1.0, -2.0, -14.0, 0.1, -0.2, 0.05))
    u = np.linalg.pinv(static) @ wrench
    speed_sq, tilt = rotor_commands_from_static(v, u)
    assert np.all(speed_sq >= 0.0)
    np.testing.assert_allclose(wrench_from_rotor_speed_sq(v, tilt) @ speed_sq, wrench, atol=1e-10)
    np.testing.assert_allclose(static_from_rotor_commands(v, speed_sq, tilt), u, atol=1e-12)


def test_static_allocation_has_full_rank_for_the_tilting_quadrotor():
    assert np.linalg.matrix_rank(static_tilting_allocation(load_vehicle("tilting_quadrotor_ex5"))) == 6


def test_static_allocation_uses_the_geometry_derived_yaw_terms():
    # Rotor 2 sits on +y with its tilt axis along +y: its lateral thrust (along e3 x e_y = -e_x) at lever
    # arm p = [0, l, 0] gives tau_z = +l per newton (the course's hand-written matrix has -l).
    v = load_vehicle("tilting_quadrotor_ex5")
    static = static_tilting_allocation(v)
    assert static[5, 3] == pytest.approx(v.arm_length)
    assert static[0, 3] == pytest.approx(-1.0)


def test_clamp_and_saturation_report_name_the_worst_rotor():
    v = load_vehicle("quadrotor_ex4")
    speeds, excess = clamp_rotor_speeds(v, np.array((100.0**2, 1200.0**2, -(50.0**2), 500.0**2)))
    np.testing.assert_allclose(speeds, [100.0, 1000.0, 0.0, 500.0])
    np.testing.assert_allclose(excess, [0.0, 200.0, 50.0, 0.0])
    report = SaturationReport()
    assert report.record(0.25, excess)
    assert not report.record(0.5, np.zeros(4))
    assert (report.count, report.first_time, report.worst_rotor) == (1, 0.25, 2)
    assert report.as_dict()["per_rotor"] == {"2": 1, "3": 1}
