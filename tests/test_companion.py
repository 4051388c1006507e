"""A controller and an estimator on a companion computer: fsr_sim, fsr_control and fsr_estimation run their
nodes without the recording and plotting dependencies (``mcap``, ``mcap-ros2-support``, ``matplotlib``),
which are extras (``fsr_sim[recording]``, ``fsr_estimation[cli]``) that fsr_bringup installs."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from importlib.metadata import requires

import pytest

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain

OPTIONAL = {"mcap", "mcap-ros2-support", "matplotlib"}
NODE_PACKAGES = ("fsr_sim", "fsr_control", "fsr_estimation")

WITHOUT_OPTIONAL_MODULES = """
import importlib.abc, sys

class Uninstalled(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("mcap", "mcap_ros2", "matplotlib"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)

sys.meta_path.insert(0, Uninstalled())
import rclpy
from fsr_control.nodes.controller_node import ControllerNode
from fsr_estimation.nodes.estimator_node import EstimatorNode
from fsr_sim.nodes.simulator_node import SimulatorNode

rclpy.init(args=["--ros-args", "-p", "scenario:=ex4_geometric"])
for make_node in (lambda: SimulatorNode([]), ControllerNode, EstimatorNode):
    node = make_node()
    print("started", node.get_name(), flush=True)
    node.destroy_node()
rclpy.shutdown()
loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("mcap", "mcap_ros2", "matplotlib"))
print("loaded", loaded)
try:
    import fsr_sim.recording.writer
except ModuleNotFoundError as error:
    print("recording:", error)
from fsr_estimation.cli.estimate_cli import main
sys.exit(main(["log.mcap", "--mass", "1.2", "--inertia", "1,1,2", "--c0", "10", "--r", "1"]))
"""


def test_the_node_packages_do_not_require_the_recording_or_plotting_libraries():
    for package in NODE_PACKAGES:
        required = {re.split(r"[ \[<>=;!~]", line, maxsplit=1)[0].lower() for line in requires(package) or []
                    if "extra ==" not in line}
        assert not required & OPTIONAL, f"{package} requires {sorted(required & OPTIONAL)} outside its extras"
    extras = " ".join(requires("fsr_sim") + requires("fsr_estimation"))
    assert "mcap" in extras and "matplotlib" in extras  # ... which are the extras


@pytest.mark.graph  # the three nodes are created (DDS participants), though not spun
def test_the_nodes_start_without_them_and_say_what_to_install(tmp_path):
    (tmp_path / "log.mcap").write_bytes(b"")
    with acquire_domain(TEST_RANGE) as lease:
        env = {**os.environ, "ROS_DOMAIN_ID": str(lease.domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
        env.pop("ROS_LOCALHOST_ONLY", None)
        run = subprocess.run([sys.executable, "-c", WITHOUT_OPTIONAL_MODULES], env=env, cwd=tmp_path,
                             capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    out = run.stdout
    assert [line.split()[1] for line in out.splitlines() if line.startswith("started")] == [
        "simulator", "controller", "estimator"], out + run.stderr
    assert "loaded []" in out
    assert "recording: MCAP recordings need 'mcap', which is not installed: pip install 'fsr_sim[recording]'" in out
    assert run.returncode == 2 and "pip install 'fsr_sim[recording]'" in run.stderr, run.stderr

