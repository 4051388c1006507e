"""fsr-tune: each method finds the optimum a grid finds on a two-gain case, a study interrupted after a
generation is continued by ``resume`` (no trial flown twice), a diverging candidate is a trial with the penalty,
and bad ranges, keys and metrics are refused with one line naming them."""

from __future__ import annotations

import math
import re
import subprocess
import sys

import numpy as np
import pytest

from fsr_bringup import sweep, tune
from fsr_bringup.sweeps.metrics import RANKABLE_METRICS
from fsr_bringup.tuning.conditions import IMU_SEED_KEY, ODOMETRY_SEED_KEY, condition_values, scenario_seed_keys
from fsr_bringup.tuning.objective import Objective, parse_objective
from fsr_bringup.tuning.space import SAME, Range, TuneError, parse_param, tuned_key
from fsr_bringup.tuning.study import GENERATION

# The two-gain case: the lateral position gains of step_disturbance against its force step (1 s to 4 s). Too
# soft and the step pushes the vehicle away, too stiff for quadrotor_ex4's slow attitude loop and it rings: the
# RMS error is a bowl in (k_p, k_v) of x and y.
BOWL = {"duration": 6.0, "disturbances.0.start": 1.0, "disturbances.0.end": 4.0, "estimator.enabled": False}
BOWL_PARAMS = {"controller.gains.k_p": "log:4:80,same,100", "controller.gains.k_v": "log:4:80,same,100"}


def test_a_range_per_entry_same_and_held_numbers():
    key = tuned_key("controller.gains.k_p", parse_param("controller.gains.k_p=log:1:50,same,100")[1], 3)
    assert key.entries == (Range("controller.gains.k_p.0", 1.0, 50.0, True), SAME, 100.0)
    assert key.value({"controller.gains.k_p.0": 7.0}) == [7.0, 7.0, 100.0]
    every = tuned_key("controller.gains.k_v", ["2:20"], 3)
    assert [r.name for r in every.ranges] == [f"controller.gains.k_v.{i}" for i in range(3)]
    assert tuned_key("estimator.c0", ["log:1:100"], None).value({"estimator.c0": 5.0}) == 5.0


@pytest.mark.parametrize(("text", "size", "message"), [
    ("k=5:1", None, "needs finite LO < HI, got 5:1"),
    ("k=log:0:10", None, "log needs 0 < LO"),
    ("k=a:b", None, "'a' and 'b' must be numbers"),
    ("k=1:2,3:4", None, "a single number, give one range"),
    ("k=1:2,3:4", 3, "3 entries, give one range for all or one item per entry, got 2"),
    ("k=same,1:2,3:4", 3, "the first entry cannot be 'same'"),
    ("k=1,2,3", 3, "no entry has a range"),
])
def test_bad_ranges_are_refused_naming_the_key(text, size, message):
    with pytest.raises(TuneError, match=message.replace("(", r"\(")):
        key, items = parse_param(text)
        tuned_key(key, items, size)


def test_the_objective_is_a_statistic_with_a_penalty_for_lost_flights():
    rows = [{"end_reason": "finished", "position_error_rms_m": value} for value in (0.1, 0.2, 0.3, math.inf)]
    rows.append({"end_reason": "diverged", "position_error_rms_m": 0.05, "flown_s": 5.0})  # lost at 5 s of 10
    objective = parse_objective("position_error_rms_m:max", penalty=3.0)
    assert objective.of(rows, 10.0) == 4.5  # 3 * (2 - 5 / 10)
    assert Objective("position_error_rms_m", "mean", 3.0).of(rows, 10.0) == pytest.approx((0.6 + 3.0 + 4.5) / 5)
    assert Objective("position_error_rms_m", "median", 3.0).of(rows, 10.0) == 0.3
    # a flight lost later counts less, never less than the penalty; one refused before flying, twice it
    lost_at = [Objective("position_error_rms_m", "mean", 3.0).of([{"end_reason": "diverged", "flown_s": t}], 10.0)
               for t in (0.5, 5.0, 9.5, 10.0)]
    assert lost_at == sorted(lost_at, reverse=True) and lost_at[-1] == 3.0
    assert objective.of([{"end_reason": "invalid"}], 10.0) == 6.0
    for text, message in (("position_error", "unknown metric 'position_error'"), ("position_error_rms_m:q99",
                                                                                    "unknown statistic 'q99'")):
        with pytest.raises(TuneError, match=message):
            parse_objective(text)
    assert "position_error_rms_m" in RANKABLE_METRICS


