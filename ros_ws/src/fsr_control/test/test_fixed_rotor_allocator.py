"""The pseudo-inverse allocation of fixed rotors (fsr_control.allocation.FixedRotorAllocator) against the rotors'
wrench (fsr_sim.model.rotors)."""

import numpy as np
import pytest

from fsr_control.allocation import FixedRotorAllocator
from fsr_sim.model.rotors import clamp_rotor_speeds, wrench_from_rotor_speed_sq
from fsr_sim.model.vehicle import load_vehicle


@pytest.mark.parametrize("name", ["octocopter", "quadrotor_ex4"])
def test_fixed_rotor_round_trip_wrench_speeds_wrench(name):
    v = load_vehicle(name)
    thrust, torque = 1.1 * v.weight, np.array((0.05, -0.03, 0.01))
    speeds, excess = clamp_rotor_speeds(v, FixedRotorAllocator(v).rotor_speed_sq(thrust, torque))
    assert not excess.any()
    wrench = wrench_from_rotor_speed_sq(v) @ (speeds**2)
    np.testing.assert_allclose(wrench, [0, 0, -thrust, *torque], atol=1e-10)


def test_fixed_allocator_refuses_tilting_vehicle():
    with pytest.raises(ValueError, match="fixed rotors"):
        FixedRotorAllocator(load_vehicle("tilting_quadrotor_ex5"))
