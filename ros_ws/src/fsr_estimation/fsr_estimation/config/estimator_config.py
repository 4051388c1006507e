"""The ``estimator`` section of a scenario (validated; unknown keys refused with a typo hint).

```yaml
estimator:
  enabled: true
  c0: 10.0                            # > 0 [rad/s]
  r: 1                                # integer >= 1
  mass: 1.5                           # optional model mass [kg] (default: the scenario's vehicle)
  inertia: [1.2416, 1.2416, 2.4832]   # optional, diagonal or 3x3 [kg m^2] (default: the vehicle's)
```
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_sim.config.scenario import Scenario, load_vehicle_for
from fsr_sim.config.validation import checked_spd

SECTION = "estimator"
KEYS = ("enabled", "c0", "r", "mass", "inertia")
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
    section.reject_unknown()
    return EstimatorConfig(enabled=enabled, mass=mass, inertia=inertia, c0=c0, r=r)