def test_conditions_are_the_same_for_every_candidate_and_differ_between_seeds():
    from fsr_bringup.sweeps.axes import sampled_key

    mass = [sampled_key("plant.mass", "uniform:1.0:1.4")]
    a = condition_values(7, 3, ["sensors.odometry.seed"], mass)
    assert a == condition_values(7, 3, ["sensors.odometry.seed"], mass)
    assert a != condition_values(7, 4, ["sensors.odometry.seed"], mass)
    assert 1.0 <= a["plant.mass"] <= 1.4 and 0 <= a["sensors.odometry.seed"] < 2**32


def test_a_seed_key_never_adds_a_sensor_the_scenario_has_not():
    """The IMU's seed, set alone, would add an (ideal) IMU that the flight profile's law flies on: a condition under
    motion capture (no IMU) seeds the odometry only; under the onboard preset the IMU as well."""
    from fsr_bringup.runner.scenario_check import check_scenario
    from fsr_bringup.sweeps.axes import flight_scenario
    from fsr_sim.config.scenario import load_scenario

    mocap = load_scenario("step_disturbance", values={"sensors.preset": "mocap"})
    assert scenario_seed_keys(mocap) == [ODOMETRY_SEED_KEY]
    assert not check_scenario(flight_scenario(mocap, {ODOMETRY_SEED_KEY: 5})).simulation.imu.enabled
    onboard = load_scenario("step_disturbance", values={"sensors.preset": "onboard"})
    assert scenario_seed_keys(onboard) == [ODOMETRY_SEED_KEY, IMU_SEED_KEY]


def test_training_conditions_span_each_sampled_key_and_held_out_ones_draw_it():
    from fsr_bringup.tuning.study import plan_tune

    # ten random draws of a +-20 % mass leave its lightest tenth unseen one study in three, and the tuned gains
    # lost the held-out flights there: the training conditions take the range's quantiles, its bounds included
    plan = plan_tune("step_disturbance", {"controller.gains.k_p": "log:1:60"}, seeds=4, holdout=50, seed=3,
                     sample={"plant.mass": "uniform:0.96:1.44", "estimator.c0": "normal:10:2"})
    training = [values for _, values in plan.batch({}, 0, plan.seeds).flights]
    assert sorted(v["plant.mass"] for v in training) == pytest.approx([0.96, 1.12, 1.28, 1.44])
    normal = sorted(v["estimator.c0"] for v in training)  # quantiles 1/8, 3/8, 5/8, 7/8 of N(10, 2)
    assert normal == pytest.approx([10 - 2.30063, 10 - 0.63719, 10 + 0.63719, 10 + 2.30063], abs=1e-4)
    assert len({v["sensors.odometry.seed"] for v in training}) == 4  # each its own noise
    assert [v["plant.mass"] for v in training] != sorted(v["plant.mass"] for v in training)  # shuffled
    # held out: independent draws of the same distribution, not the training's quantiles
    held = [values for _, values in plan.batch({}, plan.seeds, plan.holdout).flights]
    masses = np.array([v["plant.mass"] for v in held])
    assert masses.min() >= 0.96 and masses.max() <= 1.44 and len(set(masses)) == 50
    assert not set(masses) & {v["plant.mass"] for v in training}
    assert abs(masses.mean() - 1.2) < 0.05 and abs(np.mean([v["estimator.c0"] for v in held]) - 10) < 1.0


@pytest.fixture(scope="module")
def grid_optimum() -> float:
    """The best RMS error of the bowl on a 6 x 6 grid of its two gains (log spaced over their ranges)."""
    gains = np.geomspace(4.0, 80.0, 6)
    table = sweep("step_disturbance", set=BOWL, workers=2,
                  grid={"controller.gains.k_p": [[g, g, 100.0] for g in gains],
                        "controller.gains.k_v": [[g, g, 100.0] for g in gains]})
    return float(table["position_error_rms_m"].min())


@pytest.mark.slow
@pytest.mark.parametrize("method", ["cma", "tpe", "random"])
def test_each_method_finds_the_grids_optimum_within_5_percent(grid_optimum, method):
    result = tune("step_disturbance", BOWL_PARAMS, seeds=1, budget=48, method=method, set=BOWL, holdout=0,
                  workers=2, seed=1)
    assert result.best_objective <= 1.05 * grid_optimum, (result.best_values, result.best_objective, grid_optimum)
    assert len(result.trials) == 48 and (result.trials["trial_state"] == "complete").all()


