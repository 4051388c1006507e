"""Watching a flight live: the recording's topics served over the Foxglove WebSocket protocol
(:class:`~fsr_bringup.live.server.LiveServer`), at the address ``--live [PORT]`` and ``--live-host`` name
(:mod:`fsr_bringup.live.endpoint`); an in-process flight paced to be watched (:mod:`fsr_bringup.live.pacing`).

    from fsr_bringup import simulate
    from fsr_bringup.live import serve
    with serve(8765) as live:                          # Foxglove: Open connection -> ws://localhost:8765
        simulate("ex4_geometric", live=live)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from fsr_bringup.live.endpoint import DEFAULT_HOST, DEFAULT_PORT, LiveEndpoint

if TYPE_CHECKING:
    from fsr_bringup.live.server import LiveServer


def serve(port: int = DEFAULT_PORT, host: str = DEFAULT_HOST) -> LiveServer:
    """A live server for ``host:port`` (0: a free port), checked now (ValueError naming the address and the reason
    if it cannot be bound): the flight given it starts it once its topics are known; stopped by ``stop()`` or at
    the end of a ``with`` block."""
    from fsr_bringup.live.endpoint import reserve
    from fsr_bringup.live.server import LiveServer

    return LiveServer(reserve(LiveEndpoint(host, port)))
