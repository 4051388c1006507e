"""Process-level plumbing shared by every fsr node: environment, init, spin loop and clean shutdown.

* :func:`configure_environment` points Fast DDS at the shipped discovery profile and keeps discovery on
  localhost unless the user chose otherwise (ROS2_FROM_PIP.md: only ``rmw_fastrtps_cpp`` exists, domain
  ids are 0-232).
* :func:`run_node` installs our own SIGINT/SIGTERM handlers (rclpy's may surface as ``RCLError`` under
  load), spins until the node says it is done or a signal arrives, then destroys the node and shuts the
  context down. The node's ``close()`` (if any) runs in ``finally`` so files are always finished.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Callable
from importlib import resources

# Exit codes of every fsr command and node (one place): fsr-fly passes the simulator's on.
EXIT_OK = 0
EXIT_FAILURE = 1  # a node failed (or a file could not be written)
EXIT_CONFIG_ERROR = 2  # invalid scenario, parameter or argument; nothing was started
EXIT_DIVERGED = 3  # the flight diverged (NaN state, beyond physical bounds, crash)
EXIT_INTERRUPTED = 130  # fsr-fly stopped by SIGINT/SIGTERM (128 + SIGINT, the shell's convention)


def configure_environment() -> None:
    """Set DDS defaults for this process and its children (existing values win)."""
    profile = resources.files("fsr_sim.config").joinpath("fastdds_profile.xml")
    os.environ.setdefault("FASTRTPS_DEFAULT_PROFILES_FILE", str(profile))
    if "ROS_LOCALHOST_ONLY" not in os.environ:
        os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    rmw = os.environ.get("RMW_IMPLEMENTATION")
    if rmw and rmw != "rmw_fastrtps_cpp":
        # Any other value kills the process inside `import rclpy` with no message (exit 102).
        raise SystemExit(f"RMW_IMPLEMENTATION={rmw} is not available here; only rmw_fastrtps_cpp is installed")
    domain = os.environ.get("ROS_DOMAIN_ID")
    if domain is not None and domain != "":
        if not domain.isdigit() or not 0 <= int(domain) <= 232:
            raise SystemExit(f"ROS_DOMAIN_ID must be an integer in 0..232, got '{domain}'")


class StopFlag:
    """Set by SIGINT/SIGTERM; the spin loop polls it."""

    def __init__(self) -> None:
        self.signal_name: str | None = None

    def __bool__(self) -> bool:
        return self.signal_name is not None

    def install(self) -> None:
        def handler(signum: int, _frame: object) -> None:
            self.signal_name = signal.Signals(signum).name

        signal.signal(signal.SIGINT, handler)
        signal.signal(signal.SIGTERM, handler)


def run_node(make_node: Callable[[list[str]], object], argv: list[str] | None = None) -> int:
    """Create the node with ``make_node(args)`` and spin it until done or signalled; returns an exit code.

    The node may define ``done() -> bool`` (stop spinning, e.g. end of the flight), ``exit_code`` and
    ``close()``; it may define ``spin_once(executor, stop)`` to drive its own loop (the simulator's
    lockstep) instead of the executor's callbacks. ``ConfigError`` / ``ValueError`` raised while the node
    is built are printed as one line and give exit code 2.
    """
    configure_environment()
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    from fsr_sim.config.validation import ConfigError

    argv = sys.argv if argv is None else argv
    stop = StopFlag()
    stop.install()
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    node = None
    code = EXIT_OK
    try:
        try:
            node = make_node(rclpy.utilities.remove_ros_args(argv)[1:])
        except (ConfigError, ValueError) as error:
            print(f"[fsr] error: {error}", file=sys.stderr, flush=True)
            return EXIT_CONFIG_ERROR
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        own_loop = getattr(node, "spin_once", None)
        done = getattr(node, "done", lambda: False)
        while not stop and not done():
            if own_loop is not None:
                own_loop(executor, stop)
            else:
                executor.spin_once(timeout_sec=0.1)
        code = int(getattr(node, "exit_code", EXIT_OK))
        if stop:
            node.get_logger().info(f"received {stop.signal_name}, shutting down")
    except KeyboardInterrupt:
        pass
    finally:
        if node is not None:
            close = getattr(node, "close", None)
            if close is not None:
                close()
            node.destroy_node()
        rclpy.try_shutdown()
    return code


class RateLimitedWarning:
    """Warn at most once per ``period`` seconds (wall clock), counting what was suppressed."""

    def __init__(self, logger: object, period: float = 1.0) -> None:
        self.logger = logger
        self.period = period
        self.last = -float("inf")
        self.suppressed = 0
        self.total = 0

    def __call__(self, message: str) -> None:
        self.total += 1
        now = time.monotonic()
        if now - self.last < self.period:
            self.suppressed += 1
            return
        extra = f" ({self.suppressed} similar warnings suppressed)" if self.suppressed else ""
        self.logger.warning(message + extra)
        self.last = now
        self.suppressed = 0
