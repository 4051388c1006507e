"""The ``controller`` and ``trajectory`` sections of a scenario, validated (fsr_control's part of it; the
``trajectory`` section's keys: :mod:`fsr_control.config.trajectory_config`).

```yaml
controller:
  type: geometric                   # geometric (thrust along -z_b) | voliro (fully actuated) | indi
                                    # (thrust along -z_b, from the IMU and the rotors' speeds) | a law of
                                    # fsr_control.controllers.catalog.LAWS; default by vehicle
  profile: flight                   # flight (default): gains designed from the vehicle
                                    # (fsr_control.design.gain_design), geometric feedforward: reference |
                                    # report: the report's gains, geometric feedforward: measured
  gains: {k_p: [20, 20, 100], k_v: [20, 20, 100], k_r: [10, 10, 100], k_w: [10, 10, 100]}
                                    # any given here replaces the profile's; geometric also k_i [N/(m s)]
                                    # (>= 0: 3 numbers or a symmetric positive semi-definite 3x3; 0: none)
  feedforward: reference            # geometric: where R_d's rates come from: reference (jerk, snap) |
                                    # measured (the measured acceleration: the report's); default by profile
  use_imu: true                     # geometric: fly on the IMU: damp with the gyro and, where odom is a
                                    # measurement, fly on the IMU-bridged estimate of the state; its designed
                                    # gains have no odometry delay to survive; default: flight profile with
                                    # sensors.imu (report: false)
  integral_limit: 2.94              # geometric and indi, with k_i: bound [N] on |K_i int e_p| (default: 0.25 m g)
  filter_hz: 30                     # indi: cutoff [Hz] of the second-order low-pass on every measured signal
                                    # (below the Nyquist frequency of the control rate)
  angular_feedforward: consistent   # voliro only: consistent | report
  secondary_objective: {type: none} # voliro only: none | min_peak_speed (exponent: 8, iterations: 3)
  allocation: priority              # beyond the rotor limits: priority (yaw gives way first) | clamp
  air_mode: true                    # fixed rotors, priority: the thrust may rise to make room for roll/pitch
                                    # torque (true) | the thrust is kept and the torque scaled (false)
  acceleration_filter_hz: 0         # geometric: low-pass cutoff [Hz] on the measured acceleration its rates
                                    # use, and on the compensated estimate's rates (0: none, the report's
                                    # law); for noisy odom and sharp disturbances
  compensation: none                # none | estimate: cancel the external wrench the controller's own
                                    # observer estimates (needs estimator.enabled; fsr_control.compensation;
                                    # not with indi, which is its own)
  aerodynamics: model               # model: cancel the vehicle file's aerodynamics (drag, rotor drag,
                                    # inflow, lift, flapping) predicted along the reference, in still air,
                                    # when there is no compensation | none; default by profile (flight:
                                    # model), none for indi (it measures them) and vehicles on servos
```

Each gain is 3 positive numbers (a diagonal) or a symmetric positive-definite 3x3 matrix (``k_i`` may be
zero); gains not given take the profile's: ``report`` the report's values for the controller type,
``flight`` those designed from the vehicle. Unknown keys are refused with a typo hint. ``indi`` takes the
geometric law's gains and needs the vehicle's IMU (``sensors.imu``).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from fsr_control.allocation import ALLOCATION_STRATEGIES
from fsr_control.compensation import COMPENSATION_MODES, MAX_C0_PERIOD, CompensationConfig
from fsr_control.config.trajectory_config import (
    DEFAULT_AUTHORITY_MARGIN,
    DEFAULT_GOAL_DURATION,
    trajectory_config,
)
from fsr_control.controllers import geometric, indi, voliro
from fsr_control.controllers.catalog import LAWS
from fsr_control.controllers.common import check_actuation
from fsr_control.design.gain_design import INTEGRAL_LIMIT_SHARE
from fsr_control.planning.feasibility import (
    DEFAULT_FEASIBILITY,
    InfeasibleReferenceError,
    LegAdjustment,
    reference_limits,
)
from fsr_control.planning.paths import PathError, PathSpec
from fsr_control.planning.trajectory import Trajectory, Waypoint
from fsr_sim.config.scenario import Scenario, SimulationConfig, load_vehicle_for, simulation_config
from fsr_sim.config.validation import ConfigError, Section, checked_spd
from fsr_sim.model.environment import pack_surfaces
from fsr_sim.model.vehicle import Vehicle

SECONDARY_TYPES = ("none", "min_peak_speed")
DEFAULT_ALLOCATION = "priority"  # fsr_control.allocation.ALLOCATION_STRATEGIES: clamp | priority
PROFILES = ("flight", "report")  # controller.profile: the first is the default
PROFILE_FEEDFORWARD = {"flight": geometric.REFERENCE_FEEDFORWARD, "report": geometric.MEASURED_FEEDFORWARD}
AERODYNAMICS_MODES = ("model", "none")  # controller.aerodynamics
PROFILE_AERODYNAMICS = {"flight": "model", "report": "none"}


@dataclass(frozen=True)
class SecondaryObjectiveConfig:
    type: str = "none"
    exponent: int = 8
    iterations: int = 3


@dataclass(frozen=True)
class ControllerConfig:
    """Validated controller + trajectory settings. ``gains``: name -> 3x3 array."""

    type: str
    gains: dict[str, np.ndarray]
    waypoints: list[Waypoint]
    angular_feedforward: str = "consistent"  # voliro
    profile: str = PROFILES[0]  # controller.profile: flight | report
    feedforward: str = geometric.REFERENCE_FEEDFORWARD  # geometric: reference | measured
    integral_limit: float = 0.0  # geometric: [N] bound on the integral's force
    secondary_objective: SecondaryObjectiveConfig = field(default_factory=SecondaryObjectiveConfig)
    goal_duration: float = DEFAULT_GOAL_DURATION
    source: str = ""
    allocation: str = DEFAULT_ALLOCATION  # clamp | priority (fsr_control.allocation)
    compensation: CompensationConfig | None = None  # controller.compensation: estimate (None: none)
    air_mode: bool = True  # fixed rotors, priority allocation: thrust may rise for roll/pitch torque
    authority_margin: float = DEFAULT_AUTHORITY_MARGIN  # trajectory.authority_margin, in (0, 1]
    acceleration_filter_hz: float = 0.0  # controller.acceleration_filter_hz (0: the measured acceleration raw)
    feasibility: str = DEFAULT_FEASIBILITY  # trajectory.feasibility: stretch | warn | refuse
    plan_adjustments: tuple[LegAdjustment, ...] = ()  # the scenario's infeasible legs (from its initial state)
    path: PathSpec | None = None  # trajectory.kind minsnap, circle or lissajous (None: waypoints)
    trajectory_kind: str = "waypoints"  # trajectory.kind
    plan_end_time: float = 0.0  # [s] when the scenario's plan (from its initial state) comes to rest for good
    aerodynamics: str = "none"  # controller.aerodynamics: model | none
    filter_hz: float = 0.0  # indi: controller.filter_hz [Hz]
    control_period: float = 0.0  # [s] the lockstep's step (the period indi's filter is discretised at)
    rotor_state: bool = False  # the simulator publishes rotor_state (the rotors' measured speeds)
    odometry_measured: bool = False  # odom is a measurement (noisy, late or slow), not the true state
    odometry_delay_steps: int = 0  # steps odom's samples are late by (sensors.odometry)
    use_imu: bool = False  # geometric: the law flies on the IMU (controller.use_imu)

    def trajectory(self, vehicle: Vehicle, actuation: str, position: np.ndarray, rotation: np.ndarray,
                   start_time: float = 0.0) -> Trajectory:
        """The waypoints (or the path) planned from a start pose for ``vehicle``, each leg checked against its
        authority with rotor actuation (:mod:`fsr_control.planning.feasibility`; a commanded wrench has no rotor
        limits, so with ``actuation: wrench`` nothing is checked)."""
        limits = reference_limits(vehicle, self.authority_margin) if actuation == "rotors" else None
        return Trajectory(self.waypoints, position, rotation, full_attitude=vehicle.fully_actuated,
                          start_time=start_time, limits=limits, feasibility=self.feasibility, path=self.path)


def _gains(section: Section, controller_type: str, profile: str, vehicle: Vehicle,
           imu: bool = False) -> dict[str, np.ndarray]:
    """``controller.gains``: each given gain checked, the others the profile's (the report's, or designed from
    ``vehicle`` for a law that flies on the IMU or not; an optional gain the report's profile lacks is zero)."""
    law = LAWS[controller_type]
    names = (*law.default_gains, *law.optional_gains)
    given = {name: section.raw(name) for name in names if section.raw(name) is not None}
    section.reject_unknown()
    if profile == "report" or given.keys() == set(names):
        defaults = {name: law.default_gains.get(name, np.zeros((3, 3))) for name in names}
    else:
        try:
            defaults = law.designed_gains(vehicle, imu)
        except ValueError as error:  # a vehicle that cannot hover
            raise ConfigError(section.prefix, f"the flight profile's gains cannot be designed: {error}",
                              section.source) from None
    gains = {}
    for name in names:
        if name not in given:
            gains[name] = np.array(defaults[name], dtype=float)
        else:
            gains[name] = checked_spd(given[name], section.key(name), section.source,
                                      semidefinite=name in law.optional_gains)
    return gains


