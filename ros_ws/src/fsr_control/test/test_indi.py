"""INDI (controller.type: indi): its filter, its configuration and its increment at one step."""

from __future__ import annotations

import numpy as np
import pytest

from fsr_control.allocation import FixedRotorAllocator
from fsr_control.config.controller_config import controller_config
from fsr_control.controllers.indi import DEFAULT_FILTER_HZ, designed_gains, filter_coefficients, indi_lag, pack_indi
from fsr_control.core import imu_bridge, laws
from fsr_control.core.indi_law import LowPass
from fsr_control.design.gain_design import design_gains
from fsr_control.flight_controller import FlightController
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError

INDI = ("controller.type=indi", "sensors.preset=ideal")


def indi_scenario(*overrides: str, name: str = "step_disturbance"):  # noqa: ANN201
    return load_scenario(name, [*INDI, *overrides])


def run_filter(coefficients: LowPass, samples: np.ndarray) -> np.ndarray:
    """(value, rate) after each sample, started at rest on the first (as the law's memory)."""
    phi, gamma = np.array(coefficients.phi), np.array(coefficients.gamma)
    state = np.array([samples[0], 0.0])
    out = [state.copy()]
    for u in samples[1:]:
        state = phi @ state + gamma * u
        out.append(state.copy())
    return np.array(out)


def test_the_filter_passes_a_constant_and_differentiates_a_ramp():
    coefficients = filter_coefficients(DEFAULT_FILTER_HZ, 0.001)
    phi, gamma = np.array(coefficients.phi), np.array(coefficients.gamma)
    np.testing.assert_allclose(phi @ (1.0, 0.0) + gamma, (1.0, 0.0), atol=1e-12)  # DC gain 1, at rest
    t = np.arange(0.0, 0.5, 0.001)
    ramp = run_filter(coefficients, 2.0 * t)
    assert (ramp[-1, 0] - ramp[-2, 0]) / 0.001 == pytest.approx(2.0, rel=1e-9)  # it follows a ramp
    # its rate at the samples, of a staircase input: the slope within 0.3 % at 30 Hz and 1 kHz (measured 0.9970)
    assert ramp[-1, 1] == pytest.approx(2.0, rel=5e-3)
    delay = 2.0 * (1.0 / np.sqrt(2.0)) / (2.0 * np.pi * DEFAULT_FILTER_HZ)  # the group delay 2 zeta / w_n
    assert ramp[-1, 0] == pytest.approx(2.0 * (t[-1] - delay), abs=2e-3 * 2.0)
    step = run_filter(coefficients, np.r_[0.0, np.ones(200)])
    assert step[:, 0].max() < 1.05  # Butterworth: 4 % overshoot


@pytest.mark.parametrize(("cutoff", "period"), [(0.0, 0.001), (500.0, 0.001), (30.0, 0.0)])
def test_the_filter_refuses_what_it_cannot_be(cutoff, period):
    with pytest.raises(ValueError, match="cutoff|Nyquist"):
        filter_coefficients(cutoff, period)


def test_configuration_defaults():
    """The gains designed for INDI's own lag without the integral, the default cutoff, rotor_state where the
    rotors lag, the estimate where odom is a measurement."""
    config = controller_config(indi_scenario())
    sim = simulation_config(indi_scenario())
    assert config.type == "indi" and config.filter_hz == DEFAULT_FILTER_HZ
    assert config.control_period == pytest.approx(0.001) and not config.rotor_state  # quadrotor_ex4: no lag
    assert not config.odometry_measured and config.odometry_delay_steps == 0  # the ideal preset: the true state
    expected = design_gains(sim.vehicle, lag=indi_lag(sim.vehicle)).wrench_gains()
    for name in ("k_p", "k_v", "k_r", "k_w"):
        np.testing.assert_array_equal(config.gains[name], expected[name])
    np.testing.assert_array_equal(config.gains["k_i"], np.zeros((3, 3)))
    np.testing.assert_array_equal(designed_gains(sim.vehicle)["k_p"], expected["k_p"])
    lagging = controller_config(indi_scenario("vehicle=hummingbird", "controller.filter_hz=20"))
    assert lagging.rotor_state and lagging.filter_hz == 20.0  # the Hummingbird's 5 ms motor
    # its 5 ms motor and the 30 Hz filter (13 ms, a quarter more: 16 ms), not the 30 ms motor and 15 ms of
    # odometry the geometric law's gains assume (45 ms): an attitude loop 2.8 times faster, 20.5 rad/s
    hummingbird = simulation_config(indi_scenario("vehicle=hummingbird")).vehicle
    assert indi_lag(hummingbird) == pytest.approx(1.25 * (0.005 + 0.0075 + 0.0005), abs=1e-4)
    assert design_gains(hummingbird, lag=indi_lag(hummingbird)).attitude == pytest.approx(
        2.8 * design_gains(hummingbird).attitude, rel=0.02)
    onboard = controller_config(indi_scenario("sensors.preset=onboard"))
    assert onboard.odometry_measured and onboard.odometry_delay_steps == 10


