"""The ``estimator`` section of a scenario (validated; unknown keys refused with a typo hint).

```yaml
estimator:
  enabled: true
  c0: 10.0                            # > 0 [rad/s]
  r: 1                                # integer >= 1
  mass: 1.5                           # optional model mass [kg] (default: the scenario's vehicle)
  inertia: [1.2416, 1.2416, 2.4832]   # optional, diagonal or 3x3 [kg m^2] (default: the vehicle's)
  input: commanded                    # the actuator wrench the observer takes: commanded (wrench_cmd, the
                                      # default) | measured (the rotors' measured speeds and tilts, rotor_state,
                                      # through the nominal allocation: a motor lag is then no disturbance)
```

``input: measured`` needs rotor actuation. Where the plant's rotors do not lag (no ``rotor_state``: they follow
their commands within the step) the measured wrench is the commanded one, and the observer takes ``wrench_cmd``.
The controller's own observer (``controller.compensation: estimate``) takes the same input.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_sim.config.scenario import Scenario, load_vehicle_for, simulation_config
from fsr_sim.config.validation import checked_spd

SECTION = "estimator"
KEYS = ("enabled", "c0", "r", "mass", "inertia", "input")
INPUTS = ("commanded", "measured")  # estimator.input: the first is the default
DEFAULT_C0 = 10.0  # rad/s: the report's choice
DEFAULT_R = 1


@dataclass(frozen=True)
class EstimatorConfig:
    """Validated estimator settings: model mass [kg], inertia (3, 3) [kg m^2], c0 [rad/s], r."""

    enabled: bool
    mass: float
    inertia: np.ndarray
    c0: float
    r: int
    input: str = INPUTS[0]  # commanded | measured
    rotor_state: bool = False  # the observer takes rotor_state (input measured, and the simulator publishes it)


def estimator_config(scenario: Scenario) -> EstimatorConfig:
    """Parse ``scenario``'s ``estimator`` section; defaults for mass and inertia from its vehicle."""
    section = scenario.section(SECTION)
    section.reject_unknown(KEYS)  # typos first, before the values are checked
    enabled = section.boolean("enabled", True)
    c0 = section.number("c0", DEFAULT_C0, strictly_positive=True)
    r = section.integer("r", DEFAULT_R, minimum=1)
    if section.has("mass") and section.has("inertia"):
        mass = section.number("mass", strictly_positive=True)
        inertia = checked_spd(section.raw("inertia"), section.key("inertia"), scenario.source)
    else:
        vehicle = load_vehicle_for(scenario)
        mass = section.number("mass", vehicle.mass, strictly_positive=True)
        inertia = checked_spd(section.raw("inertia", vehicle.inertia), section.key("inertia"), scenario.source)
    source = section.string("input", INPUTS[0], choices=INPUTS)
    rotor_state = False
    if source == "measured":
        sim = simulation_config(scenario)
        if sim.actuation != "rotors":
            raise section.error("input", f"'measured' takes the rotors' speeds (rotor_state): it needs 'actuation: "
                                         f"rotors', got '{sim.actuation}'")
        rotor_state = sim.publishes_rotor_state
    section.reject_unknown()
    return EstimatorConfig(enabled=enabled, mass=mass, inertia=inertia, c0=c0, r=r, input=source,
                           rotor_state=rotor_state)