def _compensation(scenario: Scenario, controller: Section, vehicle: Vehicle,
                  feedforward: str = geometric.MEASURED_FEEDFORWARD) -> CompensationConfig | None:
    """``controller.compensation``: None for ``none``; for ``estimate`` the observer's filter (the scenario's
    ``estimator`` c0 and r), sample time and the contact surfaces, and whether the estimate's rates turn ``R_d``
    (the geometric law's ``feedforward: measured`` only: with ``reference`` its rates are the reference's
    alone). Refused when the estimator is off."""
    mode = controller.string("compensation", "none", choices=COMPENSATION_MODES)
    if mode == "none":
        return None
    from fsr_estimation.config.estimator_config import estimator_config

    estimation = estimator_config(scenario)
    if not estimation.enabled:
        raise controller.error("compensation", "'estimate' needs the estimator: set estimator.enabled: true "
                                               "(or controller.compensation: none)")
    sim = simulation_config(scenario)
    surfaces = pack_surfaces(sim.environment, vehicle)
    if estimation.c0 * sim.control_period > MAX_C0_PERIOD:
        raise controller.error("compensation", f"estimator.c0 * control period must be <= {MAX_C0_PERIOD:g} with "
                                               f"compensation (the compensated loop diverges from about 1), got "
                                               f"{estimation.c0:g} * {sim.control_period:g} s; lower estimator.c0")
    return CompensationConfig(estimation.c0, estimation.r, sim.control_period, surfaces, estimation.rotor_state,
                              rates=feedforward == geometric.MEASURED_FEEDFORWARD)


