"""The Python API: fly a scenario in one process and get the flight as arrays.

    from fsr_bringup import simulate
    run = simulate("ex4_geometric", set={"controller.gains.k_p": [10, 10, 50]}, duration=10.0)
    run.time, run.position, run.rotation, run.force_cmd, run.estimate_force_body   # numpy arrays
    run.save_mcap("runs/ex4.mcap")                                              # what fsr-fly --in-process writes

``simulate`` is what ``fsr-fly --in-process`` runs (:func:`fsr_bringup.runner.in_process_flight.fly_in_process`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from fsr_bringup.runner.in_process_flight import FlightRun, fly_in_process
from fsr_bringup.runner.scenario_check import CheckedScenario, check_scenario
from fsr_sim.config.scenario import Scenario, load_scenario, scenario_from_mapping
from fsr_sim.contract import recording_selection

if TYPE_CHECKING:
    from fsr_bringup.live.server import LiveServer


def simulate(
    scenario: str | Path | dict[str, Any] | Scenario,
    set: dict[str, Any] | None = None,  # noqa: A002 - the name of fsr-fly's --set
    duration: float | None = None,
    record: str | Path | None = None,
    stop: Callable[[], str | None] | None = None,
    progress: Callable[[float, float], None] | None = None,
    record_topics: str | None = None,
    live: LiveServer | None = None,
) -> FlightRun:
    """Fly a scenario in one process (the node graph's modules and lockstep, without DDS).

    Parameters
    ----------
    scenario : str, Path, dict or Scenario
        A built-in scenario name (``ex4_geometric``), a YAML path, or the scenario as a mapping.
    set : dict, optional
        ``{dotted key: value}`` overrides, as ``fsr-fly --set`` (``{"controller.gains.k_p": [10, 10, 50]}``).
    duration : float, optional
        Flight duration [s] (overrides the scenario's).
    record : str or Path, optional
        Also write the MCAP recording there (as ``fsr-fly --in-process`` does).
    stop : callable, optional
        Polled between chunks of steps (every simulated second); returning a reason (e.g. a signal name) ends
        the flight there as interrupted.
    progress : callable, optional
        Called after each chunk with the simulated time [s] of the last state flown and the wall time [s] the
        loop has taken.
    record_topics : str, optional
        With ``record``: record only these topics, comma-separated (``"odom,reference"``; ``sim_status`` is
        always kept), as ``fsr-fly --record-topics``.
    live : LiveServer, optional
        Serve the flight live as it flies, paced at the scenario's ``lockstep.real_time_factor`` (as ``fsr-fly
        --live``): ``with fsr_bringup.live.serve(8765) as live: simulate("ex4_geometric", live=live)``, then connect
        Foxglove to ``ws://localhost:8765``.

    Returns
    -------
    FlightRun
        Arrays over the published states (``time``, ``position``, ``rotation``, ``force_cmd``, ...).

    Raises
    ------
    fsr_sim.config.validation.ConfigError
        A ``ValueError`` naming the key and the reason, for any invalid value (nothing is flown).
    """
    checked = load_checked(scenario, fixed_values(set, duration))
    for warning in checked.warnings:
        warnings.warn(f"{checked.simulation.name}: {warning}", UserWarning, stacklevel=2)
    if record is not None:
        Path(record).parent.mkdir(parents=True, exist_ok=True)
    topics = None if record_topics is None else recording_selection(record_topics)
    return fly_in_process(checked.scenario, None if record is None else Path(record), stop=stop, progress=progress,
                          record_topics=topics, live=live)


def fixed_values(values: dict[str, Any] | None, duration: float | None) -> dict[str, Any]:
    """``{dotted key: value}`` every flight has (``fsr-fly --set``'s), with the ``duration`` [s] where given."""
    return {**(values or {}), **({} if duration is None else {"duration": float(duration)})}


def load_checked(scenario: str | Path | dict[str, Any] | Scenario, values: dict[str, Any]) -> CheckedScenario:
    """:func:`~fsr_bringup.runner.scenario_check.check_scenario` of ``scenario`` (as :func:`simulate` takes it: a
    built-in name, a YAML path, a mapping or a Scenario) with ``values`` (:func:`fixed_values`) over it."""
    if isinstance(scenario, Scenario):
        return check_scenario(scenario_from_mapping(scenario.data, scenario.source, scenario.base_dir, values=values))
    if isinstance(scenario, dict):
        return check_scenario(scenario_from_mapping(scenario, values=values))
    return check_scenario(load_scenario(scenario, values=values))
