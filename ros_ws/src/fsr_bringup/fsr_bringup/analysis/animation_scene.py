"""What the flight's animation shows at each frame, as numpy arrays over all frames at once (no matplotlib).

**View frame.** The recording's world frame is NED (x north, y east, z down; docs/model.md §4). The scene is
given in the right-handed east-north-up frame, ``v = (y, x, -z)`` (:data:`NED_TO_VIEW`, a rotation: det +1), so
that up is drawn up and the vehicle is not upside down. Body vectors (rotor positions ``p_i``, thrust axes
``z_i``, wrenches: body FRD) go to the world by the odometry's ``R`` (body FRD -> world NED), then to the view:
``x_v = N (p + R b)`` for a body point ``b``, ``N R f`` for a body vector ``f``.

**Frames.** Frame ``k`` shows the simulated time ``t_k = t_0 + k s / f`` (``f`` frames per second of video, ``s``
the speed: simulated seconds per second of video), ``k = 0 .. floor((t_end - t_0) f / s)``: the video lasts the
flight's duration divided by ``s``, plus one frame. Every quantity is its last sample at or before ``t_k``
(zero-order hold); a topic with no sample yet is not drawn (NaN).

**Arrows** start at the rotor centres (thrust) or the centre of mass (forces) and are drawn to scale, in metres
of the scene per newton:

* rotor thrust ``T_i = c_f |w_i| w_i`` along ``z_i = Rot(a_i, alpha_i) z_0,i`` (the plant's vehicle; speeds and
  tilts from ``rotor_state``, the rotors' actual ones, else ``rotor_cmd``; without the ground or ceiling
  effect), with hover thrust (weight / rotor count) one arm length long; in wrench actuation (no rotors) one
  arrow, the commanded body force ``wrench_cmd``, the weight one arm length long;
* the external force ``wrench_truth`` (true, disturbances and drag) and the observer's ``wrench_estimate``
  (which also holds what its model misses, docs/analysis.md), both to one scale: the largest of them two arm
  lengths long, or a tenth of the weight if the largest is smaller (no rounding noise blown up to full size).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fsr_bringup.analysis.load import RecordedFlight, RotorCommand, Wrench, zero_order_hold
from fsr_bringup.visualization.frames import NED_TO_ENU
from fsr_sim.model.rotors import rotor_axes
from fsr_sim.model.vehicle import Vehicle

NED_TO_VIEW = NED_TO_ENU  # (north, east, down) -> (east, north, up): the view is map's frame (REP 103)
TRAIL_POINTS = 3000  # the trail and the planned path are drawn through at most this many samples
DISC_POINTS = 24  # vertices of a rotor disc's outline
HEAD_FRACTION = 0.22  # arrow head length / arrow length
NO_VEHICLE_UNIT_M = 0.2  # arrow unit [m] when the recording holds no vehicle (no scenario in its metadata)
EXTERNAL_ARMS = 2.0  # the largest external force is drawn this many arm lengths long
EXTERNAL_FLOOR_WEIGHTS = 0.1  # ... unless smaller than this fraction of the weight: then drawn shorter
EXTERNAL_FLOOR_N = 1.0  # the same floor [N] when the recording holds no vehicle


@dataclass
class Arrows:
    """Arrows per frame in the view frame: ``tails`` and ``vectors`` (F, m, 3) [m as drawn], ``metres_per_newton``
    the scale, ``label`` what they are."""

    tails: np.ndarray
    vectors: np.ndarray
    metres_per_newton: float
    label: str


@dataclass
class Scene:
    """The animation's content, all in the view frame (east, north, up) [m], F frames."""

    times: np.ndarray  # (F,) simulated time of each frame [s]
    centre: np.ndarray  # (F, 3) centre of mass
    trail: np.ndarray  # (T, 3) the flown path through at most TRAIL_POINTS samples
    trail_counts: np.ndarray  # (F,) trail points flown by frame k (then the centre itself)
    rotors: np.ndarray | None = None  # (F, n, 3) rotor centres (None: no vehicle in the recording)
    discs: np.ndarray | None = None  # (F, n, DISC_POINTS + 1, 3) closed outlines of the rotor discs
    thrust: Arrows | None = None
    external_truth: Arrows | None = None
    external_estimate: Arrows | None = None
    reference: np.ndarray | None = None  # (R, 3) the planned path
    bounds: np.ndarray = field(default_factory=lambda: np.array([[-1.0, 1.0]] * 3))  # (3, 2) low, high per axis
    notes: list[str] = field(default_factory=list)

    @property
    def frame_count(self) -> int:
        return int(self.times.size)


