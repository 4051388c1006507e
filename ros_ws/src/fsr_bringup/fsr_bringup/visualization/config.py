"""The scenario's ``visualization`` section: the markers a recording carries.

    visualization:
      markers: true        # write `markers` (visualization_msgs/MarkerArray) into the recording
      marker_rate: 50.0    # [Hz] of simulated time (rounded to a whole number of control steps)

Nothing here changes the flight: the markers are drawn from what the nodes published.
"""

from __future__ import annotations

from dataclasses import dataclass

from fsr_sim.config.scenario import Scenario
from fsr_sim.contract import MARKERS

SECTION = "visualization"
KEYS = (MARKERS.name, "marker_rate")  # the key that turns the markers on or off is the topic's name
DEFAULT_MARKER_RATE_HZ = 50.0


@dataclass(frozen=True)
class VisualizationConfig:
    markers: bool = True
    marker_rate: float = DEFAULT_MARKER_RATE_HZ  # [Hz] of simulated time

    def marker_stride(self, control_period: float) -> int:
        """Markers every this many control steps (at least one)."""
        return max(1, int(round(1.0 / (self.marker_rate * control_period))))


def visualization_config(scenario: Scenario) -> VisualizationConfig:
    """Parse ``scenario``'s ``visualization`` section (module docstring)."""
    section = scenario.section(SECTION)
    section.reject_unknown(KEYS)
    config = VisualizationConfig(markers=section.boolean(MARKERS.name, True),
                                 marker_rate=section.number("marker_rate", DEFAULT_MARKER_RATE_HZ,
                                                            strictly_positive=True))
    section.reject_unknown()
    return config
