"""The agile scenarios as shipped (ideal sensors, the flight profile): what their descriptions promise, and the
controller's model of the vehicle's aerodynamics (``controller.aerodynamics: model``) cancelling them."""

from __future__ import annotations

import numpy as np
import yaml

from fsr_bringup import simulate
from fsr_sim.config.scenario import load_scenario
from fsr_sim.config.validation import resolve_config_path

G = 9.81


def position_rms(run: object) -> float:
    return float(np.sqrt(np.mean(np.sum((run.position - run.reference_position) ** 2, axis=1))))


def test_figure8_hummingbird_is_a_figure8_at_5_m_s_and_1_g():
    run = simulate("figure8_hummingbird")
    assert run.end_reason == "finished" and not run.ended_mid_path
    assert np.linalg.norm(run.reference_velocity, axis=1).max() >= 5.0
    assert np.linalg.norm(run.reference_acceleration, axis=1).max() >= G
    x, y = run.reference_position[:, 0], run.reference_position[:, 1]
    assert np.ptp(x) > 5.7 and np.ptp(y) > 2.8  # 5.8 x 2.9 m
    assert position_rms(run) < 0.2


def test_race_hummingbird_passes_its_gates_at_8_m_s():
    scenario = load_scenario("race_hummingbird")
    gates = [point["position"] for point in scenario.data["trajectory"]["waypoints"]]
    assert len(gates) >= 6 and len({z for _, _, z in gates}) > 1  # 3D
    run = simulate(scenario)
    assert run.end_reason == "finished" and not run.ended_mid_path
    assert np.linalg.norm(run.velocity, axis=1).max() >= 8.0
    for gate in gates:  # the flown path passes within 0.5 m of every gate
        assert np.linalg.norm(run.position - gate, axis=1).min() < 0.5, gate


def test_hover_crazyflie_holds_its_point():
    run = simulate("hover_crazyflie")
    assert run.end_reason == "finished"
    assert np.linalg.norm(run.position[-1] - (0.5, 0.0, -1.0)) < 0.005
    assert position_rms(run) < 0.02


def test_the_aerodynamic_model_cancels_the_drag_it_knows(tmp_path):
    """The hummingbird with parasitic drag only and an instant motor: the figure-8 tracked ten times better with
    the model's drag cancelled along the reference than without."""
    vehicle = yaml.safe_load(resolve_config_path("hummingbird", "vehicles").read_text())
    vehicle.update(name="hummingbird_drag", rotor_time_constant=0.0, rotor_drag_coefficient=0.0,
                   induced_inflow_coefficient=0.0, translational_lift_coefficient=0.0)
    (tmp_path / "drag.yaml").write_text(yaml.safe_dump(vehicle))
    scenario = yaml.safe_load(resolve_config_path("figure8_hummingbird", "scenarios").read_text())
    scenario.update(vehicle=str(tmp_path / "drag.yaml"), duration=10.0)
    model, none = (position_rms(simulate(scenario, set={"controller.aerodynamics": mode}))
                   for mode in ("model", "none"))
    assert model < 0.005 and model < none / 10, (model, none)
