"""The guard behind ``-m "not graph"`` (conftest.py): in a test without the graph mark a node does not run."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.ros.runtime import FORBID_NODES_ENV

BIN = Path(sys.executable).parent


def test_a_node_started_by_a_test_without_the_graph_mark_exits_saying_why():
    assert os.environ.get(FORBID_NODES_ENV) == "1"
    with acquire_domain(TEST_RANGE) as lease:
        env = {**os.environ, "ROS_DOMAIN_ID": str(lease.domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
        run = subprocess.run([str(BIN / "controller"), "--ros-args", "-p", "scenario:=ex4_geometric"], env=env,
                             capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL)
    assert run.returncode == 1, run.stderr
    assert f"{FORBID_NODES_ENV} is set: this process may not run a ROS node" in run.stderr