@pytest.mark.parametrize(
    ("overrides", "key", "reason"),
    [
        (("sensors.preset=mocap",), "controller.type", "needs the vehicle's IMU: set sensors.imu"),
        (("controller.compensation=estimate",), "controller.compensation", "use controller.compensation: none"),
        (("controller.filter_hz=500",), "controller.filter_hz", "below the Nyquist frequency"),
        (("controller.filter_hz=0",), "controller.filter_hz", "must be > 0"),
        (("controller.feedforward=measured",), "controller.feedforward", "only the geometric law has it"),
        (("actuation=wrench",), "controller.type", "needs 'actuation: rotors'"),
    ],
)
def test_invalid_indi_sections_are_refused(overrides, key, reason):
    with pytest.raises(ConfigError) as error:
        controller_config(indi_scenario(*overrides))
    assert error.value.key == key and reason in str(error.value)
    assert "step_disturbance" in str(error.value)


def test_indi_is_refused_for_a_fully_actuated_vehicle():
    with pytest.raises(ConfigError, match="controller.type: indi is for vehicles with thrust along -z_b"):
        controller_config(indi_scenario(name="ex5_voliro"))


def test_the_increment_meets_a_measured_force_at_once():
    """At rest and level, the rotors at hover and the IMU measuring an extra 1 N along x (an external force):
    the first step's increment is that force, and the commanded thrust axis cancels it (``-R_c e3`` along ``-f -
    m g e3``; the filter starts on its first sample)."""
    scenario = indi_scenario("vehicle=hummingbird")
    sim, config = simulation_config(scenario), controller_config(scenario)
    vehicle = sim.vehicle
    controller = FlightController(config, vehicle, sim.actuation, sim.initial.position, sim.initial.rotation)
    weight = vehicle.mass * 9.81
    hover = np.sqrt(FixedRotorAllocator(vehicle).rotor_speed_sq(weight, np.zeros(3)))
    force = np.array([1.0, 0.0, 0.0])
    imu = np.r_[0.0, 0.0, 0.0, force / vehicle.mass + (0.0, 0.0, -9.81)]  # m s = f_rotors + f_ext
    out = controller.command(0.0, sim.initial.position, np.eye(3), np.zeros(3), np.zeros(3), imu, hover,
                             np.zeros(vehicle.rotor_count))
    desired = -force - np.array([0.0, 0.0, weight])  # the rotors' force that cancels it (world)
    np.testing.assert_allclose(out.rotation_cmd @ (0.0, 0.0, -1.0), desired / np.linalg.norm(desired), atol=1e-12)
    # u_T is the projection on the current (level) body axis: the weight
    assert out.thrust == pytest.approx(weight, rel=1e-9)
    np.testing.assert_allclose(out.torque_desired[2], 0.0, atol=1e-12)


