"""The node graph's floor on this machine: stub simulator, controller and estimator processes with the graph's
topics, QoS, message sizes and lockstep, and no model work at all, with fsr's recorder (``fsr-record``,
recording every topic); beside them fsr's own graph (``fsr-fly``: the same nodes with the compiled core and
the same recorder), as CPU per step over every process and steps per second, and the ratio ours / floor
(min and median of ``--repeat`` runs each, measured in one run).

    .venv/bin/python benchmarks/graph_floor.py [--steps 5000] [--repeat 3]

Stubs (one process each, in their own ROS domain, localhost discovery), for an ex4-like quadrotor with rotor
actuation, every message packed by fsr's CDR templates with fixed values and the step's stamp:

* simulator: waits for the controller, then per step publishes ``odom``, ``wrench_truth``, ``/clock`` and waits
  (raw wait set) for the ``rotor_cmd`` stamped like the state;
* controller: takes each ``odom`` (wait set, raw bytes) and publishes ``rotor_cmd``, ``wrench_cmd``,
  ``wrench_shortfall``, ``reference``, ``attitude_cmd`` and ``wrench_desired`` with its stamp;
* estimator: takes ``odom`` and ``wrench_cmd`` and publishes ``wrench_estimate`` and ``mass_estimate`` for each.

This is what rclpy and DDS cost per step here, whatever the models do.
"""

from __future__ import annotations

import argparse
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from graph_cpu import fly_graph  # noqa: E402

from fsr_sim.contract import (  # noqa: E402
    BY_NAME,
    CLOCK,
    MASS_ESTIMATE,
    ODOM,
    ROTOR_CMD,
    WRENCH_CMD,
    WRENCH_ESTIMATE,
    WRENCH_TRUTH,
)

ROTORS = 4
NS = 1_000_000  # ns per 1 kHz step


def _node(name: str, domain: int):  # noqa: ANN202
    import rclpy
    from rclpy.context import Context
    from rclpy.node import Node

    context = Context()
    rclpy.init(context=context, domain_id=domain)
    return Node(name, context=context, start_parameter_services=False), context


def _templates() -> dict:
    from fsr_control.nodes.packets import ControllerPackets
    from fsr_estimation.nodes.packets import EstimatePackets
    from fsr_sim.nodes.state_packets import StatePackets
    from fsr_sim.ros import cdr_pack

    templates = {**StatePackets().templates, **ControllerPackets(True, ROTORS).templates,
                 **EstimatePackets().templates, CLOCK.name: cdr_pack.clock()}
    return {topic: (template, [0.5] * template.value_count) for topic, template in templates.items()}


def simulator(domain: int, steps: int) -> None:
    from fsr_sim.ros import cdr_read
    from fsr_sim.ros.endpoints import publisher, subscription
    from fsr_sim.ros.wait_set import SubscriptionWaitSet

    node, context = _node("simulator", domain)
    packets = _templates()
    odom, truth, clock = (publisher(node, topic) for topic in (ODOM, WRENCH_TRUTH, CLOCK))
    command = subscription(node, ROTOR_CMD, lambda _m: None, raw=True)
    waiting = SubscriptionWaitSet(node, [command])
    while odom.get_subscription_count() < 3 or command.get_publisher_count() < 1:  # controller, estimator, recorder
        time.sleep(0.01)
    start = time.monotonic()
    for k in range(steps + 1):
        stamp = k * NS
        for topic_publisher, topic in ((odom, ODOM), (truth, WRENCH_TRUTH), (clock, CLOCK)):
            template, values = packets[topic.name]
            topic_publisher.publish(template.pack(stamp, values))
        if k == steps:
            break
        answered = False
        while not answered:
            for _, data, _ in waiting.take_ready(1_000_000_000):
                answered = answered or cdr_read.stamp(data) == stamp
            if time.monotonic() - start > 600:
                raise SystemExit("the stub controller stopped answering")
    print(f"stepped {steps} in {time.monotonic() - start:.3f} s", flush=True)
    for topic_publisher in (odom, truth):
        topic_publisher.wait_for_all_acked()
    node.destroy_node()
    context.try_shutdown()


def controller(domain: int, steps: int) -> None:
    from fsr_control.nodes.packets import ControllerPackets
    from fsr_sim.ros import cdr_read
    from fsr_sim.ros.endpoints import publisher, subscription
    from fsr_sim.ros.wait_set import SubscriptionWaitSet

    node, context = _node("controller", domain)
    packets = _templates()
    names = ControllerPackets(True, ROTORS).templates
    publishers = [(publisher(node, BY_NAME[name]), *packets[name]) for name in names]
    odom = subscription(node, ODOM, lambda _m: None, raw=True)
    waiting = SubscriptionWaitSet(node, [odom])
    answered = -1
    while answered < steps * NS:
        for _, data, _ in waiting.take_ready(1_000_000_000):
            answered = cdr_read.stamp(data)
            for topic_publisher, template, values in publishers:
                topic_publisher.publish(template.pack(answered, values))
    for topic_publisher, _, _ in publishers:
        topic_publisher.wait_for_all_acked()
    node.destroy_node()
    context.try_shutdown()


