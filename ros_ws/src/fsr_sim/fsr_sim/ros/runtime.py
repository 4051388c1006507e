"""Process-level plumbing shared by every fsr node: environment, init, spin loop and clean shutdown.

* :func:`configure_environment` points Fast DDS at the shipped discovery profile and keeps discovery on
  localhost unless the user chose otherwise (ROS2_FROM_PIP.md: only ``rmw_fastrtps_cpp`` exists, domain
  ids are 0-232).
* :func:`run_node` installs our own SIGINT/SIGTERM handlers (rclpy's may surface as ``RCLError`` under
  load), spins until the node says it is done or a signal arrives, then destroys the node and shuts the
  context down. The node's ``close()`` (if any) runs in ``finally`` so files are always finished.

Shutdown is bounded (a node exits within ``SIGNAL_EXIT_BUDGET`` s of SIGINT/SIGTERM in any phase; only
finishing a file, which is never cut short, can take longer on an overloaded machine). The
executor is shut down *before* the node is destroyed: its cached wait generator holds every entity handle
(``with handle``) between two ``spin_once`` calls, so ``destroy_node`` could only mark them "destroy when
not in use" and their real destruction happened later, at garbage collection, after the context was shut
down (a by-hand estimator was seen spinning at 100 % CPU there for minutes). As a last resort a watchdog
thread ends the process with ``os._exit`` (and says so on stderr) if teardown still has not finished by
the budget's end, and a kernel timer does so shortly after for a hang that holds the GIL; such a node ends
killed by ``SIGALRM`` (:data:`TEARDOWN_HUNG_SIGNAL`, :class:`TeardownWatchdog`).

A node's per-step subscriptions (``hot_subscriptions``) are taken from a raw wait set and handed to their
callbacks directly (:class:`fsr_sim.ros.wait_set.WaitSetSpinner`; ROS2_FROM_PIP.md: about half the CPU of a
``SingleThreadedExecutor`` per message); the executor still runs every 50 ms (``EXECUTOR_PERIOD``) for everything
else (goals, ``sim_status``, services), and drives the node alone during its ``close()``.
"""

from __future__ import annotations

import faulthandler
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from importlib import resources

from fsr_sim.contract import (  # noqa: F401 - the exit codes are the contract's, re-exported for the nodes
    EXIT_CONFIG_ERROR,
    EXIT_DIVERGED,
    EXIT_FAILURE,
    EXIT_INTERRUPTED,
    EXIT_OK,
)
from fsr_sim.ros.node_usage import NodeUsage, wants_help

# Set by the test suite for the tests not marked graph: a node built under it exits at once with
# EXIT_FAILURE, so that `pytest -m "not graph"` provably runs no node (conftest.py).
FORBID_NODES_ENV = "FSR_FORBID_NODES"

# A node whose rcl/DDS teardown hung after its work was done (files closed, acks waited for) is ended by this
# signal from its own watchdog (TeardownWatchdog): the runner tells it from a failure by the exit status.
TEARDOWN_HUNG_SIGNAL = signal.SIGALRM

SIGNAL_EXIT_BUDGET = 2.0  # s from SIGINT/SIGTERM to process exit, in any phase
SIGNAL_TEARDOWN_LIMIT = 1.8  # s after the signal: the watchdog ends the process if teardown still runs
FINISH_TEARDOWN_LIMIT = 6.0  # s of teardown after the node ended by itself (acks, closing files)
RCL_TEARDOWN_MIN = 0.5  # s: the rcl/DDS teardown always gets at least this long
HARD_MARGIN = 0.5  # s: the kernel timer's bound on teardown lies this far past the watchdog thread's
STACK_DUMP_S = 0.2  # s between faulthandler's stack dump and the timer's signal
ACK_WAIT_AFTER_FINISH = 1.0  # s: after the flight ended, wait this long at most for subscribers' acks


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
        self.received_at: float | None = None  # time.monotonic() of the first signal

    def __bool__(self) -> bool:
        return self.signal_name is not None

    def install(self) -> None:
        def handler(signum: int, _frame: object) -> None:
            if self.received_at is None:
                self.received_at = time.monotonic()
            self.signal_name = signal.Signals(signum).name

        signal.signal(signal.SIGINT, handler)
        signal.signal(signal.SIGTERM, handler)