def controller_settings(scenario: Scenario, vehicle: Vehicle, sim: SimulationConfig) -> dict[str, Any]:
    """The ``controller`` section of ``scenario`` validated for its nominal ``vehicle`` and plant side ``sim``: the
    :class:`ControllerConfig` fields it sets (the others are the trajectory's and the plant's)."""
    actuation = sim.actuation
    controller = scenario.section("controller")
    default_type = "voliro" if vehicle.fully_actuated else "geometric"
    controller_type = controller.string("type", default_type, choices=tuple(LAWS))
    law = LAWS[controller_type]
    check_actuation(controller_type, law.fully_actuated, vehicle, lambda reason: controller.error("type", reason))
    if law.fully_actuated and actuation == "wrench":
        raise controller.error("type", f"{controller_type} allocates its 6-D wrench to the rotors: it needs "
                                       "'actuation: rotors'")
    profile = controller.string("profile", PROFILES[0], choices=PROFILES)
    imu = False
    if controller_type == "geometric":
        imu = controller.boolean("use_imu", profile == "flight" and sim.imu.enabled)
        if imu and not sim.imu.enabled:
            raise controller.error("use_imu", "the vehicle has no IMU: set sensors.imu (e.g. sensors.preset: onboard) "
                                          "or controller.use_imu: false")
    elif controller.has("use_imu"):
        raise controller.error("use_imu", f"only the geometric law has it, not {controller_type}")
    gains = _gains(controller.section("gains"), controller_type, profile, vehicle, imu)
    canted = vehicle.fully_actuated and not vehicle.has_servos  # fixed rotors: clamped rotor by rotor
    allocation = controller.string("allocation", "clamp" if canted else DEFAULT_ALLOCATION,
                                   choices=ALLOCATION_STRATEGIES)
    if canted and allocation == "priority":
        raise controller.error("allocation", f"'{vehicle.name}' is fully actuated with fixed rotors: only 'clamp' "
                                             "(the priority rules are for thrust-and-torque vehicles)")
    air_mode = controller.boolean("air_mode", True)
    acceleration_filter_hz = controller.number("acceleration_filter_hz", 0.0, minimum=0.0)
    feedforward, integral_limit, filter_hz = PROFILE_FEEDFORWARD[profile], 0.0, 0.0
    if controller_type == "geometric":
        feedforward = controller.string("feedforward", feedforward, choices=geometric.FEEDFORWARDS)
    elif controller.has("feedforward"):
        raise controller.error("feedforward", f"only the geometric law has it, not {controller_type}")
    if controller_type in ("geometric", "indi"):
        integral_limit = controller.number("integral_limit", INTEGRAL_LIMIT_SHARE * vehicle.weight,
                                           strictly_positive=True)
    elif controller.has("integral_limit"):
        raise controller.error("integral_limit", f"only the geometric and indi laws have it, not {controller_type}")
    if controller_type == "indi":
        filter_hz = controller.number("filter_hz", indi.DEFAULT_FILTER_HZ, strictly_positive=True)
        if filter_hz >= 0.5 / sim.control_period:
            raise controller.error("filter_hz", f"must be below the Nyquist frequency of the control rate, "
                                                f"{0.5 / sim.control_period:g} Hz, got {filter_hz:g}")
    elif controller.has("filter_hz"):
        raise controller.error("filter_hz", f"only the indi law has it, not {controller_type}")
    if law.needs_imu and not sim.imu.enabled:
        raise controller.error("type", f"{controller_type} needs the vehicle's IMU: set sensors.imu (e.g. "
                                       f"sensors.preset: ideal)")
    if law.needs_rotor_state and actuation != "rotors":
        raise controller.error("type", f"{controller_type} needs the rotors' speeds: it needs 'actuation: rotors'")
    angular_feedforward = "consistent"
    secondary = SecondaryObjectiveConfig()
    if controller_type == "voliro":
        angular_feedforward = controller.string("angular_feedforward", "consistent",
                                                choices=voliro.ANGULAR_FEEDFORWARDS)
        objective = controller.section("secondary_objective")
        secondary = SecondaryObjectiveConfig(
            type=objective.string("type", "none", choices=SECONDARY_TYPES),
            exponent=objective.integer("exponent", 8, minimum=4),
            iterations=objective.integer("iterations", 3, minimum=1),
        )
        if secondary.exponent % 2:
            raise objective.error("exponent", f"must be an even integer >= 4, got {secondary.exponent}")
        objective.reject_unknown()
    compensation = _compensation(scenario, controller, vehicle, feedforward)
    if compensation is not None and law.needs_imu:
        raise controller.error("compensation", f"{controller_type} cancels the external wrench its sensors measure "
                                               "itself: use controller.compensation: none")
    measures = law.needs_imu  # a law that measures the external wrench measures the aerodynamics with it
    aerodynamics = controller.string("aerodynamics", "none" if vehicle.has_servos or measures
                                     else PROFILE_AERODYNAMICS[profile], choices=AERODYNAMICS_MODES)
    if aerodynamics == "model" and vehicle.has_servos:
        raise controller.error("aerodynamics", f"'model' is for fixed rotors; '{vehicle.name}' tilts its rotors")
    if aerodynamics == "model" and measures:
        raise controller.error("aerodynamics", f"{controller_type} measures the aerodynamics with the rest of the "
                                               "external wrench: use controller.aerodynamics: none")
    controller.reject_unknown()
    odometry = sim.odometry_noise
    return {"type": controller_type, "gains": gains, "angular_feedforward": angular_feedforward, "profile": profile,
            "feedforward": feedforward, "integral_limit": integral_limit, "secondary_objective": secondary,
            "allocation": allocation, "compensation": compensation, "air_mode": air_mode,
            "acceleration_filter_hz": acceleration_filter_hz, "aerodynamics": aerodynamics, "filter_hz": filter_hz,
            "odometry_measured": odometry.enabled or odometry.delay_steps > 0 or odometry.every_steps > 1,
            "odometry_delay_steps": odometry.delay_steps, "use_imu": imu}