def view_of(ned: np.ndarray) -> np.ndarray:
    """Points or vectors (..., 3) in world NED -> the view frame (east, north, up)."""
    return np.asarray(ned, dtype=float) @ NED_TO_VIEW.T


def frame_stamps(start_ns: int, end_ns: int, fps: float, speed: float) -> np.ndarray:
    """Simulated stamps [ns] of the frames: ``t_0 + k s / f`` for ``k = 0 .. floor((t_end - t_0) f / s)``."""
    step_ns = speed / fps * 1e9
    count = int(math.floor((end_ns - start_ns) / step_ns + 1e-9)) + 1
    return start_ns + np.round(np.arange(count) * step_ns).astype(np.int64)


def world_points(position: np.ndarray, rotation: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``p + R b``: body points ``b`` (n, 3) or (F, n, 3) at poses ``p`` (F, 3), ``R`` (F, 3, 3) -> (F, n, 3)."""
    return position[:, None, :] + world_vectors(rotation, body)


def world_vectors(rotation: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``R f``: body vectors ``f`` (n, 3) or (F, n, 3) by ``R`` (F, 3, 3) -> (F, n, 3)."""
    body = np.broadcast_to(body, (rotation.shape[0], *np.shape(body)[-2:]))
    return np.einsum("fij,fnj->fni", rotation, body)


def rotor_axes_body(vehicle: Vehicle, tilts: np.ndarray | None, frames: int) -> np.ndarray:
    """Thrust axes ``z_i`` (body FRD, unit), (F, n, 3), at tilt angles ``alpha`` (F, n) [rad] (NaN, or None: the
    fixed axes ``z_0,i``): :func:`fsr_sim.model.rotors.rotor_axes`."""
    axes = rotor_axes(vehicle, None if tilts is None else np.nan_to_num(tilts, nan=0.0))
    return np.broadcast_to(axes, (frames, vehicle.rotor_count, 3)).copy()


def disc_outlines(centres: np.ndarray, axes: np.ndarray, radius: float, points: int = DISC_POINTS) -> np.ndarray:
    """Closed outlines (..., points + 1, 3) of discs of ``radius`` around ``centres`` (..., 3), normal to the unit
    ``axes`` (..., 3): ``c + r (cos theta u + sin theta w)`` with ``u, w`` unit, normal to the axis and each other."""
    helper = np.where(np.abs(axes[..., :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    u = np.cross(axes, helper)
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    w = np.cross(axes, u)
    theta = np.linspace(0.0, 2.0 * np.pi, points + 1)[:, None]
    return centres[..., None, :] + radius * (np.cos(theta) * u[..., None, :] + np.sin(theta) * w[..., None, :])


def arrow_lines(tails: np.ndarray, vectors: np.ndarray, towards_viewer: np.ndarray) -> np.ndarray:
    """Line segments (..., 3, 2, 3) drawing arrows from ``tails`` along ``vectors`` (..., 3): the shaft and the two
    sides of the head, in the plane of the arrow and ``towards_viewer`` (unit, the view's direction to the camera)
    so the head faces the camera. A zero or NaN vector gives NaN segments (nothing drawn)."""
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = vectors / length
        side = np.cross(direction, towards_viewer)
        side_norm = np.linalg.norm(side, axis=-1, keepdims=True)
        side = np.where(side_norm > 1e-9, side / side_norm, 0.0)
    tips = tails + vectors
    back = tips - HEAD_FRACTION * vectors
    half_width = 0.5 * HEAD_FRACTION * length * side
    lines = np.stack([np.stack([tails, tips], axis=-2),
                      np.stack([tips, back + half_width], axis=-2),
                      np.stack([tips, back - half_width], axis=-2)], axis=-3)
    hidden = ~(length[..., 0] > 0)  # zero or NaN
    lines[hidden] = np.nan
    return lines


def decimated(count: int, points: int = TRAIL_POINTS) -> np.ndarray:
    """Indices of at most ``points`` samples out of ``count``, evenly spaced, the last one included."""
    step = max(1, math.ceil(count / points))
    return np.unique(np.append(np.arange(0, count, step), count - 1))


def build_scene(flight: RecordedFlight, fps: float, speed: float) -> Scene:
    """The scene of ``flight`` at ``fps`` frames per second of video and ``speed`` (ValueError without odometry)."""
    odom = flight.true_odom  # the true state (a measured odom beside odom_truth: the vehicle as it flew)
    if odom is None or odom.t.size == 0:
        raise ValueError(f"{flight.recording.path}: no odometry ({flight.namespace.rstrip('/')}/odom): nothing to "
                         "animate")
    stamps = frame_stamps(int(odom.stamp_ns[0]), int(odom.stamp_ns[-1]), fps, speed)
    index = np.searchsorted(odom.stamp_ns, stamps, side="right") - 1  # >= 0: the frames start at the first sample
    position, rotation = odom.position[index], odom.rotation[index]
    kept = decimated(odom.t.size)
    scene = Scene(times=stamps * 1e-9, centre=view_of(position), trail=view_of(odom.position[kept]),
                  trail_counts=np.searchsorted(odom.stamp_ns[kept], stamps, side="right"))
    vehicle = flight.config.plant_vehicle if flight.config is not None else None
    axes_world = None
    if vehicle is not None:
        unit = vehicle.arm_length
        axes_body = rotor_axes_body(vehicle, _rotor_tilts(flight, stamps), stamps.size)
        rotors = world_points(position, rotation, vehicle.positions)
        axes_world = world_vectors(rotation, axes_body)
        scene.rotors = view_of(rotors)
        scene.discs = view_of(disc_outlines(rotors, axes_world, vehicle.rotor_radius))
    else:
        extent = np.ptp(scene.trail, axis=0).max() if scene.trail.shape[0] > 1 else 0.0
        unit = max(0.1 * extent, NO_VEHICLE_UNIT_M)
        scene.notes.append("no vehicle in the recording (no scenario in its metadata): no rotors drawn")
    scene.thrust = _thrust(flight, vehicle, stamps, rotation, scene, axes_world, unit)
    floor = EXTERNAL_FLOOR_WEIGHTS * vehicle.weight if vehicle is not None else EXTERNAL_FLOOR_N
    scene.external_truth, scene.external_estimate = _external(flight, stamps, rotation, scene.centre, unit, floor)
    if flight.reference is not None and flight.reference.t.size:
        scene.reference = view_of(flight.reference.position[decimated(flight.reference.t.size)])
    scene.bounds = _bounds(scene, unit + (vehicle.rotor_radius if vehicle is not None else 0.0))
    return scene


def _rotors(flight: RecordedFlight) -> RotorCommand | None:
    """The rotors' actual speeds and tilts (``rotor_state``, recorded with actuator dynamics), else the commands."""
    return flight.rotor_state if flight.rotor_state is not None else flight.rotor_cmd


def _rotor_tilts(flight: RecordedFlight, stamps: np.ndarray) -> np.ndarray | None:
    rotors = _rotors(flight)
    if rotors is None or rotors.tilts is None:
        return None
    return zero_order_hold(rotors.stamp_ns, rotors.tilts, stamps)


def _thrust(flight: RecordedFlight, vehicle: Vehicle | None, stamps: np.ndarray, rotation: np.ndarray,
            scene: Scene, axes_world: np.ndarray | None, unit: float) -> Arrows | None:
    """Per-rotor thrust arrows (hover thrust ``unit`` long), or the commanded body force of wrench actuation (the
    weight ``unit`` long; without a vehicle, the median commanded force); None, with a note, without either."""
    rotors = _rotors(flight)
    if rotors is not None and vehicle is not None:
        scale = unit / (vehicle.weight / vehicle.rotor_count)
        speeds = zero_order_hold(rotors.stamp_ns, rotors.speeds, stamps)[:, : vehicle.rotor_count]
        thrust = vehicle.c_f * np.abs(speeds) * speeds  # [N], NaN before the first command
        which = "actual" if flight.rotor_state is not None else "commanded"
        return Arrows(scene.rotors, scale * thrust[..., None] * view_of(axes_world), scale,
                      f"{which} rotor thrust (1 m = {1.0 / scale:.3g} N)")
    command = flight.wrench_cmd
    if command is not None:
        reference = vehicle.weight if vehicle is not None else float(np.median(np.linalg.norm(command.force, axis=1)))
        scale = unit / reference if reference > 0 else 1.0
        force = zero_order_hold(command.stamp_ns, command.force, stamps)
        vectors = view_of(world_vectors(rotation, force[:, None, :]))
        return Arrows(scene.centre[:, None, :], scale * vectors, scale, f"commanded force (1 m = {1.0 / scale:.3g} N)")
    scene.notes.append("no rotor_cmd and no wrench_cmd: no thrust arrows")
    return None


def _external(flight: RecordedFlight, stamps: np.ndarray, rotation: np.ndarray, centre: np.ndarray,
              unit: float, floor: float) -> tuple[Arrows | None, Arrows | None]:
    """The true and the estimated external force, at the centre of mass, to one scale: the largest of them (or
    ``floor`` [N] if larger) ``EXTERNAL_ARMS`` arm lengths long."""
    def world_force(wrench: Wrench | None) -> np.ndarray | None:
        if wrench is None:
            return None
        force = zero_order_hold(wrench.stamp_ns, wrench.force, stamps)
        return view_of(world_vectors(rotation, force[:, None, :]))

    truth, estimate = world_force(flight.wrench_truth), world_force(flight.wrench_estimate)
    present = [f for f in (truth, estimate) if f is not None]
    if not present:
        return None, None
    largest = max(float(np.nanmax(np.linalg.norm(f, axis=-1), initial=0.0)) for f in present)
    scale = EXTERNAL_ARMS * unit / max(largest, floor)  # forces far below the floor stay short (rounding noise)
    tails = centre[:, None, :]
    true_label = f"external force, true (1 m = {1.0 / scale:.3g} N)"
    return (None if truth is None else Arrows(tails, scale * truth, scale, true_label),
            None if estimate is None else Arrows(tails, scale * estimate, scale, "external force, estimate"))


def _bounds(scene: Scene, reach: float) -> np.ndarray:
    """Axis limits (3, 2) holding everything drawn (plus a margin), with sides of at least a third of the longest
    so that a level flight is not drawn in a flat box."""
    parts = [scene.trail, scene.centre]
    if scene.rotors is not None:
        parts.append(scene.rotors.reshape(-1, 3))
    if scene.reference is not None:
        parts.append(scene.reference)
    for arrows in (scene.thrust, scene.external_truth, scene.external_estimate):
        if arrows is not None:
            parts.append((arrows.tails + arrows.vectors).reshape(-1, 3))
    points = np.concatenate(parts)
    points = points[np.isfinite(points).all(axis=1)]  # NaN: not drawn (no sample yet); a diverged state's inf
    if points.size == 0:
        raise ValueError("the odometry holds no finite position: nothing to animate")
    low, high = points.min(axis=0) - reach, points.max(axis=0) + reach
    middle, half = (low + high) / 2, (high - low) / 2
    half = np.maximum(half, half.max() / 3)
    return np.stack([middle - half, middle + half], axis=1)
