"""The ``trajectory`` section of a scenario, validated: what is flown (``kind``) and how it is checked.

```yaml
trajectory:
  kind: waypoints                   # waypoints (default: rest-to-rest legs) | minsnap | circle | lissajous
  # kind: waypoints
  waypoints:                        # flown in order, each rest-to-rest from the previous one
    - position: [1, 1, -4]          # world NED [m]
      attitude_rpy_deg: [0, 0, 20]  # optional (default: the previous waypoint's / initial attitude);
                                    # fixed-rotor vehicles take only yaw (roll and pitch must be 0)
      duration: 20.0                # travel time [s] > 0
      hold: 0.0                     # optional wait after arrival [s] >= 0
  # kind: minsnap (minimum snap through the points, from the initial position, at rest at both ends)
  waypoints: [{position: [2, 0, -2], duration: 2.0}, {position: [2, 2, -3], duration: 1.5}]
  speed: 4.0                        # [m/s] the path's peak speed (instead of every point's duration)
  # kind: circle
  centre: [0, 0, -2]                # world NED [m]
  radius: 2.0                       # [m]
  plane: xy                         # xy | xz | yz, or normal: [nx, ny, nz] (world NED)
  speed: 3.0                        # [m/s] along the circle, or period: [s] per lap
  laps: 2                           # or duration: [s] of the path, ramps included
  direction: counterclockwise       # | clockwise, seen from the side the normal points to (xy: from above)
  # kind: lissajous
  centre: [0, 0, -2]                # world NED [m]
  amplitude: [2, 1, 0]              # [m] per world axis
  frequency: [0.2, 0.4, 0]          # [Hz] per world axis
  phase_deg: [0, 0, 0]              # [deg] per world axis
  laps: 1                           # periods of the whole figure, or duration: [s]
  # minsnap, circle, lissajous
  ramp: 1.5                         # [s] the speed ramps at both ends (circle, lissajous; default half the period
                                    # of the fastest axis) and the yaw's (default 1 s, at most a quarter)
  yaw: {mode: velocity}             # fixed (yaw_deg, default the initial yaw) | velocity | rate (rate_deg_s)
  approach_duration: 3.0            # [s] the rest-to-rest leg from the initial pose to the path's start pose
                                    # (default: at least 2 s, at half the path's peak speed)
  # every kind
  goal_duration: 10.0               # travel time [s] of a goal received at run time (`goal` topic)
  authority_margin: 0.7             # in (0, 1]: the share of the model's authority at hover
                                    # (fsr_control.design.authority) that references may use
  feasibility: stretch              # a leg, goal or path beyond it, with rotor actuation: stretch (a leg's angle
                                    # shaped or the leg lengthened, a path flown slower) | warn (flown as
                                    # written) | refuse (exit 2 before take-off)
```

Keys of another kind are refused with the kinds they belong to; unknown keys with a typo hint.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fsr_control.planning.feasibility import DEFAULT_FEASIBILITY, FEASIBILITY_MODES
from fsr_control.planning.paths import (
    CIRCLE_NORMALS,
    DIRECTIONS,
    PATH_KINDS,
    YAW_MODES,
    CirclePath,
    LissajousPath,
    MinSnapPath,
    PathSpec,
    YawSpec,
    common_period,
)
from fsr_control.planning.trajectory import Waypoint
from fsr_sim.config.validation import Section
from fsr_sim.model.so3 import rotation_from_euler_zyx
from fsr_sim.model.vehicle import Vehicle

DEFAULT_GOAL_DURATION = 10.0  # s
DEFAULT_AUTHORITY_MARGIN = 0.7  # share of the model's authority at hover (fsr_control.design.authority)
COMMON_KEYS = ("kind", "goal_duration", "authority_margin", "feasibility")
PATH_KEYS = ("ramp", "yaw", "approach_duration")  # minsnap, circle, lissajous
KIND_KEYS = {  # the keys of each kind besides COMMON_KEYS
    "waypoints": ("waypoints",),
    "minsnap": ("waypoints", "speed", *PATH_KEYS),
    "circle": ("centre", "radius", "plane", "normal", "speed", "period", "laps", "duration", "direction",
               *PATH_KEYS),
    "lissajous": ("centre", "amplitude", "frequency", "phase_deg", "laps", "duration", *PATH_KEYS),
}


@dataclass(frozen=True, eq=False)
class TrajectoryConfig:
    """The validated ``trajectory`` section: the kind, its waypoints (kind ``waypoints``) or path with the key that
    sets how fast it flies (``timing_key``: named when it is infeasible), and the check."""

    kind: str
    waypoints: list[Waypoint]
    path: PathSpec | None
    timing_key: str
    goal_duration: float
    authority_margin: float
    feasibility: str


def _reject_other_kinds(section: Section, kind: str) -> None:
    """A key of another kind names the kinds it belongs to."""
    own = set(COMMON_KEYS) | set(KIND_KEYS[kind])
    for key in section.data:
        if key in own:
            continue
        kinds = [name for name, keys in KIND_KEYS.items() if key in keys]
        if kinds:
            raise section.error(key, f"is a key of kind {' and '.join(kinds)}, not of kind {kind} "
                                     f"(trajectory.kind: {' | '.join(PATH_KINDS)})")


def _entries(section: Section) -> list[Section]:
    raw = section.raw("waypoints", [])
    if not isinstance(raw, list):
        raise section.error("waypoints", f"must be a list, got {type(raw).__name__}")
    return [Section(item, section.key(f"waypoints.{index}"), section.source) for index, item in enumerate(raw)]


def _waypoints(section: Section, vehicle: Vehicle) -> list[Waypoint]:
    """``kind: waypoints``: the rest-to-rest legs."""
    waypoints = []
    for entry in _entries(section):
        position = entry.vector("position", 3)
        rotation = None
        if entry.has("attitude_rpy_deg"):
            rpy = entry.vector("attitude_rpy_deg", 3)
            if not vehicle.fully_actuated and np.any(np.abs(rpy[:2]) > 1e-9):
                raise entry.error(
                    "attitude_rpy_deg",
                    f"roll and pitch must be 0 for '{vehicle.name}', which is not fully actuated (only yaw can be "
                    f"commanded), got {rpy.tolist()}",
                )
            rotation = rotation_from_euler_zyx(np.deg2rad(rpy))
        duration = entry.number("duration", strictly_positive=True)
        hold = entry.number("hold", 0.0, minimum=0.0)
        entry.reject_unknown()
        waypoints.append(Waypoint(position, rotation, duration, hold))
    return waypoints


def _yaw(section: Section) -> YawSpec:
    """``yaw``: a mode name, or ``{mode, yaw_deg (fixed), rate_deg_s (rate)}``."""
    raw = section.raw("yaw", {"mode": "fixed"})
    yaw = Section({"mode": raw} if isinstance(raw, str) else raw, section.key("yaw"), section.source)
    mode = yaw.string("mode", "fixed", choices=YAW_MODES)
    spec = YawSpec(mode)
    if mode == "fixed" and yaw.has("yaw_deg"):
        spec = YawSpec(mode, math.radians(yaw.number("yaw_deg")))
    elif mode == "rate":
        spec = YawSpec(mode, rate=math.radians(yaw.number("rate_deg_s")))
    for key, owner in (("yaw_deg", "fixed"), ("rate_deg_s", "rate")):
        if key in yaw.data and mode != owner:
            raise yaw.error(key, f"is for mode {owner}, not {mode}")
    yaw.reject_unknown()
    return spec


def _one_of(section: Section, first: str, second: str, default: str | None = None) -> str:
    """The one of two exclusive keys given (``default`` when neither is and there is one)."""
    given = [key for key in (first, second) if section.has(key)]
    if len(given) == 2:
        raise section.error(second, f"give {first} or {second}, not both")
    if not given and default is None:
        raise section.error(first, f"is required (or {second})")
    return given[0] if given else default


def _ramp(section: Section, default: float) -> float:
    return section.number("ramp", default, strictly_positive=True)


def _approach(section: Section) -> float | None:
    return section.number("approach_duration", strictly_positive=True) if section.has("approach_duration") else None


def _minsnap(section: Section, start: np.ndarray) -> tuple[MinSnapPath, str]:
    entries = _entries(section)
    if not entries:
        raise section.error("waypoints", "a minsnap path needs at least one point to pass through")
    points, durations = [], []
    previous = np.asarray(start, dtype=float)
    for entry in entries:
        for key, why in (("attitude_rpy_deg", "the yaw of a minsnap path is trajectory.yaw"),
                         ("hold", "a minsnap path passes through its points without stopping")):
            if key in entry.data:
                raise entry.error(key, f"is for kind waypoints: {why}")
        position = entry.vector("position", 3)
        if np.linalg.norm(position - previous) < 1e-9:
            where = "the start (initial_state.position)" if not points else "the point before it"
            raise entry.error("position", f"is {where}: a minsnap path passes through each point once")
        points.append(position)
        durations.append(entry.number("duration", strictly_positive=True) if entry.has("duration") else None)
        entry.reject_unknown()
        previous = position
    timed = [value is not None for value in durations]
    speed = section.number("speed", strictly_positive=True) if section.has("speed") else None
    if any(timed) and not all(timed):
        index = timed.index(False)
        raise section.error(f"waypoints.{index}.duration", "give every point a duration, or none (trajectory.speed)")
    if all(timed) and speed is not None:
        raise section.error("speed", "give the points' durations or speed, not both")
    if not all(timed) and speed is None:
        raise section.error("speed", "is required (the path's peak speed [m/s]), or every point's duration")
    total = sum(durations) if all(timed) else None
    ramp = _ramp(section, 1.0) if section.has("ramp") else None
    if ramp is not None and total is not None and ramp > 0.5 * total:
        raise section.error("ramp", f"must be at most half the path's duration ({0.5 * total:g} s), got {ramp:g}")
    path = MinSnapPath(points=np.array(points), durations=np.array(durations) if all(timed) else None, speed=speed,
                       yaw=_yaw(section), ramp=ramp, approach_duration=_approach(section))
    return path, "speed" if speed is not None else "waypoints"


def _clock(section: Section, period: float, fastest: float) -> tuple[float, float]:
    """(duration, ramp) [s] of a periodic path of ``period`` [s] per lap and fastest axis period ``fastest`` [s]."""
    key = _one_of(section, "laps", "duration", "laps")
    ramp = _ramp(section, 0.5 * fastest)
    if key == "laps":
        path_time = section.number("laps", 1.0, strictly_positive=True) * period
        if ramp > path_time:
            raise section.error("ramp", f"must be at most the laps' time ({path_time:g} s) so that the path keeps "
                                        f"its speed between the ramps, got {ramp:g}")
        return path_time + ramp, ramp
    duration = section.number("duration", strictly_positive=True)
    if ramp > 0.5 * duration:
        raise section.error("ramp", f"must be at most half the path's duration ({0.5 * duration:g} s), got {ramp:g}")
    return duration, ramp


def _circle(section: Section) -> tuple[CirclePath, str]:
    centre = section.vector("centre", 3)
    radius = section.number("radius", strictly_positive=True)
    if _one_of(section, "plane", "normal", "plane") == "plane":
        normal = np.array(CIRCLE_NORMALS[section.string("plane", "xy", choices=tuple(CIRCLE_NORMALS))])
    else:
        normal = section.vector("normal", 3)
        if np.linalg.norm(normal) < 1e-9:
            raise section.error("normal", f"must not be zero, got {normal.tolist()}")
        normal = normal / np.linalg.norm(normal)
    timing = _one_of(section, "speed", "period")
    if timing == "speed":
        rate = section.number("speed", strictly_positive=True) / radius
    else:
        rate = 2.0 * math.pi / section.number("period", strictly_positive=True)
    period = 2.0 * math.pi / rate
    duration, ramp = _clock(section, period, period)
    path = CirclePath(centre=centre, radius=radius, normal=normal, rate=rate,
                      direction=section.string("direction", "counterclockwise", choices=DIRECTIONS),
                      duration=duration, ramp=ramp, yaw=_yaw(section), approach_duration=_approach(section))
    return path, timing


def _lissajous(section: Section) -> tuple[LissajousPath, str]:
    centre = section.vector("centre", 3)
    amplitude = section.vector("amplitude", 3)
    frequency = section.vector("frequency", 3)
    if np.any(frequency < 0.0):
        raise section.error("frequency", f"must be >= 0 Hz on every axis, got {frequency.tolist()}")
    moving = (amplitude != 0.0) & (frequency > 0.0)
    if not moving.any():
        raise section.error("amplitude", "no axis moves: give an axis a non-zero amplitude and frequency")
    phase = np.radians(section.vector("phase_deg", 3, [0.0, 0.0, 0.0]))
    fastest = 1.0 / frequency[moving].max()
    period = common_period(frequency[moving])
    if period is None and not section.has("duration"):
        raise section.error("laps", f"the frequencies {frequency[moving].tolist()} Hz have no common period (laps of "
                                    "the figure): give trajectory.duration instead")
    duration, ramp = _clock(section, period if period is not None else fastest, fastest)
    path = LissajousPath(centre=centre, amplitude=amplitude, frequency=2.0 * math.pi * frequency * moving,
                         phase=phase, duration=duration, ramp=ramp, yaw=_yaw(section),
                         approach_duration=_approach(section))
    return path, "frequency"


def trajectory_config(section: Section, vehicle: Vehicle, start: np.ndarray) -> TrajectoryConfig:
    """Validate the ``trajectory`` section (module docstring) for ``vehicle`` starting at ``start`` [m]."""
    kind = section.string("kind", "waypoints", choices=PATH_KINDS)
    _reject_other_kinds(section, kind)
    waypoints: list[Waypoint] = []
    path, timing_key = None, "waypoints"
    if kind == "waypoints":
        waypoints = _waypoints(section, vehicle)
    else:
        path, timing_key = {"minsnap": lambda: _minsnap(section, start), "circle": lambda: _circle(section),
                            "lissajous": lambda: _lissajous(section)}[kind]()
    goal_duration = section.number("goal_duration", DEFAULT_GOAL_DURATION, strictly_positive=True)
    authority_margin = section.number("authority_margin", DEFAULT_AUTHORITY_MARGIN)
    if not 0.0 < authority_margin <= 1.0:
        raise section.error("authority_margin", f"must be in (0, 1] (the share of the vehicle's authority at "
                                                f"hover that references may use), got {authority_margin}")
    feasibility = section.string("feasibility", DEFAULT_FEASIBILITY, choices=FEASIBILITY_MODES)
    section.reject_unknown()
    return TrajectoryConfig(kind, waypoints, path, timing_key, goal_duration, authority_margin, feasibility)