def process_age() -> float:
    """Seconds since this process started (``/proc/self/stat``; the venv python's re-exec included)."""
    try:
        with open("/proc/self/stat") as stat:
            start_ticks = int(stat.read().rsplit(")", 1)[1].split()[19])
        with open("/proc/uptime") as uptime:
            return float(uptime.read().split()[0]) - start_ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return float("nan")


def run_node(make_node: Callable[[list[str]], object], argv: list[str] | None = None,
             exit_process: bool = True, usage: NodeUsage | None = None) -> int:
    """Create the node with ``make_node(args)`` and spin it until done or signalled; returns an exit code.
    ``-h`` / ``--help`` (before ``--ros-args``) prints ``usage`` and returns 0 without starting anything.

    The node may define ``done() -> bool`` (stop spinning, e.g. end of the flight), ``exit_code`` and
    ``close()``; it may define ``spin_once(executor, stop)`` to drive its own loop (the simulator's
    lockstep) instead of the executor's callbacks. ``ConfigError`` / ``ValueError`` raised while the node
    is built are printed as one line and give exit code 2. A node with a ``stop_flag`` attribute gets the
    :class:`StopFlag`; its ``close()`` can then keep within the signal budget (:func:`signal_deadline`).

    With ``exit_process`` (the console scripts), once a node was built and torn down the process ends right
    here with ``os._exit(code)`` after flushing stdout/stderr: interpreter finalisation (garbage collection
    of rclpy objects, Fast DDS global destructors) adds up to seconds on a loaded machine and is where a
    by-hand node was seen to hang. Files are already closed by ``close()``.
    """
    argv = sys.argv if argv is None else argv
    if usage is not None and wants_help(argv):
        print(usage.text())
        return EXIT_OK
    configure_environment()
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.signals import SignalHandlerOptions

    stop = StopFlag()
    stop.install()
    rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
    node = None
    executor = None
    code = EXIT_OK
    watchdog = TeardownWatchdog(stop, hard=exit_process)
    try:
        try:
            node = make_node(rclpy.utilities.remove_ros_args(argv)[1:])
        except ValueError as error:  # fsr_sim.config.validation.ConfigError is one
            print(f"[fsr] error: {error}", file=sys.stderr, flush=True)
            return EXIT_CONFIG_ERROR
        if os.environ.get(FORBID_NODES_ENV):
            print(f"[fsr] error: {FORBID_NODES_ENV} is set: this process may not run a ROS node (a test that is not "
                  "marked graph started it)", file=sys.stderr, flush=True)
            return EXIT_FAILURE
        if hasattr(node, "stop_flag"):
            node.stop_flag = stop  # lets close() keep within the signal budget
        node.get_logger().info(f"ready {process_age():.2f} s after the process started")
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        own_loop = getattr(node, "spin_once", None)
        hot = getattr(node, "hot_subscriptions", None)
        if own_loop is None and hot:  # per-step inputs from a raw wait set, the executor every 50 ms
            from fsr_sim.ros.wait_set import WaitSetSpinner

            own_loop = WaitSetSpinner(node, hot, getattr(node, "hot_gather_s", 0.0)).spin_once
        done = getattr(node, "done", lambda: False)
        while not stop and not done():
            if own_loop is not None:
                own_loop(executor, stop)
            else:
                executor.spin_once(timeout_sec=0.1)
        code = int(getattr(node, "exit_code", EXIT_OK))
        if stop:  # a node that saw the flight end (flight_over) is stopped, not interrupted
            node.get_logger().info(f"the flight is over: stopping ({stop.signal_name})"
                                   if getattr(node, "flight_over", False)
                                   else f"received {stop.signal_name}, shutting down")
    except KeyboardInterrupt:
        pass
    finally:
        try:
            # The node's own close() comes first and is not cut short: it finishes files (a recording must
            # stay valid even on a machine so loaded that closing it takes longer than the signal budget);
            # its drains keep within the budget themselves (signal_deadline). The watchdog guards what can
            # hang: the rcl/DDS teardown below.
            if node is not None:
                close = getattr(node, "close", None)
                if close is not None:
                    close()  # may still spin the executor (a drain of what is queued)
                if not stop:
                    wait_for_acks(node, ACK_WAIT_AFTER_FINISH)
            watchdog.start()
            if executor is not None:
                executor.shutdown(timeout_sec=0.5)  # releases the entity handles its wait generator holds
            if node is not None:
                node.destroy_node()
        finally:
            rclpy.try_shutdown()
            watchdog.cancel()
    if exit_process and node is not None:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def exit_on_finish_parameter(node: object, node_kind: str) -> bool:
    """Declare and read the boolean parameter ``exit_on_finish`` (default true): whether a helper node ends
    by itself once the flight has ended (:mod:`fsr_sim.ros.flight_end`). Anything but a bool is refused."""
    from rcl_interfaces.msg import ParameterDescriptor

    from fsr_sim.config.validation import ConfigError

    value = node.declare_parameter("exit_on_finish", True, ParameterDescriptor(dynamic_typing=True)).value
    if not isinstance(value, bool):
        raise ConfigError("parameter 'exit_on_finish'", f"must be true or false, got {value!r}", node_kind)
    return value


