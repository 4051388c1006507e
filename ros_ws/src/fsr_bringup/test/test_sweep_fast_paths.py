"""The sweep's fast paths give the rows of the full path: a flight measured in the compiled loop (no per-step
arrays) has the row its arrays give, a flight set up from the sweep's packed scenario (only the swept values
packed anew) the row of a flight set up in full; what they cannot do falls back to the full path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fsr_bringup.runner.in_process_flight import prepare_flight
from fsr_bringup.sweeps.axes import flight_scenario
from fsr_bringup.sweeps.batch import TRUTH_COLUMNS, fly_one, packed_sweep
from fsr_bringup.sweeps.measured import loop_flight
from fsr_bringup.sweeps.metrics import METRIC_COLUMNS
from fsr_bringup.tuning.conditions import condition_values, seed_keys
from fsr_sim.config.scenario import load_scenario

TEXT_COLUMNS = ("end_reason", "end_detail", "gave_way")


def assert_rows_agree(got: dict, want: dict, rel: float = 1e-9) -> None:
    for column in METRIC_COLUMNS:
        if column in TEXT_COLUMNS:
            assert got[column] == want[column], column
        elif math.isnan(want[column]):
            assert math.isnan(got[column]), (column, got[column])
        else:
            assert got[column] == pytest.approx(want[column], rel=rel, abs=1e-12), column


@pytest.mark.parametrize(("scenario", "fixed", "values"), [
    ("ex4_geometric", {"duration": 1.5}, {"plant.mass": 1.3}),  # wrench actuation, estimator on
    ("step_disturbance", {"duration": 8.0, "disturbances.0.end": 6.0, "disturbances.0.force": [0.5, 0, 0]},
     {"plant.mass": 1.2}),  # settles after the step
    ("ex3_estimation", {"duration": 6.0}, {"estimator.c0": 7.0}),  # the RMS from the 5 s settle window on
    ("ex4_geometric", {"duration": 1.5, "estimator.mass": 1.0, "estimator.inertia": [0.02, 0.02, 0.05]},
     {"plant.mass": 1.4}),  # a model mismatch in mass and inertia
    ("ex4_geometric", {"duration": 1.0, "actuation": "rotors", "estimator.enabled": False},
     {"plant.mass": 2.5}),  # rotors at their limits (saturation, the wrench gives way)
    ("ex5_voliro", {"duration": 1.0, "estimator.enabled": False}, {"plant.mass": 2.0}),  # tilts
    ("ex5_voliro", {"duration": 1.0}, {"plant.mass": 2.0}),  # rotors and tilts with the estimator
    ("octo_ground_effect", {"duration": 1.5}, {"plant.mass": 2.5}),  # ground effect: the thrust ratios
    ("ceiling_approach", {"duration": 1.0}, {}),  # the ceiling's
    ("wind_rejection", {"duration": 1.0, "plant.rotor_time_constant": 0.02}, {"plant.mass": 1.3}),  # rotor lag
    ("ex5_voliro", {"duration": 1.0, "plant.tilt_time_constant": 0.03, "plant.tilt_rate_max_deg_s": 120},
     {}),  # tilt lag
    ("ex3_estimation", {"duration": 1.0, "plant.rotor_time_constant": 0.03}, {"plant.mass": 1.3}),  # wrench lag
])
def test_a_flight_measured_in_the_loop_has_the_row_of_its_arrays(scenario, fixed, values):
    base = load_scenario(scenario, values=fixed)
    measured, steps = fly_one(base, values)
    from_arrays, steps_from_arrays = fly_one(base, values, measured=False)
    assert measured["end_reason"] == "finished" and steps == steps_from_arrays
    assert_rows_agree(measured, from_arrays)


def test_the_loop_leaves_a_flight_that_ends_early_to_its_arrays():
    diverging = load_scenario("ex4_geometric", values={"duration": 2.0, "actuation": "rotors",
                                                       "estimator.enabled": False})
    row, steps = fly_one(diverging, {"plant.mass": 30.0})
    assert row["end_reason"] == "diverged" and steps < 2000
    assert_rows_agree(row, fly_one(diverging, {"plant.mass": 30.0}, measured=False)[0])


@pytest.mark.parametrize(("scenario", "fixed", "mass"), [
    ("ex4_geometric", {"duration": 1.0}, 1.1),  # wrench actuation
    ("wind_rejection", {"duration": 1.0, "plant.rotor_time_constant": 0.02}, 1.3),  # rotors that lag
    ("wind_rejection_turbulent", {"duration": 1.0, "sensors.odometry.position_std": 0.001}, 1.3),  # gusts, noise
])
def test_flights_set_up_from_the_packed_sweep_have_the_rows_of_a_full_set_up(scenario, fixed, mass):
    base = load_scenario(scenario, values=fixed)
    packed = packed_sweep(base, 0.01)
    flights = [{"plant.mass": mass}, {"plant.mass": mass + 0.3, "plant.inertia": [0.03, 0.03, 0.06]},
               {"plant.inertia": [[0.03, 0.001, 0.0], [0.001, 0.03, 0.0], [0.0, 0.0, 0.06]]}, {"plant.mass": mass}]
    rows = []
    for values in flights:  # one after the other: each starts from the initial states again
        assert packed.flight_for(values) is not None
        row, steps = fly_one(base, values, packed=packed)
        full, full_steps = fly_one(base, values)
        assert row == full and steps == full_steps == 1000  # the same arithmetic: the same numbers
        assert_rows_agree(row, fly_one(base, values, measured=False)[0])
        rows.append(row)
    assert rows[0] == rows[3] and rows[0] != rows[1]


@pytest.mark.parametrize("values", [
    {"plant.mass": 1.2, "estimator.mass": 1.3}, {"controller.allocation": "clamp"},  # what it does not re-pack:
    {"controller.type": "indi"}, {"plant.rotor_time_constant": 0.02}, {"duration": 0.2},  # the model, the plan,
    {"trajectory.goal_duration": 2.0}, {"sensors.imu.rate_hz": -1.0},  # the layout; refused values:
    {"controller.gains.k_p": [7, -7, 40]}, {"controller.gains.k_i": [1, 1, 1], "controller.integral_limit": -1},
    {"plant.mass": -1.0}, {"plant.mass": True}, {"plant.mass": math.nan},  # values the full set-up refuses
    {"plant.inertia": [0.03, -0.03, 0.06]}, {"plant.inertia": [[0.03, 0.01, 0.0], [0.0, 0.03, 0.0], [0, 0, 0.06]]},
    {"plant.inertia.0": 0.03},
    {"estimator.c0": -1.0}, {"estimator.c0": 3000.0}, {"estimator.r": 0}, {"estimator.r": 2.0}, {"estimator.r": True},
])
def test_what_the_packed_sweep_cannot_set_up_is_set_up_in_full(values):
    base = load_scenario("ex4_geometric", values={"duration": 0.3})
    packed = packed_sweep(base, 0.01)
    assert packed.flight_for(values) is None
    assert fly_one(base, values, packed=packed) == fly_one(base, values)


def test_a_refused_or_diverging_value_of_a_packed_sweep_is_the_full_path_row():
    base = load_scenario("ex4_geometric", values={"duration": 2.0, "actuation": "rotors",
                                                  "estimator.enabled": False})
    packed = packed_sweep(base, 0.01)
    refused, _ = fly_one(base, {"plant.mass": -1.0}, packed=packed)
    assert refused["end_reason"] == "invalid" and "plant.mass" in refused["end_detail"]
    assert packed.flight_for({"plant.mass": 30.0}) is not None
    diverged, steps = fly_one(base, {"plant.mass": 30.0}, packed=packed)
    assert diverged["end_reason"] == "diverged" and "crashed into the ground" in diverged["end_detail"]
    assert (diverged, steps) == fly_one(base, {"plant.mass": 30.0}, measured=False)


def test_a_filter_of_the_observer_is_packed_anew_and_each_flight_has_the_row_of_a_full_set_up():
    base = load_scenario("ex3_estimation", values={"duration": 6.0})
    packed = packed_sweep(base, 0.01)
    flights = [{"estimator.c0": 5.0, "estimator.r": 3}, {"estimator.r": 1}, {"estimator.c0": 20.0},
               {"plant.mass": 1.2, "estimator.c0": 5.0, "estimator.r": 3}, {"estimator.c0": 5.0, "estimator.r": 3}]
    rows = []
    for values in flights:
        assert packed.flight_for(values) is not None
        row, _ = fly_one(base, values, packed=packed)
        assert row == fly_one(base, values)[0]
        rows.append(row)
    assert rows[0] == rows[4] and rows[0] != rows[1] != rows[2] and rows[0] != rows[3]


@pytest.mark.parametrize(("fixed", "values"), [
    ({"controller.compensation": "estimate"}, {"estimator.c0": 5.0}),  # the controller's observer has c0 too
    ({"estimator.enabled": False}, {"estimator.r": 2}),
])
def test_the_observer_filter_is_set_up_in_full_where_more_than_the_observer_reads_it(fixed, values):
    base = load_scenario("wind_rejection", values={"duration": 0.3, **fixed})
    packed = packed_sweep(base, 0.01)
    assert packed.flight_for(values) is None and packed.flight_for({"plant.mass": 1.3}) is not None
    assert fly_one(base, values, packed=packed) == fly_one(base, values)


def assert_packed_equal(got, want, where: str = "") -> None:
    """Two packed objects (NamedTuples of arrays and numbers, nested) equal to the bit."""
    if isinstance(want, np.ndarray):
        assert got.dtype == want.dtype and got.shape == want.shape, where
        if want.dtype.names:  # a record (named state): field by field
            for name in want.dtype.names:
                assert_packed_equal(np.asarray(got[name]), np.asarray(want[name]), f"{where}.{name}")
        else:
            assert np.array_equal(got, want, equal_nan=True), where
    elif isinstance(want, tuple):
        assert type(got) is type(want) and len(got) == len(want), where
        names = getattr(want, "_fields", range(len(want)))
        for name, a, b in zip(names, got, want, strict=True):
            assert_packed_equal(a, b, f"{where}.{name}")
    elif isinstance(want, float) and math.isnan(want):
        assert math.isnan(got), where
    else:
        assert type(got) is type(want) and got == want, where


GAINS = {"controller.gains.k_p": [3.0, 3.0, 20.0], "controller.gains.k_v": [4.0, 4.0, 9.0],
         "controller.gains.k_r": [12.0, 12.0, 3.0], "controller.gains.k_w": [2.5, 2.5, 1.5]}


@pytest.mark.parametrize(("scenario", "fixed", "values"), [
    ("step_disturbance", {"duration": 1.0, "sensors.preset": "onboard", "plant.rotor_time_constant": 0.03},
     {"plant.mass": 1.3, **GAINS}),  # fsr-tune's walk-through: gains, seeds, a mass
    ("wind_rejection_turbulent", {"duration": 1.0, "sensors.preset": "onboard"},
     {"controller.gains.k_i": [0.5, 0.5, 1.0], "controller.integral_limit": 2.0}),  # the Dryden wind's seed too
    ("ex3_estimation", {"duration": 1.0}, {"estimator.c0": 7.0, "controller.gains.k_r": [9, 9, 90],
                                           "controller.acceleration_filter_hz": 20.0}),  # the report's law
    ("ex5_voliro", {"duration": 0.5}, {"controller.gains.k_p": [9, 9, 30], "plant.inertia": [0.03, 0.03, 0.06]}),
    ("ex4_geometric", {"duration": 0.5, "actuation": "rotors", "controller.type": "indi",
                       "sensors.preset": "ideal"}, {"controller.filter_hz": 40.0, **GAINS}),
])
def test_gains_and_seeds_are_packed_anew_into_the_arrays_of_a_full_set_up(scenario, fixed, values):
    base = load_scenario(scenario, values=fixed)
    packed = packed_sweep(base, 0.01)
    keys = seed_keys(base.data, lambda key: True)
    for condition in (0, 1, 0, 2, 1):  # one after the other: each from the initial states again, a condition
        flight = {**condition_values(0, condition, keys, []), **values}  # flown again from what was kept of it
        fast = packed.flight_for(flight)
        assert fast is not None
        full = loop_flight(prepare_flight(flight_scenario(base, flight)), 0.01)
        for name in ("plant_params", "plant_state", "controller_params", "controller_state", "observer_params",
                     "observer_state", "measures", "actuator_params", "actuator_state", "steps", "control_bounds"):
            assert_packed_equal(getattr(fast, name), getattr(full, name), name)
        row, steps = fly_one(base, flight, packed=packed)
        assert (row, steps) == fly_one(base, flight)


def test_a_sensor_switched_off_under_a_law_that_needs_it_is_refused_as_the_full_set_up_refuses_it():
    base = load_scenario("ex4_geometric", values={"duration": 0.3, "actuation": "rotors", "controller.type": "indi",
                                                  "sensors.preset": "ideal"})
    packed = packed_sweep(base, 0.01)
    assert packed.flight_for({"sensors.imu.enabled": False}) is None
    refused, _ = fly_one(base, {"sensors.imu.enabled": False}, packed=packed)
    assert refused["end_reason"] == "invalid" and "controller.type" in refused["end_detail"]
    assert packed.flight_for({"sensors.imu.seed": 5}) is not None


@pytest.mark.parametrize("values", [{"sensors.odometry.delay_steps": 4}, {"sensors.odometry.rate_hz": 250.0},
                                    {"sensors.preset": "ideal"}])
def test_the_odometry_indi_bridges_is_packed_anew_with_its_law(values):
    """INDI's law reads the odometry's delay and rate (its IMU bridge): a sweep over them packs the law anew."""
    base = load_scenario("ex4_geometric", values={"duration": 0.3, "actuation": "rotors", "controller.type": "indi",
                                                  "sensors.preset": "onboard"})
    packed = packed_sweep(base, 0.01)
    fast = packed.flight_for(values)
    assert fast is not None
    full = loop_flight(prepare_flight(flight_scenario(base, values)), 0.01)
    assert_packed_equal(fast.controller_params, full.controller_params, "controller_params")
    assert fly_one(base, values, packed=packed) == fly_one(base, values)


@pytest.mark.parametrize("values", [GAINS, {"plant.mass": 1.4}])
def test_a_flight_for_one_metric_has_the_columns_of_the_whole_row_but_the_estimators(values):
    base = load_scenario("step_disturbance", values={"duration": 6.0, "sensors.preset": "onboard",
                                                     "plant.rotor_time_constant": 0.03})
    packed = packed_sweep(base, 0.01)
    flight = {**condition_values(0, 1, seed_keys(base.data, lambda key: True), []), **values}
    whole, steps = fly_one(base, flight)
    assert whole["end_reason"] == "finished" and math.isfinite(whole["estimate_force_rms_N"])
    one, one_steps = fly_one(base, flight, packed=packed, metric="position_error_rms_m")
    assert one_steps == steps
    for column in METRIC_COLUMNS:  # without the estimator (the controller does not read it), the same flight
        assert math.isnan(one[column]) if column in TRUTH_COLUMNS else one[column] == whole[column], column
    assert fly_one(base, flight, packed=packed, metric="estimate_force_rms_N") == (whole, steps)


def test_a_lost_flight_for_one_metric_is_its_end_alone():
    base = load_scenario("ex4_geometric", values={"duration": 2.0, "actuation": "rotors", "estimator.enabled": False})
    packed = packed_sweep(base, 0.01)
    whole, steps = fly_one(base, {"plant.mass": 30.0})
    lost, lost_steps = fly_one(base, {"plant.mass": 30.0}, packed=packed, metric="position_error_rms_m")
    assert whole["end_reason"] == lost["end_reason"] == "diverged" and lost_steps == steps < 2000
    assert lost["flown_s"] == whole["flown_s"] and math.isnan(lost["position_error_rms_m"])


ONE_TRUTH_FLIGHTS = [
    ("ex3_estimation", {"duration": 1.0, "plant.rotor_time_constant": 0.03}),  # wrench actuation, the wrench lags
    ("octo_ground_effect", {"duration": 1.0}),  # rotors, the ground's thrust ratios
    ("wind_rejection", {"duration": 1.0, "plant.rotor_time_constant": 0.02}),  # rotors that lag
    ("ex5_voliro", {"duration": 1.0, "estimator.mass": 1.9}),  # tilts, a model mismatch
]


@pytest.mark.parametrize(("scenario", "fixed"), ONE_TRUTH_FLIGHTS)
def test_the_analysis_effective_truth_is_the_loops(scenario, fixed):
    """One flight flown written out and measured at once: the loop's accumulators (the effective truth of each
    step from its state) equal the same accumulators fed the flight's arrays and the analysis's effective truth
    of them (one compiled function, applied to a log)."""
    import numpy as np

    from fsr_bringup.analysis.effective import effective_wrench
    from fsr_bringup.analysis.in_memory import recorded_flight_of_run
    from fsr_bringup.core import flight_loop
    from fsr_bringup.core import flight_measures as core
    from fsr_bringup.runner.in_process_flight import prepare_flight
    from fsr_bringup.sweeps.measured import loop_flight

    setup = prepare_flight(load_scenario(scenario, values=fixed))
    loop, a = loop_flight(setup, 0.01), setup.arrays
    acc = core.new_accumulators()
    estimator = flight_loop.LoopEstimator(loop.with_estimator, loop.estimator_measured, loop.observer_params,
                                          loop.observer_state)
    trace = flight_loop.LoopTrace(a.states, a.published, a.actuators, a.control, a.estimates)
    measurement = core.Measurement(loop.measures, loop.actuator_params, loop.actuator_state, a.rotor_rows, acc)
    outcome, k, _ = flight_loop.fly(
        flight_loop.LoopPlant(loop.plant_params, loop.plant_state),
        flight_loop.LoopController(loop.controller_params, loop.controller_state), estimator, 0, setup.steps,
        setup.steps, setup.period_ns, loop.control_bounds, flight_loop.RECORD | flight_loop.MEASURE, trace, measurement)
    assert outcome == flight_loop.FINISHED and k == setup.steps
    flight = recorded_flight_of_run(setup.run(k + 1, "finished", "", 0.0))
    truth = effective_wrench(flight)
    from_arrays = core.new_accumulators()
    odom = flight.odom
    core.measure_log(loop.measures, from_arrays, odom.t, np.ascontiguousarray(odom.position),
                     np.ascontiguousarray(odom.rotation), a.control[:k + 1], truth.wrench_body, a.estimates[:k + 1])
    assert acc[0].truth_samples == from_arrays[0].truth_samples == setup.steps
    for name in core.ACCUMULATORS.names:
        np.testing.assert_allclose(np.asarray(from_arrays[0][name], float), np.asarray(acc[0][name], float),
                                   rtol=1e-9, atol=1e-12, err_msg=name)


@pytest.mark.parametrize(("scenario", "fixed"), ONE_TRUTH_FLIGHTS[:3])
def test_a_recorded_flights_row_is_the_sweeps_row_of_that_flight(scenario, fixed, tmp_path):
    """The row of a flight's recording (its samples fed through the sweep's accumulators) is the row the sweep
    measured as it flew the same flight."""
    from fsr_bringup.analysis.load import load_flight
    from fsr_bringup.runner.in_process_flight import fly_in_process
    from fsr_bringup.sweeps.metrics import recorded_row

    base = load_scenario(scenario, values=fixed)
    measured, _ = fly_one(base, {})
    fly_in_process(base, tmp_path / "flight.mcap")
    assert_rows_agree(recorded_row(load_flight(tmp_path / "flight.mcap")), measured)