@pytest.mark.slow
def test_an_interrupted_study_is_resumed_without_flying_a_trial_twice(tmp_path):
    kwargs = dict(seeds=1, budget=3 * GENERATION, method="cma", set=BOWL, holdout=0, workers=2, out=tmp_path)

    def stop_after_the_first_generation(done: int, *_: object) -> None:
        raise KeyboardInterrupt

    first = tune("step_disturbance", BOWL_PARAMS, progress=stop_after_the_first_generation, **kwargs)
    assert first.interrupted and len(first.trials) == GENERATION
    again = tune("step_disturbance", BOWL_PARAMS, resume=True, **kwargs)
    assert not again.interrupted and (again.trials["trial_state"] == "complete").sum() == 3 * GENERATION
    assert again.flights == 1 + 2 * GENERATION  # the baseline, then only the trials still to fly
    np.testing.assert_array_equal(again.trials.iloc[:GENERATION].to_numpy(), first.trials.to_numpy())
    with pytest.raises(TuneError, match="other settings"):
        tune("step_disturbance", BOWL_PARAMS, resume=True, **{**kwargs, "seeds": 2})
    with pytest.raises(TuneError, match="holds a study already"):
        tune("step_disturbance", BOWL_PARAMS, **kwargs)


@pytest.mark.slow
def test_a_diverging_candidate_is_a_trial_with_the_penalty():
    # an attitude damping far beyond what a 1 kHz loop on 1.24 kg m^2 can take (k_w dt / I > 2) spins it up
    result = tune("ex4_geometric", {"controller.gains.k_w": "log:100:100000,same,100"}, seeds=2, budget=GENERATION,
                  method="random", duration=1.0, holdout=0, workers=1, penalty=7.0)
    lost = result.trials[result.trials["lost"] == 2]
    kept = result.trials[result.trials["lost"] == 0]
    # a lost flight counts between the penalty and twice it (less the later it was lost): 7 <= objective < 14
    assert len(lost) and lost["objective"].between(7.0, 14.0, inclusive="left").all()
    assert (lost["controller.gains.k_w.0"] > 4000).all()
    assert len(kept) and (kept["objective"] < 7.0).all()


def fsr_tune(*args: str, cwd) -> subprocess.CompletedProcess:  # noqa: ANN001
    return subprocess.run([sys.executable, "-m", "fsr_bringup.cli.tune_cli", *args], capture_output=True, text=True,
                          cwd=cwd, timeout=240)


@pytest.mark.parametrize(("args", "message"), [
    (["--param", "controller.gains.k_p=5:1"], "needs finite LO < HI"),
    (["--param", "controller.gains.kp=1:5"], "did you mean 'k_p'"),
    (["--param", "plant.mass=1:2", "--objective", "rms"], "unknown metric 'rms'"),
    (["--param", "plant.mass=1:2", "--objective", "position_error_rms_m:q95"], "unknown statistic 'q95'"),
    (["--param", "estimator.c0=1:100", "--param", "estimator.c0=1:5"], "estimator.c0: given twice"),
    ([], "give at least one --param"),
])
def test_the_cli_exits_2_with_one_line_naming_the_problem(tmp_path, capsys, args, message):
    from fsr_bringup.cli.tune_cli import main

    try:
        code = main(["ex4_geometric", "--duration", "0.2", "--budget", "8", "--out", str(tmp_path / "out"), *args])
    except SystemExit as stop:  # argparse's errors
        code = stop.code
    assert code == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], lines
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_the_cli_writes_the_best_the_trials_the_summary_and_the_figures(tmp_path):
    import yaml

    out = tmp_path / "tune"
    result = fsr_tune("step_disturbance", "--param", "controller.gains.k_p=log:4:80,same,100", "--seeds", "2",
                      "--budget", "8", "--holdout", "2", "--duration", "3", "--set", "estimator.enabled=false",
                      "--out", str(out), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    best = yaml.safe_load((out / "best.yaml").read_text())
    gains = best["controller"]["gains"]["k_p"]
    assert len(gains) == 3 and gains[0] == gains[1] and gains[2] == 100.0
    summary = (out / "summary.md").read_text()
    assert "## Against the scenario's own parameters" in summary and "held out (2)" in summary
    # flown again in the conditions it was tuned for
    fly = re.search(r"Fly it: `(fsr-fly [^`]*)`", summary).group(1)
    assert "--set estimator.enabled=false" in fly and "--set duration=3" in fly and "controller.gains.k_p=[" in fly
    for name in ("trials.csv", "objective.png", "parameters.png", "study.db"):
        assert (out / name).stat().st_size > 0, name