def test_the_node_answers_a_stamp_once_all_its_inputs_have_arrived():
    """odom, imu and rotor_state of one stamp in any order: one answer, with each input; late ones dropped."""
    from fsr_control.nodes.inputs import (
        IMU_INPUT,
        INITIAL_ROTOR_STATE,
        ODOM_INPUT,
        ROTOR_STATE_INPUT,
        StampedInputs,
    )

    inputs = StampedInputs(needs_imu=True, needs_rotor_state=True)
    assert inputs.kinds == (ODOM_INPUT, IMU_INPUT, ROTOR_STATE_INPUT)
    # t_0: its rotor_state comes only after the first command: answered with the rotors' initial state
    assert inputs.add(IMU_INPUT, 0, "imu 0") is None
    assert inputs.add(ODOM_INPUT, 0, "odom 0") == ("odom 0", "imu 0", INITIAL_ROTOR_STATE)
    assert inputs.add(ROTOR_STATE_INPUT, 0, "rotors 0") is None and inputs.dropped == 1
    assert inputs.add(IMU_INPUT, 1000, "imu 1") is None
    assert inputs.add(ODOM_INPUT, 2000, "odom 2") is None  # the next stamp's odom before this one completes
    assert inputs.add(ROTOR_STATE_INPUT, 1000, "rotors 1") is None
    assert inputs.add(ODOM_INPUT, 1000, "odom 1") == ("odom 1", "imu 1", "rotors 1")
    assert inputs.add(IMU_INPUT, 1000, "imu 1 again") is None and inputs.dropped == 2  # answered already
    assert inputs.add(ROTOR_STATE_INPUT, 2000, "rotors 2") is None
    assert inputs.add(IMU_INPUT, 2000, "imu 2") == ("odom 2", "imu 2", "rotors 2")
    only_imu = StampedInputs(needs_imu=True, needs_rotor_state=False)
    assert only_imu.add(ODOM_INPUT, 5, "odom") is None  # the first stamp waits for everything but rotor_state
    assert only_imu.add(IMU_INPUT, 5, "imu") == ("odom", "imu")


def test_the_estimate_bridges_the_odometry_delay_and_hold_with_the_imu():
    """A vehicle turning at a constant body rate under a constant world acceleration, its odom 10 steps late
    and held 10 steps, an exact IMU: the estimate of the current step is the true state (to the trapezoid's
    rounding), where odom is up to 19 steps behind it."""
    scenario = indi_scenario("vehicle=hummingbird")
    vehicle = simulation_config(scenario).vehicle
    period, delay, every = 0.001, 10, 10
    params = pack_indi(vehicle, designed_gains(vehicle), DEFAULT_FILTER_HZ, period, True, predict=True,
                       delay_steps=delay)
    memory = laws.new_law_memory().bridge[0]  # INDI keeps its estimate where the geometric law keeps its own
    rate, acceleration = np.array([0.8, -0.5, 0.3]), np.array([2.0, -1.0, 0.5])
    p0, v0 = np.array([1.0, 2.0, -3.0]), np.array([3.0, -1.0, 0.2])

    def truth(step: int) -> tuple:
        t = step * period
        angle = np.linalg.norm(rate * t)
        axis = rate / np.linalg.norm(rate)
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        rotation = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k
        return p0 + v0 * t + 0.5 * acceleration * t * t, v0 + acceleration * t, rotation

    estimate = getattr(imu_bridge.bridged_state, "py_func", imu_bridge.bridged_state)
    worst, lag = 0.0, 0.0
    for step in range(600):
        measured = truth(max((step // every) * every - delay, 0))  # the sensor stage: delayed, then held
        position, velocity, rotation = truth(step)
        imu = np.r_[rate, rotation.T @ (acceleration - (0.0, 0.0, 9.81))]
        rows = tuple(tuple(row) for row in measured[2])
        p, r, v = estimate(params.bridge, memory, tuple(measured[0]), rows, tuple(measured[1]), imu)
        if step > 200:
            worst = max(worst, np.linalg.norm(np.subtract(p, position)), np.linalg.norm(np.subtract(v, velocity)),
                        np.abs(np.subtract(r, rotation)).max())
            lag = max(lag, np.linalg.norm(measured[0] - position))
    assert lag > 0.05  # odom alone is up to 19 ms (6 cm) behind
    assert worst < 1e-6
