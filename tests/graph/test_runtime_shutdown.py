"""run_node's teardown (fsr_sim.ros.runtime): entities really destroyed before the context goes, and a hung
teardown cut short by the watchdog. Each case runs in a child process (its own rclpy context and signal
handlers) in a leased ROS domain, with a timeout."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

import pytest

from fsr_bringup.runner.domains import TEST_RANGE, acquire_domain
from fsr_sim.ros.runtime import TEARDOWN_HUNG_SIGNAL

pytestmark = pytest.mark.graph  # child processes with their own rclpy context, in a leased domain

HELD_HANDLES = textwrap.dedent('''
    from rclpy.node import Node
    from rclpy.waitable import NumberOfEntities, Waitable
    from std_msgs.msg import String

    from fsr_sim.ros.runtime import run_node

    class AlwaysReady(Waitable):
        """The executor yields a ready waitable from inside the block where it holds every entity handle."""

        def __init__(self, group):
            super().__init__(group)
            self.runs = 0

        def is_ready(self, wait_set):
            return True

        def take_data(self):
            return None

        async def execute(self, taken_data):
            self.runs += 1

        def get_num_entities(self):
            return NumberOfEntities()

        def add_to_wait_set(self, wait_set):
            pass

    class Held(Node):
        def __init__(self):
            super().__init__("held")
            self.sub = self.create_subscription(String, "x", lambda msg: None, 10)
            self.ready = AlwaysReady(self.default_callback_group)
            self.add_waitable(self.ready)

        def done(self):
            return self.ready.runs >= 1

    nodes = []
    code = run_node(lambda args: nodes.append(Held()) or nodes[0], ["held"], exit_process=False)
    print("destroyed" if nodes[0].sub.handle.pointer == 0 else "NOT destroyed", code, flush=True)
''')

HUNG_TEARDOWN = textwrap.dedent('''
    import os
    import signal
    import time

    from rclpy.node import Node

    from fsr_sim.ros.runtime import run_node

    class HangsInTeardown(Node):
        """The rcl/DDS teardown hangs (as destroy_node was seen to): the watchdog must end the process."""

        def __init__(self):
            super().__init__("hangs")

        def spin_once(self, executor, stop):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)

        def destroy_node(self):
            time.sleep(60.0)  # a teardown that never ends

    run_node(lambda args: HangsInTeardown(), ["hangs"])
''')


def run_child(script: str, timeout: float) -> tuple[subprocess.CompletedProcess, float]:
    with acquire_domain(TEST_RANGE) as lease:
        env = {**os.environ, "ROS_DOMAIN_ID": str(lease.domain_id), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
        start = time.monotonic()
        result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True,
                                timeout=timeout, stdin=subprocess.DEVNULL)
        return result, time.monotonic() - start


def test_entities_are_destroyed_although_the_executor_held_their_handles():
    """The executor's cached wait generator holds every handle between two spin_once calls; destroy_node
    could then only defer their destruction (to garbage collection after the context was shut down)."""
    result, _ = run_child(HELD_HANDLES, timeout=60.0)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["destroyed", "0"], result.stdout + result.stderr


@pytest.mark.alone  # the watchdog's cut timed on the wall clock (1-2 s)
def test_watchdog_ends_a_hung_teardown_within_the_signal_budget():
    result, _ = run_child(HUNG_TEARDOWN, timeout=60.0)
    assert result.returncode == -TEARDOWN_HUNG_SIGNAL, result.stdout + result.stderr  # only the teardown hung
    lines = [line for line in result.stderr.splitlines() if "shutdown did not finish" in line]
    assert len(lines) == 1 and lines[0].endswith("(node teardown hung): exiting now"), result.stderr
    seconds = float(lines[0].split("within ")[1].split(" s")[0])
    assert 1.0 <= seconds <= 2.0  # cut at SIGNAL_TEARDOWN_LIMIT (1.8 s) after the signal


GIL_HELD_TEARDOWN = HUNG_TEARDOWN.replace(
    "time.sleep(60.0)  # a teardown that never ends",
    "ctypes.PyDLL(None).sleep(60)  # never ends and keeps the GIL, as a deadlocked Fast DDS participant deletion",
).replace("import os\n", "import ctypes\nimport os\n", 1)


def test_a_hung_teardown_that_holds_the_gil_is_ended_too():
    """The watchdog thread cannot run while rcl/DDS holds the GIL; the kernel timer still ends the process,
    after faulthandler printed the stack of the hang."""
    assert "PyDLL" in GIL_HELD_TEARDOWN and "import ctypes" in GIL_HELD_TEARDOWN
    result, elapsed = run_child(GIL_HELD_TEARDOWN, timeout=60.0)
    assert result.returncode == -TEARDOWN_HUNG_SIGNAL, result.stdout + result.stderr
    assert "Timeout" in result.stderr and "destroy_node" in result.stderr, result.stderr
    assert "shutdown did not finish" not in result.stderr  # the thread never got the GIL
    assert elapsed < 20.0
