"""What ``fsr-fly`` knows of a running flight: the events of its watcher process, one JSON line each.

The watcher (:mod:`fsr_bringup.runner.watcher_node`, why it is a process of its own is said there) reports
the simulated time, every vehicle's ``sim_status`` and the graph's nodes. :class:`FlightWatcher` keeps the
latest of each; :meth:`FlightWatcher.feed` is called from the thread that reads the watcher's output and
:meth:`FlightWatcher.wait` wakes the supervising loop when something arrived.
"""

from __future__ import annotations

import json
import sys
import threading

from fsr_sim.contract import SimStatus

WATCHER_PROCESS = "flight_watcher"  # its name among the run's processes (log: <logs>/flight_watcher.log)


def watcher_command(namespaces: list[str]) -> list[str]:
    """The watcher's command line for these vehicles' namespaces."""
    command = [sys.executable, "-m", "fsr_bringup.runner.watcher_node"]
    for namespace in namespaces:
        command += ["--namespace", namespace]
    return command


class FlightWatcher:
    """The latest simulated time, ``sim_status`` per namespace and node list reported by the watcher."""

    def __init__(self, namespaces: list[str]) -> None:
        self.namespaces = list(namespaces)
        self.sim_time = 0.0
        self.first: tuple[float, float] | None = None  # (wall monotonic [s], sim time [s]) of the first progress
        self.last: tuple[float, float] | None = None
        self.statuses: dict[str, SimStatus | None] = {}  # None: a message that was not a status
        self.node_paths: set[str] | None = None  # None until the first list arrived
        self.lock = threading.Lock()
        self.changed = threading.Event()

    def feed(self, line: str) -> bool:
        """Take one line of the watcher's output; True if it was an event (else it is a log line)."""
        if not line.startswith("{"):
            return False
        try:
            event = json.loads(line)
        except ValueError:
            return False
        if not isinstance(event, dict):
            return False
        try:
            with self.lock:
                if "progress" in event:
                    now, sim_time = float(event["at"]), float(event["progress"])
                    self.sim_time = sim_time
                    if self.first is None:
                        self.first = (now, sim_time)
                    self.last = (now, sim_time)
                elif "status" in event:
                    self.statuses[str(event["status"])] = SimStatus.from_dict(event.get("value"))
                elif "nodes" in event:
                    self.node_paths = {str(path) for path in event["nodes"]}
                else:
                    return False
        except (KeyError, TypeError, ValueError):
            return False  # not one of the watcher's events: keep it as a log line
        self.changed.set()
        return True

    def wait(self, timeout: float) -> None:
        """Return when an event arrived since the last call, or after ``timeout`` s."""
        self.changed.wait(timeout)
        self.changed.clear()

    @property
    def stepping_rate(self) -> float:
        """Simulated seconds per wall second between the first and the last progress message (NaN before two)."""
        with self.lock:
            if self.first is None or self.last is None or self.last[0] - self.first[0] < 0.05:
                return float("nan")
            return (self.last[1] - self.first[1]) / (self.last[0] - self.first[0])

    def final_statuses(self) -> dict[str, SimStatus] | None:
        """Every vehicle's final ``sim_status`` once all of them ended, else None."""
        with self.lock:
            finals = {ns: self.statuses.get(ns) for ns in self.namespaces}
            return finals if all(status is not None and status.final for status in finals.values()) else None

    def state(self, namespace: str) -> str | None:
        """The ``state`` of the vehicle's last ``sim_status`` (None before the first)."""
        with self.lock:
            status = self.statuses.get(namespace)
            return None if status is None else status.state

    def started(self) -> bool:
        """True once every simulator reported a status (``running`` or a final one)."""
        with self.lock:
            return all(ns in self.statuses for ns in self.namespaces)

    def missing(self, expected: dict[str, str]) -> list[str] | None:
        """Process names of the expected nodes (``{node path: process name}``) not in the graph yet; None
        before the watcher listed the graph once."""
        with self.lock:
            if self.node_paths is None:
                return None
            return [process for path, process in expected.items() if path not in self.node_paths]
