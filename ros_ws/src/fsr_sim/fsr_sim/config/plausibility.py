"""Values a scenario accepts but that are likely a slip of units: warnings, not errors (a user may mean them).

Each is checked against the vehicle's own numbers (the nominal vehicle file the controller and the estimator
use) or against what any multirotor has:

* the true plant's mass or inertia more than :data:`MASS_FACTOR` times (or less than its inverse) the vehicle's
  (``plant.mass: 1200`` for a 1.2 kg vehicle: grams for kilograms);
* a rotor or servo time constant above :data:`MAX_TIME_CONSTANT_S` (real motors and servos take 5-100 ms:
  ``30`` meant as 30 ms);
* with rotor actuation, rotors that cannot lift the plant: the largest thrust along ``-z_b`` at full speed (each
  rotor's along its thrust axis at tilt 0; a tilting rotor can turn to the vertical) below its weight.
"""

from __future__ import annotations

import numpy as np

from fsr_sim.config.scenario import SimulationConfig
from fsr_sim.core.rigid_body import GRAVITY

MASS_FACTOR = 3.0  # the true mass or inertia beyond this factor of the vehicle's: a warning
MAX_TIME_CONSTANT_S = 0.5  # s: a rotor or servo lag beyond this


def plausibility_warnings(config: SimulationConfig) -> list[str]:
    """The warnings of the module docstring for a validated plant side (empty: nothing looks wrong)."""
    nominal, plant = config.vehicle, config.plant_vehicle
    warnings = []
    ratio = plant.mass / nominal.mass
    if not 1.0 / MASS_FACTOR <= ratio <= MASS_FACTOR:
        warnings.append(f"plant.mass {plant.mass:g} kg is {ratio:.3g} times {nominal.name}'s {nominal.mass:g} kg (the "
                        f"controller's model): a slip of units?")
    inertia_ratio = np.trace(plant.inertia) / np.trace(nominal.inertia)
    if not 1.0 / MASS_FACTOR <= inertia_ratio <= MASS_FACTOR:
        warnings.append(f"plant.inertia is {inertia_ratio:.3g} times {nominal.name}'s (trace "
                        f"{np.trace(plant.inertia):g} against {np.trace(nominal.inertia):g} kg m^2): a slip of units?")
    for name, value in (("rotor_time_constant", plant.rotor_time_constant),
                        ("tilt_time_constant", plant.tilt_time_constant)):
        if value > MAX_TIME_CONSTANT_S:
            warnings.append(f"{name} {value:g} s: real motors and servos take 0.005-0.1 s (did you mean "
                            f"{value / 1000:g} s, {value:g} ms?)")
    if config.actuation == "rotors":
        lift = plant.c_f * plant.rotor_speed_max ** 2
        vertical = np.ones(plant.rotor_count) if plant.has_servos else np.clip(-plant.thrust_axes[:, 2], 0.0, None)
        thrust_max = float(lift * np.sum(vertical))
        weight = plant.mass * GRAVITY
        if thrust_max < weight:
            warnings.append(f"the rotors give at most {thrust_max:.3g} N of thrust at full speed for the plant's "
                            f"{weight:.3g} N weight ({plant.mass:g} kg): it cannot hover")
    return warnings
