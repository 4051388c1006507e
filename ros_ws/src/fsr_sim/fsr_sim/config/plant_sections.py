"""The plant-side sections of a scenario that describe the world: ``environment`` and ``disturbances``.

Each parser reads one section with :class:`fsr_sim.config.validation.Section` (unknown keys refused with a
typo hint) and returns the model objects of :mod:`fsr_sim.model.environment` and
:mod:`fsr_sim.model.disturbances`.
"""

from __future__ import annotations

import numpy as np

from fsr_sim.config.validation import Section, checked_array
from fsr_sim.model.disturbances import ZERO3, DisturbanceProfile
from fsr_sim.model.environment import GROUND_MODELS, Environment, Surface
from fsr_sim.model.turbulence import DrydenTurbulence


def environment_from_section(section: Section) -> Environment:
    """Parse the scenario's ``environment`` section (see module docstring); unknown keys are refused."""
    ground = section.section("ground")
    ground_surface = Surface(
        enabled=ground.boolean("enabled", True),
        height=ground.number("height", 0.0),
        effect=ground.boolean("effect", True),
        max_ratio=ground.number("max_ratio", 1.5, minimum=1.0),
    )
    ground_model = ground.string("model", "single", choices=GROUND_MODELS)
    body_factor = ground.number("body_factor", 2.0, minimum=0.0)
    ground.reject_unknown()
    ceiling = section.section("ceiling")
    ceiling_surface = Surface(
        enabled=ceiling.boolean("enabled", False),
        height=ceiling.number("height", -3.0),
        effect=ceiling.boolean("effect", True),
        max_ratio=ceiling.number("max_ratio", 1.5, minimum=1.0),
    )
    k1 = ceiling.number("k1", 6.924, strictly_positive=True)
    k2 = ceiling.number("k2", 0.03782, minimum=0.0)
    ceiling.reject_unknown()
    section.reject_unknown()
    if ground_surface.enabled and ceiling_surface.enabled and ceiling_surface.height >= ground_surface.height:
        raise section.error("ceiling.height", "the ceiling must be above the ground (smaller NED z)")
    return Environment(ground_surface, ceiling_surface, ground_model, body_factor, k1, k2)



def disturbance_from_section(section: Section) -> DisturbanceProfile | DrydenTurbulence:
    """Parse one entry of the scenario's ``disturbances`` list (unknown keys refused)."""
    kind = section.string("kind", choices=("constant", "step", "sinusoid", "table", "dryden"))
    if kind == "dryden":
        turbulence = DrydenTurbulence(
            wind_speed=section.number("wind_speed", minimum=0.0),
            altitude=section.number("altitude", strictly_positive=True),
            airspeed=section.number("airspeed", strictly_positive=True) if section.has("airspeed") else None,
            mean=section.vector("mean", 3, [0.0, 0.0, 0.0]),
            seed=section.integer("seed", 0, minimum=0, maximum=2**32 - 1),
        )
        section.reject_unknown()
        return turbulence
    frame = section.string("frame", "world", choices=("world", "body"))
    if kind == "table":
        times = section.raw("time")
        if not isinstance(times, list) or len(times) < 1:
            raise section.error("time", "must be a non-empty list of times [s]")
        times_array = checked_array(times, (len(times),), section.key("time"), section.source)
        if np.any(np.diff(times_array) <= 0.0):
            raise section.error("time", "must be strictly increasing")
        shape = (len(times), 3)
        zeros = np.zeros(shape).tolist()
        force = checked_array(section.raw("force", zeros), shape, section.key("force"), section.source)
        torque = checked_array(section.raw("torque", zeros), shape, section.key("torque"), section.source)
        section.reject_unknown()
        return DisturbanceProfile(kind, frame, force, torque, times=times_array)
    force = section.vector("force", 3, [0.0, 0.0, 0.0])
    torque = section.vector("torque", 3, [0.0, 0.0, 0.0])
    start = section.number("start", 0.0, minimum=0.0) if kind != "constant" else 0.0
    end = section.number("end") if kind != "constant" and section.has("end") else float("inf")
    if end <= start:
        raise section.error("end", f"must be after start ({start}), got {end}")
    frequency = phase = 0.0
    offset_force = offset_torque = ZERO3
    if kind == "sinusoid":
        frequency = section.number("frequency_hz", strictly_positive=True)
        phase = np.deg2rad(section.number("phase_deg", 0.0))
        offset_force = section.vector("offset_force", 3, [0.0, 0.0, 0.0])
        offset_torque = section.vector("offset_torque", 3, [0.0, 0.0, 0.0])
    section.reject_unknown()
    return DisturbanceProfile(
        kind, frame, force, torque, start, end, frequency, phase, offset_force, offset_torque
    )
