"""The flight watcher: the one DDS participant of ``fsr-fly``, in a child process that it reads line by line.

``python -m fsr_bringup.runner.watcher_node [--namespace NS ...]`` (one ``--namespace`` per vehicle, ``''``
for a single vehicle) follows the first vehicle's ``sim_progress`` and every vehicle's latched
``sim_status``, and lists the graph's nodes every ``NODE_LIST_PERIOD`` s. Each event is one JSON line on
stdout (:mod:`fsr_bringup.runner.watcher` reads them):

* ``{"progress": <simulated time [s]>, "at": <time.monotonic() [s] when it arrived>}``
* ``{"status": <namespace>, "value": <the sim_status JSON object>}``
* ``{"nodes": [<node path>, ...]}``

Why a process of its own: deleting a Fast DDS 2.14 participant can deadlock when a discovery callback is
running at that moment, e.g. while the endpoints of nodes that just left are removed, as at the end of a
flight. ``rmw_fastrtps`` deletes it with ``DomainParticipant::set_listener(nullptr)``, which waits for running
callbacks with ``condition_variable::wait_until(steady_clock::time_point::max())``; the wheels' libstdc++
converts that deadline through ``system_clock``, it overflows into the past, and the wait spins
(``system_clock::now()`` in the stack) holding the mutex that the running callback needs to finish (gdb on a
hung process: the main thread in ``set_listener``, a receive thread in ``onWriterDiscovery`` waiting for the
mutex). The call holds the GIL, so nothing in that process can end it. Seen once in CI (a remote host's
``fsr-fly`` hung after its flight), reproduced about once in 130 teardowns by hand. ``fsr-fly`` supervises
flights and must never hang there: a watcher stuck in its teardown is stopped like any node (SIGINT,
SIGTERM, SIGKILL), and :class:`fsr_sim.ros.runtime.TeardownWatchdog` bounds its teardown anyway.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from fsr_sim.contract import SIM_PROGRESS, SIM_STATUS, SimStatus, resolve

NODE_NAME = "fsr_fly_watcher"
NODE_LIST_PERIOD = 1.0  # s between two lists of the graph's nodes


def parse_args(argv: list[str]) -> argparse.Namespace:
    parser = argparse.ArgumentParser(prog="fsr_bringup.runner.watcher_node", description=__doc__.split("\n")[0])
    parser.add_argument("--namespace", action="append", default=[],
                        help="a vehicle's namespace ('' for a single vehicle); repeat for a fleet")
    args = parser.parse_args(argv)
    if not args.namespace:
        args.namespace = [""]
    return args


def emit(event: dict) -> None:
    """One event as one JSON line on stdout."""
    sys.stdout.write(json.dumps(event, separators=(",", ":")) + "\n")
    sys.stdout.flush()


def make_watcher(namespaces: list[str]) -> object:
    """The watcher node (rclpy is imported only here, after run_node configured the environment)."""
    from rclpy.node import Node

    from fsr_sim.ros.message_schema import message_class
    from fsr_sim.ros.qos import qos_of

    class FlightWatcherNode(Node):
        def __init__(self) -> None:
            super().__init__(NODE_NAME, start_parameter_services=False)
            self.create_subscription(message_class(SIM_PROGRESS.type), resolve(SIM_PROGRESS.name, namespaces[0]),
                                     self._on_progress, qos_of(SIM_PROGRESS))
            for namespace in namespaces:
                self.create_subscription(message_class(SIM_STATUS.type), resolve(SIM_STATUS.name, namespace),
                                         lambda msg, ns=namespace: self._on_status(ns, msg.data), qos_of(SIM_STATUS))
            self.create_timer(NODE_LIST_PERIOD, self._list_nodes)
            self.final: dict[str, bool] = dict.fromkeys(namespaces, False)

        def _on_progress(self, msg: object) -> None:  # rosgraph_msgs/Clock
            emit({"progress": msg.clock.sec + msg.clock.nanosec * 1e-9, "at": time.monotonic()})

        def _on_status(self, namespace: str, data: str) -> None:
            status = SimStatus.from_json(data)
            self.final[namespace] = status is not None and status.final
            emit({"status": namespace, "value": None if status is None else status.as_dict()})

        @property
        def flight_over(self) -> bool:
            """Every vehicle's simulator published its final status (fsr-fly stops the watcher then)."""
            return all(self.final.values())

        def _list_nodes(self) -> None:
            emit({"nodes": [f"{ns.rstrip('/')}/{name}" for name, ns in self.get_node_names_and_namespaces()]})

    return FlightWatcherNode()


def main(argv: list[str] | None = None) -> None:
    from fsr_sim.ros.runtime import run_node

    sys.exit(run_node(lambda args: make_watcher(parse_args(args).namespace), argv))


if __name__ == "__main__":
    main()
