"""Where a flight is served live: ``--live [PORT]`` and ``--live-host ADDRESS`` of ``fsr-fly`` and ``fsr-record``.

The port is checked before anything is flown or recorded (:func:`reserve`): a bad port, an address that is not
on this machine or a port in use is one line and exit code 2. Port 0 takes a free port (the one taken is
printed with the address to connect to).
"""

from __future__ import annotations

import argparse
import errno
import socket
from dataclasses import dataclass

DEFAULT_PORT = 8765  # Foxglove's (and foxglove_bridge's) default
DEFAULT_HOST = "127.0.0.1"  # this machine only; 0.0.0.0 (or an interface's address) for other hosts
SUBPROTOCOL = "foxglove.sdk.v1"  # the WebSocket subprotocol the Foxglove SDK's server speaks


@dataclass(frozen=True)
class LiveEndpoint:
    """The address and port a live server binds to."""

    host: str = DEFAULT_HOST
    port: int = DEFAULT_PORT

    @property
    def url(self) -> str:
        """What a viewer connects to (an address that binds every interface is reached by this host's name)."""
        host = socket.gethostname() if self.host in ("0.0.0.0", "::", "") else self.host
        return f"ws://[{host}]:{self.port}" if ":" in host else f"ws://{host}:{self.port}"


def parse_port(text: str) -> int:
    """A TCP port, 0 (a free one) to 65535; ValueError names the problem."""
    try:
        port = int(text)
    except ValueError:
        raise ValueError(f"expected a port number (0-65535), got '{text}'") from None
    if not 0 <= port <= 65535:
        raise ValueError(f"a port is 0-65535 (0: a free one), got {port}")
    return port


def add_live_arguments(parser: argparse.ArgumentParser, what: str) -> None:
    """``--live [PORT]`` and ``--live-host ADDRESS``; ``what`` says what is served."""
    from fsr_sim.cli.arguments import argument_type

    parser.add_argument(
        "--live", nargs="?", const=DEFAULT_PORT, type=argument_type(parse_port), metavar="PORT",
        help=f"serve {what} live over the Foxglove WebSocket protocol on PORT (default {DEFAULT_PORT}; 0: a free "
             "one): in Foxglove, Open connection -> Foxglove WebSocket -> ws://HOST:PORT, then import the layout "
             "docs/foxglove/fsr.json",
    )
    parser.add_argument(
        "--live-host", default=DEFAULT_HOST, metavar="ADDRESS",
        help=f"address the live server binds (default {DEFAULT_HOST}: this machine only; 0.0.0.0: every "
             "interface, anyone who reaches the port may watch)",
    )


def endpoint_of(args: argparse.Namespace) -> LiveEndpoint | None:
    """The endpoint ``--live`` asks for (None: not served live)."""
    return None if args.live is None else LiveEndpoint(args.live_host, args.live)


_REASONS = {errno.EADDRINUSE: "the port is in use (another live flight, a foxglove_bridge?): choose another with "
                              "--live PORT",
            errno.EADDRNOTAVAIL: "the address is not one of this machine's",
            errno.EACCES: "permission denied (ports below 1024 need privileges)"}


def reserve(endpoint: LiveEndpoint) -> LiveEndpoint:
    """Check that ``endpoint`` can be bound now (port 0: pick a free port) and return it with its port; ValueError
    names the address and the reason. The port is released again for the server to bind."""
    where = f"{endpoint.host}:{endpoint.port}"
    try:
        family, kind, proto, _, address = socket.getaddrinfo(endpoint.host, endpoint.port, type=socket.SOCK_STREAM,
                                                             flags=socket.AI_PASSIVE)[0]
    except (socket.gaierror, UnicodeError) as error:
        raise ValueError(f"cannot serve live on {where}: unknown address ({error})") from None
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the server's own listener does
        try:
            probe.bind(address)
        except OSError as error:
            reason = _REASONS.get(error.errno, error.strerror or str(error))
            raise ValueError(f"cannot serve live on {where}: {reason}") from None
        return LiveEndpoint(endpoint.host, probe.getsockname()[1])
