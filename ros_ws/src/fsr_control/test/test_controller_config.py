from pathlib import Path

import numpy as np
import pytest
import yaml

from fsr_control.config import controller_config
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import ConfigError

SCENARIOS = Path(__file__).parent / "scenarios"


def scenario_with(tmp_path, base="ex4_wrench.yaml", **changes):
    data = yaml.safe_load((SCENARIOS / base).read_text())
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return load_scenario(path)


def test_test_scenarios_are_valid():
    ex4 = controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml"))
    assert ex4.type == "geometric"
    np.testing.assert_array_equal(ex4.gains["k_p"], np.diag((20.0, 20.0, 100.0)))
    assert len(ex4.waypoints) == 1 and ex4.waypoints[0].hold == 10.0
    ex5 = controller_config(load_scenario(SCENARIOS / "ex5_voliro.yaml"))
    assert ex5.type == "voliro" and ex5.angular_feedforward == "consistent"
    assert ex5.secondary_objective.type == "none"
    np.testing.assert_array_equal(ex5.gains["k_w"], np.diag((10.0, 10.0, 50.0)))


def test_type_defaults_by_vehicle_and_gains_default_to_the_profile(tmp_path):
    """No profile: ``flight``, the gains designed for the vehicle and the reference's feed-forward; ``report``:
    the report's gains (no integral) and the measured acceleration's."""
    from fsr_control.design.gain_design import design_gains
    from fsr_sim.model.vehicle import load_vehicle

    config = controller_config(scenario_with(tmp_path, controller={}))
    assert config.type == "geometric" and config.profile == "flight" and config.feedforward == "reference"
    designed = design_gains(load_vehicle("quadrotor_ex4")).wrench_gains()
    for name, gain in designed.items():
        np.testing.assert_array_equal(config.gains[name], gain)
    config = controller_config(scenario_with(tmp_path, controller={"profile": "report"}))
    assert config.feedforward == "measured"
    np.testing.assert_array_equal(config.gains["k_w"], np.diag((10.0, 10.0, 100.0)))
    np.testing.assert_array_equal(config.gains["k_i"], np.zeros((3, 3)))
    config = controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller=None))
    assert config.type == "voliro" and config.profile == "flight"
    np.testing.assert_array_equal(config.gains["k_d"],
                                  design_gains(load_vehicle("tilting_quadrotor_ex5")).acceleration_gains()["k_d"])


def test_explicit_gains_and_feedforward_override_either_profile(tmp_path):
    config = controller_config(scenario_with(tmp_path, controller={"profile": "report", "feedforward": "reference",
                                                                   "gains": {"k_i": [1, 1, 2]}}))
    assert config.feedforward == "reference"
    np.testing.assert_array_equal(config.gains["k_i"], np.diag((1.0, 1.0, 2.0)))
    np.testing.assert_array_equal(config.gains["k_p"], np.diag((20.0, 20.0, 100.0)))  # the rest: the report's
    config = controller_config(scenario_with(tmp_path, controller={"feedforward": "measured", "integral_limit": 1.5,
                                                                   "gains": {"k_p": [5, 5, 20], "k_i": [0, 0, 0]}}))
    assert config.feedforward == "measured" and config.integral_limit == 1.5
    np.testing.assert_array_equal(config.gains["k_p"], np.diag((5.0, 5.0, 20.0)))
    np.testing.assert_array_equal(config.gains["k_i"], np.zeros((3, 3)))


def test_full_matrix_gain_accepted(tmp_path):
    gain = [[20, 1, 0], [1, 20, 0], [0, 0, 100]]
    config = controller_config(scenario_with(tmp_path, controller={"gains": {"k_p": gain}}))
    np.testing.assert_array_equal(config.gains["k_p"], gain)


