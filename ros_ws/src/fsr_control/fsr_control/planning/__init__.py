"""Trajectory planning: rest-to-rest 7th-order polynomials, waypoint trajectories, flat feed-forward."""

from fsr_control.planning.trajectory import Reference, Trajectory, Waypoint

__all__ = ["Reference", "Trajectory", "Waypoint"]
