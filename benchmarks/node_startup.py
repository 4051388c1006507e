"""How fast a node can be ready on this machine: the floor under the target "each node ready within 0.5 s".

    .venv/bin/python benchmarks/node_startup.py [--repeat 3] [--together 4]

Prints min and median over ``--repeat`` runs of:

* a minimal rclpy node (this file with ``--minimal``: ``import rclpy``, two message types, ``rclpy.init``,
  one node without parameter services, one publisher and one raw subscription), ready time after its
  process started, started alone and ``--together`` at once (the graph starts four nodes at once);
* the import of each fsr node's module alone (``python -c "import ..."``, wall time of the process).

The fsr nodes do this minimum plus their own imports and parameter checks: when the minimal node alone is
already near 0.5 s, or ``--together`` of them share the cores and take longer, the target cannot be met by
the nodes' own code on this machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

NODE_MODULES = ("fsr_sim.nodes.simulator_node", "fsr_control.nodes.controller_node",
                "fsr_estimation.nodes.estimator_node", "fsr_bringup.recording.recorder_node")


def minimal_node() -> None:
    """Child: become ready like a node does and print the seconds since this process started."""
    from fsr_sim.ros.runtime import configure_environment, process_age

    configure_environment()
    import rclpy

    from fsr_sim.contract import ODOM, WRENCH_CMD
    from fsr_sim.ros.endpoints import publisher, subscription

    rclpy.init()
    node = rclpy.create_node("startup_probe", start_parameter_services=False)
    publisher(node, WRENCH_CMD)
    subscription(node, ODOM, lambda _message: None, raw=True)
    print(f"{process_age():.4f}", flush=True)
    node.destroy_node()
    rclpy.try_shutdown()


def ready_times(count: int, domain_id: int) -> list[float]:
    """Start ``count`` minimal nodes at once in ROS domain ``domain_id``; their ready times [s]."""
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain_id))
    processes = [subprocess.Popen([sys.executable, __file__, "--minimal"], env=env, stdout=subprocess.PIPE,
                                  text=True) for _ in range(count)]
    times = []
    for process in processes:
        out, _ = process.communicate(timeout=60)
        if process.returncode != 0:
            raise SystemExit(f"minimal node failed with exit code {process.returncode}")
        times.append(float(out.split()[-1]))
    return times


def import_time(module: str) -> float:
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", f"import {module}"], check=True)
    return time.perf_counter() - start


def report(label: str, values: list[float]) -> None:
    values = sorted(values)
    print(f"  {label:58s} min {values[0]:.2f} s   median {statistics.median(values):.2f} s", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs of each figure")
    parser.add_argument("--together", type=int, default=4, help="minimal nodes started at once")
    parser.add_argument("--minimal", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.minimal:
        minimal_node()
        return
    from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain

    print(f"node start-up on {os.cpu_count()} CPUs, Python {sys.version.split()[0]}")
    with acquire_domain(TEST_RANGE) as lease:
        domain = lease.domain_id
        report("minimal rclpy node alone: ready after",
               [t for _ in range(args.repeat) for t in ready_times(1, domain)])
        report(f"minimal rclpy node, {args.together} started at once: ready after",
               [t for _ in range(args.repeat) for t in ready_times(args.together, domain)])
    for module in NODE_MODULES:
        report(f"import {module}", [import_time(module) for _ in range(args.repeat)])


if __name__ == "__main__":
    main()
