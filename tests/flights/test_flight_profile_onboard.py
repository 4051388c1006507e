"""The flight profile under an onboard sensor suite (``sensors.preset: onboard``: odometry at 100 Hz, 10 ms late
and noisy, the BMI088 IMU at 1 kHz): the geometric law flies on the IMU (the gyro's rates, the IMU-bridged
estimate of the state, gains designed without the odometry's delay), and the compensated estimate's rates stay
out of ``R_d``'s (numbers in docs/control.md, "The laws compared under real conditions")."""

from __future__ import annotations

import numpy as np

from fsr_bringup import simulate
from fsr_bringup.runner.in_process_flight import FlightRun

ONBOARD = {"sensors.preset": "onboard", "sensors.odometry.seed": 3, "sensors.imu.seed": 4}
DRYDEN = {"kind": "dryden", "wind_speed": 7.7, "altitude": 6.0, "seed": 5}  # light turbulence


def position_rms(run: FlightRun) -> float:
    return float(np.sqrt(np.mean(np.sum((run.position - run.reference_position) ** 2, axis=1))))


def test_the_figure8_flies_within_10_cm_on_onboard_sensors_in_turbulence():
    """The Hummingbird's figure-8 (6.4 m/s, its 5 ms motor) under onboard sensors and Dryden turbulence at
    7.7 m/s: 0.21 m RMS (median of 20 seeds, one lost) when the law flew on the late odometry with gains designed
    for its delay; on the IMU 0.05-0.07 m."""
    run = simulate("figure8_hummingbird", set={**ONBOARD, "disturbances": [DRYDEN]})
    assert run.end_reason == "finished", run.reason
    assert position_rms(run) < 0.1


def test_the_figure8_on_odometry_alone_keeps_the_law_of_before():
    """``controller.use_imu: false``: the law flies on ``odom`` with the gains designed for its delay, as before (the
    figure-8 with the true state: 0.168 m RMS)."""
    run = simulate("figure8_hummingbird", set={"sensors.preset": "ideal", "controller.use_imu": False})
    assert run.end_reason == "finished"
    assert abs(position_rms(run) - 0.168) < 0.002


def test_compensation_under_onboard_noise_keeps_control():
    """``step_disturbance`` with the compensated estimate (c0 = 10, r = 1) on onboard sensors: it lost control at
    2.7 s while the estimate's rates turned ``R_d``; from the reference's rates alone it rejects the step."""
    run = simulate("step_disturbance", set={**ONBOARD, "controller.compensation": "estimate",
                                            "estimator.enabled": True, "estimator.c0": 10.0, "estimator.r": 1})
    assert run.end_reason == "finished", run.reason
    assert position_rms(run) < 0.15