def signal_deadline(stop: object, limit: float, default: float) -> float:
    """Monotonic deadline for shutdown work: ``limit`` s after the signal if ``stop`` (a :class:`StopFlag`)
    received one, else ``default`` s from now."""
    received = getattr(stop, "received_at", None)
    return received + limit if received is not None else time.monotonic() + default


def wait_for_acks(node: object, timeout: float) -> bool:
    """Wait (at most ``timeout`` s in all) until every subscriber acknowledged each publisher's messages,
    so that a node ending by itself does not take its last messages with it; False on timeout."""
    from rclpy.duration import Duration

    deadline = time.monotonic() + timeout
    for publisher in list(getattr(node, "publishers", [])):
        remaining = deadline - time.monotonic()
        if remaining <= 0.0 or not publisher.wait_for_all_acked(Duration(nanoseconds=int(remaining * 1e9))):
            return False
    return True


class TeardownWatchdog:
    """Ends the process with ``os._exit`` if teardown outlives its bound (a hang in rcl/DDS must never
    keep a node alive): :data:`SIGNAL_TEARDOWN_LIMIT` s after the signal (at least :data:`RCL_TEARDOWN_MIN`
    s of teardown), else :data:`FINISH_TEARDOWN_LIMIT` s after teardown began. Started after the node's
    ``close()``, so files are always finished.

    With ``hard`` (a process that exits after teardown) the process ends killed by
    :data:`TEARDOWN_HUNG_SIGNAL`, which tells the runner that only the teardown hung. The watching thread needs
    the GIL, and a Fast DDS participant deletion that deadlocks holds it (``fsr_bringup/runner/watcher_node.py``
    says when), so a kernel timer (``setitimer``, the signal's default action) ends the process anyway
    :data:`HARD_MARGIN` s past the bound known at the start, after ``faulthandler`` (its own C thread) printed
    the stack of the hang. Without ``hard`` (a caller's process) the thread ends it with ``os._exit(1)``."""

    def __init__(self, stop: StopFlag, hard: bool = False) -> None:
        self.stop = stop
        self.hard = hard
        self.finished = threading.Event()
        self.thread: threading.Thread | None = None
        self.began = time.monotonic()

    def start(self) -> None:
        self.began = time.monotonic()
        self.thread = threading.Thread(target=self._watch, name="fsr-teardown-watchdog", daemon=True)
        self.thread.start()
        if self.hard:
            bound = self.deadline() - self.began + HARD_MARGIN
            signal.signal(TEARDOWN_HUNG_SIGNAL, signal.SIG_DFL)  # its default action: terminate
            faulthandler.dump_traceback_later(bound, exit=False)
            signal.setitimer(signal.ITIMER_REAL, bound + STACK_DUMP_S)

    def deadline(self) -> float:
        """Monotonic time at which teardown is cut short (moves earlier if a signal arrives meanwhile)."""
        if self.stop.received_at is not None:
            return max(self.stop.received_at + SIGNAL_TEARDOWN_LIMIT, self.began + RCL_TEARDOWN_MIN)
        return self.began + FINISH_TEARDOWN_LIMIT

    def _watch(self) -> None:
        while not self.finished.wait(max(0.0, min(0.05, self.deadline() - time.monotonic()))):
            if time.monotonic() >= self.deadline():
                print(f"[fsr] error: shutdown did not finish within {time.monotonic() - self.began:.1f} s "
                      "(node teardown hung): exiting now", file=sys.stderr, flush=True)
                if self.hard:
                    os.kill(os.getpid(), TEARDOWN_HUNG_SIGNAL)
                os._exit(EXIT_FAILURE)

    def cancel(self) -> None:
        self.finished.set()
        if self.hard:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            faulthandler.cancel_dump_traceback_later()


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