@pytest.mark.parametrize(
    ("controller", "key", "reason"),
    [
        ({"gains": {"k_p": [20, -1, 100]}}, "controller.gains.k_p", "positive definite"),
        ({"gains": {"k_p": [20, 100]}}, "controller.gains.k_p", "3 numbers"),
        ({"gains": {"k_p": [[1, 2, 0], [0, 1, 0], [0, 0, 1]]}}, "controller.gains.k_p", "symmetric"),
        ({"gains": {"k_P": [1, 1, 1]}}, "controller.gains.k_P", "did you mean 'k_p'"),
        ({"gains": {"k_d": [1, 1, 1]}}, "controller.gains.k_d", "unknown key"),  # voliro's name
        ({"gains": {"k_i": [1, -1, 1]}}, "controller.gains.k_i", "positive semi-definite"),
        ({"gains": {"k_r": [0, 1, 1]}}, "controller.gains.k_r", "positive definite"),  # only k_i may be 0
        ({"profile": "fast"}, "controller.profile", "must be one of flight, report"),
        ({"feedforward": "model"}, "controller.feedforward", "must be one of measured, reference"),
        ({"integral_limit": 0}, "controller.integral_limit", "must be > 0"),
        ({"aerodynamics": "measured"}, "controller.aerodynamics", "must be one of model, none"),
        ({"type": "voliro"}, "controller.type", "needs a fully actuated vehicle"),
        ({"type": "pid"}, "controller.type", "must be one of"),
        ({"angular_feedforward": "report"}, "controller.angular_feedforward", "unknown key"),
        ({"gain": {}}, "controller.gain", "did you mean 'gains'"),
    ],
)
def test_invalid_controller_sections_are_refused(tmp_path, controller, key, reason):
    with pytest.raises(ConfigError) as error:
        controller_config(scenario_with(tmp_path, controller=controller))
    assert error.value.key == key
    assert reason in str(error.value)
    assert "scenario.yaml" in str(error.value)


@pytest.mark.parametrize(("key", "laws"), [("feedforward", "geometric law"),
                                           ("integral_limit", "geometric and indi laws"), ("filter_hz", "indi law")])
def test_the_geometric_laws_keys_are_refused_for_voliro(tmp_path, key, laws):
    with pytest.raises(ConfigError, match=f"controller.{key}: only the {laws} ha(s|ve) it, not voliro"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller={key: "reference"}))


def test_the_aerodynamic_model_defaults_by_profile_and_is_for_fixed_rotors(tmp_path):
    assert controller_config(scenario_with(tmp_path, controller={})).aerodynamics == "model"
    assert controller_config(scenario_with(tmp_path, controller={"profile": "report"})).aerodynamics == "none"
    assert controller_config(scenario_with(tmp_path, controller={"profile": "report", "aerodynamics": "model"})
                             ).aerodynamics == "model"
    assert controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller=None)).aerodynamics == "none"
    with pytest.raises(ConfigError, match="controller.aerodynamics: 'model' is for fixed rotors; "
                                          "'tilting_quadrotor_ex5' tilts its rotors"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller={"aerodynamics": "model"}))
    indi = ["controller.type=indi", "sensors.preset=onboard"]  # INDI measures what the model would predict
    assert controller_config(load_scenario("figure8_hummingbird", indi)).aerodynamics == "none"
    with pytest.raises(ConfigError, match="controller.aerodynamics: indi measures the aerodynamics"):
        controller_config(load_scenario("figure8_hummingbird", [*indi, "controller.aerodynamics=model"]))


def test_geometric_refused_for_tilting_vehicle_and_voliro_for_wrench_actuation(tmp_path):
    with pytest.raises(ConfigError, match="tilting"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller={"type": "geometric"}))
    with pytest.raises(ConfigError, match="actuation: rotors"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", actuation="wrench"))


@pytest.mark.parametrize(
    ("waypoint", "key", "reason"),
    [
        ({"position": [0, 0, -1], "attitude_rpy_deg": [10, 0, 0], "duration": 5}, "attitude_rpy_deg", "roll and pitch"),
        ({"position": [0, 0, -1], "duration": 0}, "duration", "> 0"),
        ({"position": [0, 0, -1], "duration": 5, "hold": -1}, "hold", ">= 0"),
        ({"position": [0, 0], "duration": 5}, "position", "shape"),
        ({"position": [0, 0, -1], "duraton": 5}, "duration", "is required"),
        ({"position": [0, 0, -1], "duration": 5, "hodl": 1}, "hodl", "did you mean 'hold'"),
    ],
)
def test_invalid_waypoints_are_refused(tmp_path, waypoint, key, reason):
    with pytest.raises(ConfigError) as error:
        controller_config(scenario_with(tmp_path, trajectory={"waypoints": [waypoint]}))
    assert error.value.key == f"trajectory.waypoints.0.{key}"
    assert reason in str(error.value)


def test_roll_pitch_waypoints_accepted_for_tilting_vehicle_and_voliro_options(tmp_path):
    scenario = scenario_with(
        tmp_path, "ex5_voliro.yaml",
        controller={"angular_feedforward": "report", "secondary_objective": {"type": "min_peak_speed", "exponent": 6}},
    )
    config = controller_config(scenario)
    assert config.angular_feedforward == "report"
    assert config.secondary_objective.type == "min_peak_speed" and config.secondary_objective.exponent == 6
    with pytest.raises(ConfigError, match="even"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml",
                                        controller={"secondary_objective": {"type": "min_peak_speed", "exponent": 5}}))
    with pytest.raises(ConfigError, match="must be one of"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller={"secondary_objective": {"type": "x"}}))


