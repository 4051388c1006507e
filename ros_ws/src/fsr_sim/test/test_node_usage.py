"""``simulator --help``, ``controller --help``, ``estimator --help``: each node prints its usage and exits 0
without starting (its parameters with defaults, the topics it publishes and reads, its exit codes)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from fsr_sim.contract import EXIT_CODES, TOPICS

BIN = Path(sys.executable).parent
EXPECTED = {  # node -> parameters it must document, topics it reads
    "simulator": (("scenario", "wait_for_subscribers:=1", "startup_timeout:=20.0", "failsafe", "duration"),
                  ("rotor_cmd", "wrench_cmd")),
    "controller": (("scenario", "controller_type", "k_p", "k_w", "exit_on_finish:=true"), ("odom", "goal")),
    "estimator": (("scenario", "c0", "r", "mass", "inertia", "control_period", "exit_on_finish:=true"),
                  ("odom", "wrench_cmd")),
}


@pytest.mark.slow  # seconds of subprocesses, figures or flights: not for the fast tier
@pytest.mark.parametrize("node", sorted(EXPECTED))
@pytest.mark.parametrize("flag", ["--help", "-h"])
def test_a_node_prints_its_usage(node, flag):
    run = subprocess.run([str(BIN / node), flag], capture_output=True, text=True, timeout=60,
                         stdin=subprocess.DEVNULL)
    assert run.returncode == 0 and run.stderr == "", run.stderr
    lines = run.stdout.splitlines()
    assert lines[0].startswith(f"usage: {node} ")
    parameters, reads = EXPECTED[node]
    start, end = lines.index("parameters (-p name:=value):"), lines.index("publishes (relative names move with "
                                                                           "the namespace):")
    section = [line for line in lines[start + 1:end] if line]
    assert [line.split()[0] for line in section][:1] == ["scenario"]
    assert set(parameters) <= {line.split()[0] for line in section}, section
    published = lines[lines.index("publishes (relative names move with the namespace):") + 1:lines.index("subscribes:")]
    assert [line.split()[0] for line in published if line] == [t.name for t in TOPICS if t.publisher == node]
    subscribed = lines[lines.index("subscribes:") + 1:lines.index("exit codes:")]
    assert set(reads) <= {line.split()[0] for line in subscribed if line}
    codes = lines[lines.index("exit codes:") + 1:]
    assert all(EXIT_CODES[int(line.split()[0])] in line for line in codes) and "  2   " in "\n".join(codes)


def test_help_after_ros_args_is_not_the_nodes_own():
    """``--ros-args --help`` belongs to ROS: the node does not print its usage for it."""
    from fsr_sim.ros.node_usage import wants_help

    assert wants_help(["simulator", "--help"]) and wants_help(["simulator", "-h", "--ros-args", "-p", "x:=1"])
    assert not wants_help(["simulator", "--ros-args", "--help"]) and not wants_help(["simulator"])