def estimator(domain: int, steps: int) -> None:
    from fsr_sim.ros import cdr_read
    from fsr_sim.ros.endpoints import publisher, subscription
    from fsr_sim.ros.wait_set import SubscriptionWaitSet

    node, context = _node("estimator", domain)
    packets = _templates()
    wrench, mass = publisher(node, WRENCH_ESTIMATE), publisher(node, MASS_ESTIMATE)
    subscriptions = [subscription(node, topic, lambda _m: None, raw=True) for topic in (ODOM, WRENCH_CMD)]
    waiting = SubscriptionWaitSet(node, subscriptions)
    halves: dict[int, int] = {}
    last = -1
    while last < steps * NS:
        for _, data, _ in waiting.take_ready(1_000_000_000):
            stamp = cdr_read.stamp(data)
            halves[stamp] = halves.get(stamp, 0) + 1
            if halves[stamp] == 2:  # both halves of the step: estimate
                del halves[stamp]
                last = stamp
                for topic_publisher, topic in ((wrench, WRENCH_ESTIMATE), (mass, MASS_ESTIMATE)):
                    template, values = packets[topic.name]
                    topic_publisher.publish(template.pack(stamp, values))
    node.destroy_node()
    context.try_shutdown()


ROLES = {"simulator": simulator, "controller": controller, "estimator": estimator}


def floor_run(steps: int) -> tuple[float, float]:
    """(CPU per step over the three stub processes and the recorder [us], steps per second of the stub
    simulator)."""
    from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain

    with acquire_domain(TEST_RANGE) as lease, tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "ROS_DOMAIN_ID": str(lease.domain_id)}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        recorder = subprocess.Popen([str(Path(sys.executable).parent / "fsr-record"), "--out", f"{tmp}/floor.mcap",
                                     "--keep-running"], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        processes = [subprocess.Popen([sys.executable, __file__, "--role", role, "--domain", str(lease.domain_id),
                                       "--steps", str(steps)], env=env, stdout=subprocess.PIPE, text=True, cwd=tmp)
                     for role in ROLES]
        outputs = [p.communicate(timeout=900)[0] for p in processes]
        recorder.send_signal(signal.SIGINT)  # the stubs are done: the recorder drains and closes its file
        recorder.wait(timeout=60)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if any(p.returncode for p in processes):
        raise SystemExit(f"a stub node failed: {[p.returncode for p in processes]}\n{outputs}")
    seconds = float(outputs[0].split(" in ")[1].split()[0])
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return 1e6 * cpu / steps, steps / seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--steps", type=int, default=5000, help="1 kHz steps per flight (default 5000)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--role", choices=tuple(ROLES), help=argparse.SUPPRESS)
    parser.add_argument("--domain", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.role:
        ROLES[args.role](args.domain, args.steps)
        return
    floors = [floor_run(args.steps) for _ in range(args.repeat)]
    ours = [fly_graph("ex4_geometric", args.steps / 1000.0, ["--set", "actuation=rotors"])
            for _ in range(args.repeat)]
    floor_cpu = sorted(cpu for cpu, _ in floors)
    floor_rate = sorted(rate for _, rate in floors)
    our_cpu = sorted(1e6 * run.cpu_total / (run.sim_time * 1000.0) for run in ours)
    our_rate = sorted(run.stepping_rate * 1000.0 for run in ours)
    print(f"floor (stubs): CPU per step min {floor_cpu[0]:.0f} median {statistics.median(floor_cpu):.0f} us, "
          f"steps/s min {floor_rate[0]:.0f} median {statistics.median(floor_rate):.0f}")
    print(f"fsr graph:     CPU per step min {our_cpu[0]:.0f} median {statistics.median(our_cpu):.0f} us, "
          f"steps/s min {our_rate[0]:.0f} median {statistics.median(our_rate):.0f}")
    print(f"ours / floor:  CPU per step {statistics.median(our_cpu) / statistics.median(floor_cpu):.2f}, "
          f"steps/s {statistics.median(our_rate) / statistics.median(floor_rate):.2f} (medians; {args.repeat} "
          f"run(s) of {args.steps} steps each)")


if __name__ == "__main__":
    main()
