"""INDI (``controller.type: indi``) in whole in-process flights, with an ideal IMU and no estimator: it holds a
hover through a step of external force and torque and tracks paths at speed on the Hummingbird.

Measured (the Hummingbird, its 5 ms motor measured on ``rotor_state``, INDI's gains designed for it): a 1.1 N
force and 0.015 N m torque step (5..10 s) peaks at 0.020 m and is held within 1e-8 m at its end (the geometric
law of the flight profile on the same IMU, whose integral meets it: 0.200 m peak, 0.007 m at 10 s); a 3 m/s
circle of 1.5 m is tracked within 0.0046 m RMS (0.080 m for the geometric law without its aerodynamics model,
0.009 m with it), a lissajous at up to 3.8 m/s within 0.0040 m RMS (0.053 m, 0.008 m).
"""

from __future__ import annotations

import numpy as np

from fsr_bringup import simulate
from fsr_bringup.runner.in_process_flight import FlightRun, fly_in_process
from fsr_sim.config.scenario import load_scenario

INDI = ("controller.type=indi", "sensors.preset=ideal", "estimator.enabled=false")
STEP = ("vehicle=hummingbird", "disturbances=[{kind: step, frame: world, start: 5.0, end: 10.0, "
        "force: [1.0, 0.5, 0.0], torque: [0.01, -0.01, 0.005]}]")


def position_error(run: FlightRun) -> np.ndarray:
    return np.linalg.norm(run.position - run.reference_position, axis=1)


def window(run: FlightRun, start: float, end: float) -> np.ndarray:
    return (run.time >= start) & (run.time <= end)


def test_indi_holds_hover_through_a_force_and_torque_step_without_an_estimator():
    run = fly_in_process(load_scenario("step_disturbance", [*INDI, *STEP]))
    assert run.end_reason == "finished" and run.estimate_force_body is None
    errors = position_error(run)
    assert errors[window(run, 9.5, 10.0)].max() < 0.01  # the step at full strength: held
    assert errors[window(run, 14.5, 15.0)].max() < 0.01  # and after it
    assert errors.max() < 0.03
    geometric = fly_in_process(load_scenario("step_disturbance", ["sensors.preset=ideal", *STEP]))
    assert errors.max() * 3.0 < position_error(geometric).max()


def path_scenario(controller: dict, trajectory: dict, start: list[float]) -> dict:
    return {"name": "indi_path", "vehicle": "hummingbird", "duration": 12.0, "actuation": "rotors",
            "initial_state": {"position": start}, "trajectory": trajectory, "controller": controller,
            "estimator": {"enabled": False}, "sensors": {"preset": "ideal"},
            "environment": {"ground": {"effect": False}}}


def rms_error(run: FlightRun) -> float:
    return float(np.sqrt(np.mean(position_error(run) ** 2)))


def test_indi_tracks_a_circle_and_a_lissajous_on_the_hummingbird():
    circle = {"kind": "circle", "centre": [0, 0, -2], "radius": 1.5, "speed": 3.0, "laps": 2, "yaw": "velocity"}
    lissajous = {"kind": "lissajous", "centre": [0, 0, -2], "amplitude": [1.5, 1.0, 0.3],
                 "frequency": [0.25, 0.5, 0.25], "laps": 1}
    for trajectory, start, limit in ((circle, [1.5, 0.0, -2.0], 0.006), (lissajous, [0.0, 0.0, -2.0], 0.006)):
        # INDI measures the air the geometric law knows nothing of, and does better than its model of it
        indi, blind, modelled = (simulate(path_scenario(controller, trajectory, start)) for controller in (
            {"type": "indi"}, {"type": "geometric", "aerodynamics": "none"}, {"type": "geometric"}))
        assert indi.end_reason == "finished" and not indi.ended_mid_path and indi.saturation["count"] == 0
        assert rms_error(indi) < limit
        assert rms_error(indi) * 4.0 < rms_error(blind) and rms_error(indi) < rms_error(modelled)