def test_authority_margin_defaults_to_0_7_and_is_checked(tmp_path):
    assert controller_config(load_scenario(SCENARIOS / "ex4_wrench.yaml")).authority_margin == 0.7
    trajectory = yaml.safe_load((SCENARIOS / "ex4_wrench.yaml").read_text())["trajectory"]
    config = controller_config(scenario_with(tmp_path, trajectory={**trajectory, "authority_margin": 1}))
    assert config.authority_margin == 1.0
    for value, reason in ((0, "must be in (0, 1]"), (-0.2, "must be in (0, 1]"), (1.5, "must be in (0, 1]"),
                          ("most", "must be a number")):
        with pytest.raises(ConfigError) as error:
            controller_config(scenario_with(tmp_path, trajectory={**trajectory, "authority_margin": value}))
        assert error.value.key == "trajectory.authority_margin"
        assert reason in str(error.value) and "scenario.yaml" in str(error.value)


def test_the_flight_profile_flies_on_the_imu_where_the_vehicle_has_one(tmp_path):
    """``controller.use_imu`` defaults to the flight profile on a vehicle with an IMU; its designed gains then have no
    odometry delay to survive (the motor's 30 ms and half an IMU sample: 30.5 ms); the report's profile, a vehicle
    without an IMU or ``use_imu: false`` keep the law on ``odom``; the compensated estimate's rates reach ``R_d``
    only with the measured feed-forward."""
    from fsr_control.design.gain_design import design_gains, design_lag
    from fsr_sim.model.vehicle import load_vehicle

    octocopter = load_vehicle("octocopter")
    assert design_lag(octocopter, imu=True) == pytest.approx(0.0305)
    onboard = {"preset": "onboard"}
    config = controller_config(scenario_with(tmp_path, "ex4_wrench.yaml", vehicle="octocopter", sensors=onboard,
                                             controller={}))
    assert config.use_imu and config.odometry_measured
    designed = design_gains(octocopter, imu=True).wrench_gains()
    np.testing.assert_array_equal(designed["k_r"], design_gains(octocopter, lag=0.0305).wrench_gains()["k_r"])
    np.testing.assert_array_equal(config.gains["k_r"], designed["k_r"])
    assert design_gains(octocopter, lag=0.0305).attitude > design_gains(octocopter).attitude
    for sensors, controller in (({"preset": "mocap"}, {}), (onboard, {"profile": "report"}),
                                (onboard, {"use_imu": False}), (None, {})):
        config = controller_config(scenario_with(tmp_path, "ex4_wrench.yaml", vehicle="octocopter", sensors=sensors,
                                                 controller=controller))
        assert not config.use_imu
        if controller.get("profile") != "report":
            np.testing.assert_array_equal(config.gains["k_r"], design_gains(octocopter).wrench_gains()["k_r"])
    with pytest.raises(ConfigError, match=r"controller\.use_imu: the vehicle has no IMU"):
        controller_config(scenario_with(tmp_path, controller={"use_imu": True}))
    with pytest.raises(ConfigError, match=r"controller\.use_imu: only the geometric law has it, not voliro"):
        controller_config(scenario_with(tmp_path, "ex5_voliro.yaml", controller={"use_imu": True}))
    estimator = {"enabled": True}
    flight = controller_config(scenario_with(tmp_path, estimator=estimator, controller={"compensation": "estimate"}))
    report = controller_config(scenario_with(tmp_path, estimator=estimator,
                                             controller={"compensation": "estimate", "profile": "report"}))
    assert not flight.compensation.rates and report.compensation.rates
