"""A small private network of Linux network namespaces ("hosts") for tests and benchmarks over real DDS.

:class:`NetLab` builds one namespace holding a bridge (the "switch") and one namespace per host, each
joined to the bridge by a veth pair whose host end is ``eth0`` with a private address (``10.77.0.x/24``)
and the multicast route (``224.0.0.0/4 dev eth0``) that SUBNET discovery needs (``multicast=False``
leaves it out: discovery then needs static peers, ``ROS_STATIC_PEERS``). Nothing is created in the
caller's namespace: the veth pairs are made inside the bridge namespace and their host ends moved, so
traffic and discovery can only reach the lab's hosts. Names carry the creating process id (parallel runs
never collide). :meth:`NetLab.close` deletes every namespace it created (with them their links) and is
safe to call twice; use the lab as a context manager so that happens also when a test fails.

Processes run on a host with ``ip netns exec`` (:meth:`NetLab.popen`); they are the caller's to stop, and
:meth:`NetLab.close` kills whatever still runs inside the lab's namespaces (only processes started there: a
namespace whose name is deleted lives on, unreachable, while a process is inside it; a node of a finished
test still tearing down would otherwise outlive its lab). :func:`network_environment` is the environment of
a graph spread over the hosts: SUBNET discovery and UDP only (namespaces of one machine share
``/dev/shm``; Fast DDS's shared-memory transport would carry the data past the links otherwise, unlike
between real machines).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from collections.abc import Sequence

SUBNET = "10.77.0"
MULTICAST = "224.0.0.0/4"


class NetLabUnavailableError(RuntimeError):
    """Namespaces cannot be made here (not root, no ``ip``, or the kernel refused); the message says why."""


def _ip(*args: str, netns: str | None = None, check: bool = True) -> subprocess.CompletedProcess:
    command = ["ip", *(["-n", netns] if netns else []), *args]
    result = subprocess.run(command, capture_output=True, text=True, timeout=10)
    if check and result.returncode != 0:
        raise RuntimeError(f"'{' '.join(command)}' failed: {result.stderr.strip()}")
    return result


def unavailable_reason() -> str | None:
    """Why namespaces cannot be made here, or None if they can (probed by making and deleting one)."""
    if os.geteuid() != 0:
        return "network namespaces need root (ip netns add); not root here"
    if shutil.which("ip") is None:
        return "the 'ip' command (iproute2) is not installed"
    probe = f"fsrprobe{os.getpid()}"
    made = _ip("netns", "add", probe, check=False)
    if made.returncode != 0:
        return f"'ip netns add' failed: {made.stderr.strip()}"
    _ip("netns", "del", probe, check=False)
    return None


class NetLab:
    """Hosts ``names`` (e.g. ``("sim", "ctl", "est")``) on one bridge; ``address(name)``, ``popen``, link faults."""

    def __init__(self, names: Sequence[str], multicast: bool = True) -> None:
        reason = unavailable_reason()
        if reason is not None:
            raise NetLabUnavailableError(reason)
        self.tag = tag = f"fsr{os.getpid()}"  # every namespace of this process's labs is named tag-...
        self.switch = f"{tag}-sw"
        self.hosts = {name: f"{tag}-{name}" for name in names}
        self.ports = {name: f"p{index}" for index, name in enumerate(names, start=1)}  # bridge-side veth ends
        self.addresses = {name: f"{SUBNET}.{index}" for index, name in enumerate(names, start=1)}
        self.multicast = multicast  # False: no multicast route, as on networks without multicast (static peers)
        self.created: list[str] = []
        try:
            self._build()
        except BaseException:
            self.close()
            raise

    def _add_netns(self, name: str) -> None:
        _ip("netns", "add", name)
        self.created.append(name)
        _ip("link", "set", "lo", "up", netns=name)

    def _build(self) -> None:
        self._add_netns(self.switch)
        _ip("link", "add", "br0", "type", "bridge", netns=self.switch)
        _ip("link", "set", "br0", "type", "bridge", "mcast_snooping", "0", netns=self.switch)
        _ip("link", "set", "br0", "up", netns=self.switch)
        for name, netns in self.hosts.items():
            self._add_netns(netns)
            port = self.ports[name]
            _ip("link", "add", port, "type", "veth", "peer", "name", "eth0", "netns", netns, netns=self.switch)
            _ip("link", "set", port, "master", "br0", netns=self.switch)
            _ip("link", "set", port, "up", netns=self.switch)
            _ip("addr", "add", f"{self.addresses[name]}/24", "dev", "eth0", netns=netns)
            _ip("link", "set", "eth0", "up", netns=netns)
            if self.multicast:
                _ip("route", "add", MULTICAST, "dev", "eth0", netns=netns)

    def address(self, name: str) -> str:
        return self.addresses[name]

    def command(self, name: str, argv: Sequence[str]) -> list[str]:
        """``argv`` run on host ``name``."""
        return ["ip", "netns", "exec", self.hosts[name], *argv]

    def popen(self, name: str, argv: Sequence[str], **kwargs: object) -> subprocess.Popen:
        return subprocess.Popen(self.command(name, argv), **kwargs)

    def set_link(self, name: str, up: bool) -> None:
        """Unplug (``up=False``) or plug back host ``name``'s cable: its port on the bridge goes down/up.

        The host keeps its address and routes (its ``eth0`` only loses the carrier), as with a pulled cable.
        """
        _ip("link", "set", self.ports[name], "up" if up else "down", netns=self.switch)

    def close(self) -> None:
        """Kill the processes left inside the lab's namespaces, then delete every namespace this lab created
        (their veth pairs and the bridge go with them)."""
        for netns in self.created:
            for pid in _ip("netns", "pids", netns, check=False).stdout.split():
                try:
                    os.kill(int(pid), signal.SIGKILL)
                except ProcessLookupError:  # ended meanwhile
                    pass
        while self.created:
            _ip("netns", "del", self.created.pop(), check=False)

    def __enter__(self) -> NetLab:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.close()


def network_environment(domain_id: int, base: dict[str, str] | None = None) -> dict[str, str]:
    """Environment for nodes that talk over the lab's links: the domain, SUBNET discovery, UDP only."""
    env = dict(os.environ if base is None else base)
    env.update({
        "ROS_DOMAIN_ID": str(domain_id),
        "ROS_AUTOMATIC_DISCOVERY_RANGE": "SUBNET",
        "FASTDDS_BUILTIN_TRANSPORTS": "UDPv4",
        "PYTHONUNBUFFERED": "1",
        "MPLBACKEND": "Agg",
    })
    env.pop("ROS_LOCALHOST_ONLY", None)
    return env
