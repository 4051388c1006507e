"""The estimator node's parameters: typed checks and how they override the scenario (no rclpy here).

ROS parameters (``--ros-args -p name:=value``):

* ``scenario`` (string): a built-in scenario name or a scenario YAML file; its ``estimator`` section
  (:mod:`fsr_estimation.config.estimator_config`) gives c0, r, mass and inertia, and its physics step x
  substeps the expected control period.
* Overrides: ``c0`` (rad/s > 0), ``r`` (integer >= 1), ``mass`` (kg > 0), ``inertia`` (3 numbers, the
  diagonal, or 9, row-major; symmetric positive definite) and ``control_period`` (s > 0; without it and
  without a scenario the period is taken from the first two samples).

Without a scenario, ``mass`` and ``inertia`` are required. A refused value raises :class:`ConfigError`
reading ``ROS parameter: <name>: <reason>``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from fsr_estimation.config.estimator_config import DEFAULT_C0, DEFAULT_R, EstimatorConfig, estimator_config
from fsr_estimation.estimator.filter_design import check_filter_parameters
from fsr_sim.config.scenario import load_scenario, simulation_config
from fsr_sim.config.validation import ConfigError, Section, checked_spd
from fsr_sim.contract import (
    ESTIMATOR,
    EXIT_CONFIG_ERROR,
    EXIT_FAILURE,
    EXIT_OK,
    ODOM,
    ROTOR_STATE,
    SIM_STATUS,
    WRENCH_CMD,
)
from fsr_sim.model.rotors import actuation_matrix
from fsr_sim.ros.node_usage import NodeUsage, Parameter
from fsr_sim.ros.recorder_match import RECORDED_TOPICS

PARAMETER_SOURCE = "ROS parameter"
USAGE = NodeUsage(
    ESTIMATOR,
    "Momentum-based external wrench and mass estimation on the live graph (docs/model.md section 3.8).",
    (
        Parameter("scenario", "", "built-in scenario name or scenario YAML path: its estimator section"),
        Parameter("c0", "", f"rad/s > 0, the observer's filter (default: the scenario's, else {DEFAULT_C0:g})"),
        Parameter("r", "", f"integer >= 1, the filter's order (default: the scenario's, else {DEFAULT_R})"),
        Parameter("mass", "", "kg > 0, the nominal mass (required without a scenario)"),
        Parameter("inertia", "", "3 numbers (the diagonal) or 9 (row-major), kg m^2 (required without a scenario)"),
        Parameter("control_period", "", "s > 0 (default: the scenario's, else from the first two samples)"),
        Parameter("exit_on_finish", "true", "end by itself once sim_status reports the end of the flight"),
        RECORDED_TOPICS,
    ),
    (ODOM, WRENCH_CMD, ROTOR_STATE, SIM_STATUS),
    (EXIT_OK, EXIT_FAILURE, EXIT_CONFIG_ERROR),
)
PARAMETER_NAMES = tuple(p.name for p in USAGE.parameters  # those two: fsr_sim.ros
                        if p.name not in ("exit_on_finish", RECORDED_TOPICS.name))


@dataclass(frozen=True)
class EstimatorNodeSettings:
    config: EstimatorConfig
    control_period: float | None  # s; None: measured from the first two samples
    # estimator.input measured (and rotor_state published): the nominal vehicle's allocation (fsr_sim.model.
    # allocation.actuation_matrix), c_f [N s^2] and whether its rotors tilt; None: the observer takes wrench_cmd
    rotor_allocation: tuple[np.ndarray, float, bool] | None = None


def node_settings(values: dict[str, Any]) -> EstimatorNodeSettings:
    """Check raw parameter values (``None`` = not given), merge them over the scenario's estimator section."""
    given = {name: value for name, value in values.items() if value is not None}
    section = Section(given, "", PARAMETER_SOURCE)
    scenario = section.string("scenario", "").strip()
    c0 = section.number("c0", strictly_positive=True) if section.has("c0") else None
    r = section.integer("r", minimum=1) if section.has("r") else None
    mass = section.number("mass", strictly_positive=True) if section.has("mass") else None
    inertia = None
    if section.has("inertia"):
        raw = np.asarray(list(section.raw("inertia")), dtype=float)
        inertia = checked_spd(raw.reshape(3, 3) if raw.size == 9 else raw, "inertia", PARAMETER_SOURCE)
    period = section.number("control_period", strictly_positive=True) if section.has("control_period") else None
    section.reject_unknown()
    rotor_allocation = None
    if scenario:
        loaded = load_scenario(scenario)
        base = estimator_config(loaded)
        sim = simulation_config(loaded)
        if period is None:
            period = sim.control_period
        if base.rotor_state:
            vehicle = sim.vehicle
            rotor_allocation = (np.ascontiguousarray(actuation_matrix(vehicle)), float(vehicle.c_f),
                                bool(vehicle.has_servos))
    else:
        for name, value in (("mass", mass), ("inertia", inertia)):
            if value is None:
                raise ConfigError(name, "is required when no scenario is given", PARAMETER_SOURCE)
        base = EstimatorConfig(enabled=True, mass=mass, inertia=inertia, c0=DEFAULT_C0, r=DEFAULT_R)
    overrides = {"mass": mass, "inertia": inertia, "c0": c0, "r": r}  # the parameters given win
    config = replace(base, **{name: value for name, value in overrides.items() if value is not None})
    if period is not None:
        try:
            check_filter_parameters(config.c0, config.r, period)
        except ValueError as error:
            raise ConfigError("", str(error), PARAMETER_SOURCE) from None
    return EstimatorNodeSettings(config=config, control_period=period, rotor_allocation=rotor_allocation)
