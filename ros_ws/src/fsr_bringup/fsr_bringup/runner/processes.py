"""Starting, watching and stopping the node processes of a run (what ``ros2 launch`` would do).

Each node runs in its own session (so a terminal Ctrl-C reaches only the runner, which then stops the
nodes in order: the simulators first, then the nodes that answer their states, the recorder last) and
gets ``PR_SET_PDEATHSIG`` so that it is terminated if the runner itself dies: no orphans. Output (stdout
and stderr) is streamed line by line, prefixed with the node's name, and copied to ``<log_dir>/<name>.log``.
"""

from __future__ import annotations

import ctypes
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

PR_SET_PDEATHSIG = 1
DRAIN_WAIT_S = 20.0  # s a node may take after SIGINT to answer/record what is queued (it bounds itself)


def _die_with_parent() -> None:  # runs in the child between fork and exec
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def executable(name: str) -> str:
    """Path of a console script: next to the running Python first (the venv), then on PATH."""
    candidate = Path(sys.executable).parent / name
    if candidate.is_file():
        return str(candidate)
    found = shutil.which(name)
    if found is None:
        raise FileNotFoundError(f"console script '{name}' not found (is fsr installed in this environment?)")
    return found


def describe_exit(code: int) -> str:
    """'exit code 3' or 'killed by SIGKILL'."""
    if code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            return f"killed by signal {-code}"
    return f"exit code {code}"


@dataclass
class NodeProcess:
    """One started node: its process, its log file and the thread that streams its output."""

    name: str
    command: list[str]
    process: subprocess.Popen
    log_path: Path
    reader: threading.Thread
    stopping: bool = False
    tail: list[str] = field(default_factory=list)
    events: Callable[[str], bool] | None = None  # takes the lines of a process that reports events

    @property
    def returncode(self) -> int | None:
        return self.process.poll()

    def signal(self, signum: int) -> None:
        if self.process.poll() is None:
            try:
                self.process.send_signal(signum)
            except ProcessLookupError:
                pass


class ProcessGroup:
    """The processes of one run; ``stop_all`` ends them in the order they should end."""

    def __init__(self, env: dict[str, str], log_dir: Path, echo: Callable[[str, str], None]) -> None:
        self.env = env
        self.log_dir = log_dir
        self.echo = echo
        self.nodes: list[NodeProcess] = []

    def start(self, name: str, command: list[str], events: Callable[[str], bool] | None = None) -> NodeProcess:
        """Start ``command`` as the process ``name``. ``events``: a process that reports to the runner (the flight
        watcher): each output line goes to ``events(line)`` first; lines it takes are neither logged nor echoed,
        and the others are logged but not echoed."""
        log_path = self.log_dir / f"{name}.log"  # a fleet's "uav1/simulator" logs in a folder per vehicle
        log_path.parent.mkdir(parents=True, exist_ok=True)
        process = subprocess.Popen(
            command,
            env=self.env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            start_new_session=True,
            preexec_fn=_die_with_parent,
            text=True,
            bufsize=1,
        )
        node = NodeProcess(name, command, process, log_path, threading.Thread(daemon=True), events=events)
        node.reader = threading.Thread(target=self._stream, args=(node,), name=f"log-{name}", daemon=True)
        node.reader.start()
        self.nodes.append(node)
        return node

    def _stream(self, node: NodeProcess) -> None:
        with open(node.log_path, "w", encoding="utf-8") as log:
            for line in node.process.stdout:
                line = line.rstrip("\n")
                if node.events is not None and node.events(line):
                    continue
                log.write(line + "\n")
                log.flush()
                node.tail = (node.tail + [line])[-20:]
                if node.events is None:
                    self.echo(node.name, line)

    def get(self, name: str) -> NodeProcess | None:
        return next((n for n in self.nodes if n.name == name), None)

    def wait_for_exit(self, names: list[str], timeout: float) -> None:
        """Wait up to ``timeout`` s for the named nodes to exit by themselves (no signal)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and any(
                n.process.poll() is None for n in self.nodes if n.name in names):
            time.sleep(0.02)

    def stop(self, names: list[str], timeout: float) -> None:
        """SIGINT the named nodes, wait up to ``timeout`` s, then SIGTERM, then SIGKILL."""
        nodes = [n for n in self.nodes if n.name in names and n.process.poll() is None]
        for signum, wait in ((signal.SIGINT, timeout), (signal.SIGTERM, 2.0), (signal.SIGKILL, 2.0)):
            for node in nodes:
                node.stopping = True
                node.signal(signum)
            deadline = time.monotonic() + wait
            while time.monotonic() < deadline and any(n.process.poll() is None for n in nodes):
                time.sleep(0.02)
            nodes = [n for n in nodes if n.process.poll() is None]
            if not nodes:
                break
        for node in self.nodes:
            if node.name in names:
                node.reader.join(timeout=2.0)

    def stop_all(self, last: tuple[str, ...] = ("recorder",), timeout: float = 5.0, first: tuple[str, ...] = ()
                 ) -> None:
        """SIGINT in waves, each waiting for the previous one to exit: ``first`` (the simulators: they publish
        their final ``sim_status``), then the others (controller, estimator: they answer every state up to the
        simulator's last one), then ``last`` (the recorder: it drains up to that state and closes the file)."""
        self.stop(list(first), timeout)
        middle = [n.name for n in self.nodes if n.name not in last and n.name not in first]
        self.stop(middle, DRAIN_WAIT_S if first else timeout)
        self.stop(list(last), DRAIN_WAIT_S)
