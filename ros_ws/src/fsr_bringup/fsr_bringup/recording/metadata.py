"""The scenario a recording's metadata holds (:data:`fsr_sim.recording.reader.SCENARIO_METADATA`), for one vehicle
namespace."""

from __future__ import annotations

from pathlib import Path

from fsr_sim.config.scenario import Scenario
from fsr_sim.config.validation import ConfigError, parse_yaml_mapping


def scenario_from_text(text: str | None, namespace: str, source: str, base_dir: Path) -> tuple[Scenario | None,
                                                                                               str | None]:
    """``(scenario, note)`` of the vehicle under ``namespace`` (``/`` or ``/uav1``) in a recorded scenario text: a
    single vehicle's scenario, or the member of a fleet (``fleet: [{namespace, scenario}, ...]``, what ``fsr-fly``
    records for several vehicles). The scenario is None, with a note saying why, when there is none."""
    if text is None:
        return None, "no scenario in the recording's metadata: vehicle limits, true mass and surfaces unknown"
    try:
        data = parse_yaml_mapping(text, source)
    except ConfigError as error:
        return None, f"scenario in the metadata cannot be read: {error}"
    if isinstance(data.get("fleet"), list):
        members = {"/" + str(m.get("namespace", "")).strip("/"): m.get("scenario") for m in data["fleet"]
                   if isinstance(m, dict)}
        data = members.get(namespace)
        if not isinstance(data, dict):
            return None, (f"the fleet in the metadata has no vehicle under {namespace} (it has "
                          f"{', '.join(sorted(members)) or 'none'}): vehicle limits, true mass and surfaces unknown")
        source = f"{source}, fleet member {namespace}"
    return Scenario(data=data, source=source, base_dir=base_dir), None