def controller_config(scenario: Scenario) -> ControllerConfig:
    """Validate ``controller`` and ``trajectory`` of ``scenario``; :class:`ConfigError` names file and key."""
    vehicle = load_vehicle_for(scenario)
    actuation = scenario.data.get("actuation", "rotors")
    sim = simulation_config(scenario)
    settings = controller_settings(scenario, vehicle, sim)
    section = scenario.section("trajectory")
    trajectory = trajectory_config(section, vehicle, sim.initial.position)
    config = ControllerConfig(**settings, waypoints=trajectory.waypoints, goal_duration=trajectory.goal_duration,
                              source=scenario.source, authority_margin=trajectory.authority_margin,
                              feasibility=trajectory.feasibility, path=trajectory.path,
                              trajectory_kind=trajectory.kind, control_period=sim.control_period,
                              rotor_state=sim.publishes_rotor_state)
    # Every leg checked before take-off, from the scenario's initial state: refused here, listed otherwise.
    try:
        plan = config.trajectory(vehicle, actuation, sim.initial.position, sim.initial.rotation)
    except InfeasibleReferenceError as error:
        key = {"approach": "approach_duration", "path": trajectory.timing_key}.get(error.part,
                                                                                 f"waypoints.{error.waypoint}")
        raise section.error(key, str(error)) from None
    except PathError as error:
        raise section.error(error.key, str(error)) from None
    return replace(config, plan_adjustments=tuple(plan.adjustments), plan_end_time=plan.end_time)
