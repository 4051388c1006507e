"""Gains designed from the vehicle (fsr_control.design.gain_design): each loop's bandwidth follows the vehicle's
authority, its motor and its layout as the rules say, and the gains follow the bandwidths."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

from fsr_bringup.cli.vehicle_cli import main
from fsr_control.design import gain_design
from fsr_control.design.authority import authority
from fsr_control.design.authority_cache import model_force_set
from fsr_control.design.gain_design import design_gains
from fsr_sim.model.vehicle import load_vehicle

QUAD = load_vehicle("quadrotor_ex4")


def test_the_quadrotors_attitude_follows_its_authority_and_its_position_the_attitude():
    design, alpha = design_gains(QUAD), authority(QUAD).roll_acceleration  # 2.13 rad/s^2 on 1.24 kg m^2
    share, error = gain_design.AUTHORITY_SHARE, gain_design.ATTITUDE_ERROR
    assert design.limits == {"attitude": "authority", "yaw": "authority", "horizontal": "cascade",
                             "vertical": "authority"}
    assert design.attitude == pytest.approx(math.sqrt(share * alpha / error))  # 5.52 rad/s
    assert design.horizontal == pytest.approx(design.attitude / gain_design.CASCADE_RATIO)
    assert design.attitude < design.lag_bandwidth
    gains = design.wrench_gains()
    assert gains["k_r"][0, 0] * error == pytest.approx(share * authority(QUAD).roll_torque)  # half the torque
    assert gains["k_p"][0, 0] == pytest.approx(QUAD.mass * design.horizontal ** 2)
    assert gains["k_v"][2, 2] == pytest.approx(2 * gain_design.DAMPING * QUAD.mass * design.vertical)
    assert gains["k_i"][0, 0] == pytest.approx(gains["k_p"][0, 0] * design.horizontal / gain_design.INTEGRAL_RATIO)
    assert design.integral_limit == pytest.approx(0.25 * QUAD.weight)


def test_more_inertia_slows_the_attitude_loop_and_keeps_its_torque():
    """Twice the inertia with the same rotors: half the angular acceleration, so the authority-bound attitude
    loop is sqrt(2) slower and asks for the same torque per radian (the position loop follows it down)."""
    light, heavy = design_gains(QUAD), design_gains(replace(QUAD, inertia=2.0 * QUAD.inertia))
    assert heavy.attitude == pytest.approx(light.attitude / math.sqrt(2.0))
    assert heavy.horizontal == pytest.approx(light.horizontal / math.sqrt(2.0))
    np.testing.assert_allclose(heavy.wrench_gains()["k_r"], light.wrench_gains()["k_r"], rtol=1e-9)


def test_a_vehicle_with_authority_to_spare_is_bounded_by_the_lag_and_a_slower_motor_lowers_it():
    octocopter = load_vehicle("octocopter")  # 147 rad/s^2 of roll acceleration
    design = design_gains(octocopter)
    assert design.limits["attitude"] == "lag"
    assert design.lag == pytest.approx(0.03 + 0.01 + 0.005)
    assert design.attitude == pytest.approx(1.0 / (3.0 * 0.045))  # 7.4 rad/s
    slow = design_gains(replace(octocopter, rotor_time_constant=0.06))  # slower than the 30 ms designed for
    assert slow.lag == pytest.approx(0.075) and slow.attitude == pytest.approx(1.0 / (3.0 * 0.075))
    assert slow.horizontal < design.horizontal
    fast = design_gains(replace(octocopter, rotor_time_constant=0.005))  # faster: still designed for 30 ms
    assert fast.attitude == design.attitude


def test_a_heavier_vehicle_has_less_thrust_to_spare_and_a_slower_vertical_loop():
    heavy = replace(QUAD, mass=4.0)  # 66 N of thrust for 39 N of weight: 6.8 m/s^2 up (less than g down)
    up = (authority(heavy).thrust_max - heavy.weight) / heavy.mass
    design = design_gains(heavy)
    assert design.vertical == pytest.approx(math.sqrt(gain_design.AUTHORITY_SHARE * up / gain_design.POSITION_ERROR))
    assert design.vertical < design_gains(QUAD).vertical
    assert design.wrench_gains()["k_p"][2, 2] == pytest.approx(4.0 * design.vertical ** 2)


def test_a_fully_actuated_vehicle_moves_without_tilting_its_position_loop_is_not_a_cascade():
    tilting = load_vehicle("tilting_quadrotor_ex5")
    design = design_gains(tilting)
    assert design.limits["horizontal"] == "authority" and design.horizontal > design_gains(QUAD).horizontal
    lateral = gain_design.lateral_acceleration(tilting, model_force_set(tilting))
    assert design.horizontal == pytest.approx(math.sqrt(0.5 * lateral / gain_design.POSITION_ERROR))
    gains = design.acceleration_gains()
    assert gains["k_p"][0, 0] == pytest.approx(design.horizontal ** 2)
    assert gains["k_w"][2, 2] == pytest.approx(2 * gain_design.DAMPING * design.yaw)


@pytest.mark.parametrize("name", ["quadrotor_ex4", "octocopter"])
def test_the_designed_cascade_is_stable_where_the_reports_gains_are_not(name):
    """The lateral loop linearised at hover with the reference feed-forward (docs/control.md):
    ``I m s^4 + K_w m s^3 + K_R m s^2 + K_R K_v s + K_R K_p``: every root in the left half-plane with the
    designed gains; with the report's (K_R = K_w = 10, K_p = K_v = 20) a pair in the right one."""
    vehicle = load_vehicle(name)
    gains = design_gains(vehicle).wrench_gains()

    def roots(k_p: float, k_v: float, k_r: float, k_w: float) -> np.ndarray:
        m, inertia = vehicle.mass, vehicle.inertia[0, 0]
        return np.roots((inertia * m, k_w * m, k_r * m, k_r * k_v, k_r * k_p))

    assert np.all(roots(*(gains[k][0, 0] for k in ("k_p", "k_v", "k_r", "k_w"))).real < 0.0)
    assert np.any(roots(20.0, 20.0, 10.0, 10.0).real > 0.0)


def test_fsr_vehicle_prints_the_designed_gains(capsys):
    assert main(["quadrotor_ex4", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)["designed_gains"]
    assert data["limits"]["horizontal"] == "cascade"
    assert data["wrench_gains"]["k_p"][0][0] == pytest.approx(design_gains(QUAD).wrench_gains()["k_p"][0, 0])
    assert main(["quadrotor_ex4"]) == 0
    out = capsys.readouterr().out
    assert "Gains designed from the vehicle (`controller.profile: flight`" in out
    assert "| position x / y | 1.84 rad/s | attitude / 3 |" in out and "| k_r | [37.84, 37.84, 2.211] |" in out
