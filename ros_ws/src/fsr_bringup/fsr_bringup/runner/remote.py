"""One flight over several hosts: which nodes this host runs, who is still missing, when the flight ended.

``fsr-fly SCENARIO --network --domain-id N --nodes simulator,recorder`` on one host and ``... --nodes
controller,estimator`` on another run one flight: DDS joins the nodes (discovery range SUBNET, or static
peers), the simulator's handshake waits for its odom subscribers and its command publisher wherever they run.

* :func:`parse_node_selection` turns ``--nodes`` into the set of process names this host starts: a role
  (``simulator``, ``controller``, ``estimator``, ``recorder``) selects that node of every vehicle, a
  process name (``uav2/controller``) one vehicle's node.
* the flight watcher (:mod:`fsr_bringup.runner.watcher`) follows each vehicle's latched ``sim_status`` (a
  host without the simulator ends its nodes when the flight's final status arrives) and the graph's node
  names (:func:`expected_node_paths`: which nodes of other hosts have not been discovered yet).
"""

from __future__ import annotations

from collections.abc import Iterable

ROLES = ("simulator", "controller", "estimator", "recorder")
RECORDER_NODE = "fsr_recorder"  # the recorder's ROS node name (its process is called "recorder")


def parse_node_selection(text: str, process_names: Iterable[str]) -> set[str]:
    """The process names selected by ``--nodes`` (comma-separated roles or process names).

    ``process_names`` are the run's processes (``recorder``, ``simulator`` or ``uav1/simulator``, ...).
    Raises ``ValueError`` naming an entry that selects nothing.
    """
    names = list(process_names)
    selected: set[str] = set()
    entries = [entry.strip().strip("/") for entry in text.split(",") if entry.strip()]
    if not entries:
        raise ValueError("--nodes needs at least one of " + ", ".join(ROLES))
    for entry in entries:
        matches = {n for n in names if n == entry or n.rsplit("/", 1)[-1] == entry}
        if not matches:
            raise ValueError(f"--nodes: '{entry}' is not a node of this run (nodes: {', '.join(names)})")
        selected |= matches
    return selected


def expected_node_paths(process_names: Iterable[str]) -> dict[str, str]:
    """{ROS node path: process name} of the run's nodes (``uav1/controller`` -> ``/uav1/controller``)."""
    paths = {}
    for name in process_names:
        if name == "recorder":
            paths["/" + RECORDER_NODE] = name
        else:
            paths["/" + name] = name
    return paths
