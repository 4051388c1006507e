"""Why a flight went wrong, where fsr can tell: a diagnosis for a flight that diverged or whose rotors sat at a
limit for a large share of its steps (:data:`SATURATED_SHARE`).

What it gives (``metrics.json`` ``diagnosis``; the summary's *Diagnosis* section):

* the first saturated step: when the law's demand first gave way at the rotor limits and on which body axis
  (``wrench_shortfall``: the axis with the largest shortfall then), else the first rotor command at a limit;
* the share of steps with a rotor command at a speed limit (and of the tilts at theirs);
* the likely causes fsr can name from the scenario, each with the key that changes it:

  - noisy odometry (``sensors.odometry``) into the geometric law's measured-acceleration feed-forward
    (``controller.feedforward: measured``, the report's) without a low-pass (``controller.acceleration_filter_hz:
    0``): the differentiated noise drives the attitude rates, the torques switch between the rotor limits;
  - a gain beyond the authority: a position or attitude gain more than :data:`GAIN_FACTOR` times the one designed
    from the vehicle's authority (``controller.profile: flight``, :mod:`fsr_control.design.gain_design`);
  - a motor lag beside a fast observer: with ``controller.compensation: estimate``, an observer rate ``c0``
    faster than ``1 / (3 tau)`` of the rotors' time constant ``tau`` (``plant.rotor_time_constant``): the
    estimate cancels the lag's own error.

None for a flight that neither diverged nor saturated much.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from fsr_bringup.analysis.load import RecordedFlight
from fsr_sim.contract import DIVERGED, SIM_STATUS, SimStatus
from fsr_sim.model.rotors import SHORTFALL_TOLERANCE, WRENCH_AXES

SATURATED_SHARE = 0.05  # a flight with more of its steps at a rotor limit gets a diagnosis
GAIN_FACTOR = 2.0  # a gain this many times the designed one (on some axis) is beyond the authority
LAG_FACTOR = 3.0  # an observer faster than 1 / (LAG_FACTOR tau) sees the motor lag as a disturbance


def _first_shortfall(flight: RecordedFlight) -> dict[str, Any] | None:
    shortfall = flight.wrench_shortfall
    if shortfall is None or not len(shortfall.t):
        return None
    values = np.abs(np.hstack((shortfall.force, shortfall.torque)))
    gave_way = np.flatnonzero((values > SHORTFALL_TOLERANCE).any(axis=1))
    if not gave_way.size:
        return None
    k = int(gave_way[0])
    axis = int(np.argmax(values[k]))
    return {"step": k, "time_s": float(shortfall.t[k]), "axis": WRENCH_AXES[axis], "shortfall": float(values[k, axis])}


def _gain_causes(flight: RecordedFlight) -> list[dict[str, str]]:
    """Gains more than GAIN_FACTOR times those designed from the vehicle (rotor actuation only: a wrench has no
    authority limit)."""
    from fsr_control.design.gain_design import design_gains

    controller, config = flight.controller, flight.config
    if controller is None or config is None or config.actuation != "rotors":
        return []
    try:
        design = design_gains(config.vehicle, imu=controller.use_imu)
    except ValueError:
        return []
    designed = design.wrench_gains() if controller.type == "geometric" else design.acceleration_gains()
    causes = []
    for name, gain in controller.gains.items():
        if name not in designed or name == "k_i":
            continue
        used, reference = np.diag(np.asarray(gain, float)), np.diag(designed[name])
        ratio = used / np.where(reference > 0.0, reference, np.inf)
        if np.max(ratio) > GAIN_FACTOR:
            axis = int(np.argmax(ratio))
            causes.append({
                "cause": f"gain beyond the authority: {name} = {used[axis]:.4g} on axis {'xyz'[axis]} is "
                         f"{ratio[axis]:.1f} times the {reference[axis]:.4g} designed from the vehicle's authority",
                "key": f"controller.gains.{name} (or controller.profile: flight)"})
    return causes


def likely_causes(flight: RecordedFlight) -> list[dict[str, str]]:
    """The causes of the module docstring the scenario shows (``cause``, ``key``)."""
    controller, config = flight.controller, flight.config
    causes: list[dict[str, str]] = []
    if controller is not None and config is not None:
        if (config.odometry_noise.enabled and controller.type == "geometric" and controller.feedforward == "measured"
                and controller.acceleration_filter_hz == 0.0):
            causes.append({
                "cause": "noisy odometry (sensors.odometry) into the measured-acceleration feed-forward without a "
                         "filter: the differentiated noise drives the commanded attitude rates",
                "key": "controller.acceleration_filter_hz (e.g. 2) or controller.feedforward: reference"})
        causes += _gain_causes(flight)
        tau = config.plant_vehicle.rotor_time_constant
        if controller.compensation is not None and tau > 0.0 and controller.compensation.c0 * LAG_FACTOR * tau > 1.0:
            causes.append({
                "cause": f"a motor lag beside a fast observer: c0 = {controller.compensation.c0:g} rad/s is faster "
                         f"than 1 / (3 tau) = {1.0 / (LAG_FACTOR * tau):.3g} rad/s of the rotors' {tau:g} s lag",
                "key": "estimator.c0 (or plant.rotor_time_constant)"})
    return causes


def diagnosis(flight: RecordedFlight, metrics: dict[str, Any]) -> dict[str, Any] | None:
    """The diagnosis of a flight (module docstring) from its metrics (:func:`~fsr_bringup.analysis.metrics.
    flight_metrics`' so far); None when it neither diverged nor saturated much."""
    status = SimStatus.from_dict(metrics.get(SIM_STATUS.name))
    saturation = metrics.get("saturation") or {}
    speed = saturation.get("rotor_speed") or {}
    share = float(speed.get("fraction") or 0.0)
    tilt = saturation.get("tilt") or {}
    diverged = status is not None and status.state == DIVERGED
    if not diverged and share <= SATURATED_SHARE:
        return None
    first = _first_shortfall(flight)
    if first is None and speed.get("steps"):
        first = {"step": None, "time_s": speed.get("first_time_s"), "axis": None, "shortfall": None,
                 "rotor": speed.get("worst_rotor")}
    return {
        "why": status.reason if diverged else f"{share:.0%} of the steps at a rotor limit",
        "first_saturation": first,
        "rotor_limit_share": share if speed else None,
        "tilt_limit_share": float(tilt["fraction"]) if tilt else None,
        "likely_causes": likely_causes(flight),
    }
