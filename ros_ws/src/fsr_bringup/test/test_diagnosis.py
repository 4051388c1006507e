"""A flight that diverged or saturated much gets a diagnosis: its first saturated step and axis, the share of
steps at a rotor limit and the causes fsr can name, each with the scenario key that changes it."""

from __future__ import annotations

from fsr_bringup import simulate
from fsr_bringup.analysis.diagnosis import likely_causes
from fsr_bringup.analysis.in_memory import recorded_flight_of_run
from fsr_bringup.analysis.summary import markdown_summary

NOISY = {"sensors.odometry": {"position_std": 0.0005, "attitude_std_deg": 0.05, "velocity_std": 0.001,
                              "angular_velocity_std": 0.003, "seed": 1}}
REPORT_ON_ROTORS = {"actuation": "rotors", "controller.profile": "report", **NOISY}


def test_the_reports_law_on_rotors_under_noise_is_diagnosed_with_its_causes_and_keys():
    run = simulate("ex4_geometric", set=REPORT_ON_ROTORS, duration=0.5)
    found = run.metrics()["diagnosis"]
    assert found is not None and found["rotor_limit_share"] > 0.05
    first = found["first_saturation"]
    assert first["step"] is not None and first["step"] < 50 and first["axis"] in ("torque_x", "torque_y", "torque_z")
    keys = [cause["key"] for cause in found["likely_causes"]]
    assert any(key.startswith("controller.acceleration_filter_hz") for key in keys), keys
    assert any(key.startswith("controller.gains.") for key in keys), keys
    text = markdown_summary(run.metrics())
    assert "**Diagnosis**" in text and "first saturated step" in text and "`controller.acceleration_filter_hz" in text


def test_a_filter_removes_the_feed_forward_cause_and_a_clean_flight_has_no_diagnosis():
    filtered = simulate("ex4_geometric", set={**REPORT_ON_ROTORS, "controller.acceleration_filter_hz": 2.0},
                        duration=0.05)
    assert not [c for c in likely_causes(recorded_flight_of_run(filtered)) if "feed-forward" in c["cause"]]
    clean = simulate("ex4_geometric", set={"actuation": "rotors"}, duration=0.5).metrics()
    assert clean["diagnosis"] is None and "Diagnosis" not in markdown_summary(clean)


def test_a_motor_lag_beside_a_fast_observer_is_named():
    run = simulate("ex4_geometric", set={"plant.rotor_time_constant": 0.05, "controller.compensation": "estimate",
                                         "estimator.enabled": True, "estimator.c0": 50.0}, duration=0.02)
    causes = likely_causes(recorded_flight_of_run(run))
    assert [c for c in causes if c["key"].startswith("estimator.c0")], causes
