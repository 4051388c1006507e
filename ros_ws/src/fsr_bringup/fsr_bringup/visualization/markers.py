"""``markers`` (``visualization_msgs/msg/MarkerArray``): the vehicle as a viewer draws it, all in ``world_ned``.

One array per marker step (:class:`~fsr_bringup.visualization.config.VisualizationConfig`), each marker stamped
with the step's state and ``frame_id`` ``world_ned`` (drawn from the recorded pose: no TF lookup needed, live or
in a recording). Namespaces (``ns``) and what they show, ``a`` being the vehicle's arm length:

* ``arms``: a line from the centre of mass to each rotor;
* ``rotors``: a disc per rotor (diameter ``2 r_rotor``) normal to its thrust axis (tilted with its servo), coloured
  by ``(w - w_min) / (w_max - w_min)`` from blue (at ``w_min``) through grey to red (at ``w_max``);
* ``thrust``: per rotor an arrow along its thrust axis, ``a`` long at the hover thrust ``m g / n`` and in
  proportion to ``c_f w^2`` (out of ground effect);
* ``force_true`` and ``force_estimate``: the external force (``wrench_truth``, ``wrench_estimate``: body frame, drawn
  in the world) from the centre of mass, ``a`` long for a quarter of the weight;
* ``reference_position``: the reference position; ``goal_position``: the last waypoint (or the last ``goal``
  received);
  ``path``: the scenario's planned path; ``ground`` and ``ceiling``: the surfaces a scenario enables.

Each array has the same layout (:class:`fsr_sim.ros.cdr_pack.StampedNumbers`), packed for many steps at once;
a marker's constant fields are written once into the template.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fsr_bringup.visualization.frames import axis_quaternions
from fsr_sim.contract import WORLD_FRAME
from fsr_sim.model.environment import Environment
from fsr_sim.model.rotors import rotor_axes
from fsr_sim.model.so3 import rotations_from_quaternions
from fsr_sim.model.vehicle import Vehicle
from fsr_sim.ros.cdr_pack import StampedNumbers, Template

ARROW, CUBE, SPHERE, CYLINDER, LINE_STRIP, LINE_LIST = 0, 1, 2, 3, 4, 5  # visualization_msgs/Marker types
FORCE_PER_ARM = 0.25  # an external force of this fraction of the weight is drawn one arm length long
SPEED_COLOURS = np.array(((0.23, 0.30, 0.75, 1.0), (0.87, 0.87, 0.87, 1.0), (0.71, 0.02, 0.15, 1.0)))
GREY = (0.3, 0.3, 0.3, 1.0)
THRUST_COLOUR = (1.0, 0.6, 0.0, 0.9)
TRUE_FORCE_COLOUR = (0.85, 0.1, 0.1, 1.0)
ESTIMATE_COLOUR = (0.1, 0.7, 0.2, 1.0)
REFERENCE_COLOUR = (0.1, 0.4, 1.0, 1.0)
PATH_COLOUR = (0.1, 0.4, 1.0, 0.6)
GOAL_COLOUR = (0.1, 0.4, 1.0, 0.4)
GROUND_COLOUR = (0.5, 0.5, 0.5, 0.35)
CEILING_COLOUR = (0.6, 0.5, 0.3, 0.25)
IDENTITY = (0.0, 0.0, 0.0, 1.0)
ORIGIN = (0.0, 0.0, 0.0, *IDENTITY)  # a pose: position, orientation x y z w


@dataclass
class MarkerInputs:
    """What ``K`` marker steps show (world NED unless said; None: not recorded)."""

    stamps_ns: np.ndarray  # (K,) int
    position: np.ndarray  # (K, 3) [m]
    quaternion: np.ndarray  # (K, 4) x y z w, body FRD -> world NED
    speeds: np.ndarray | None = None  # (K, n) rotor speeds [rad/s]
    tilts: np.ndarray | None = None  # (K, n) [rad]
    force_true: np.ndarray | None = None  # (K, 3) body [N]
    force_estimate: np.ndarray | None = None  # (K, 3) body [N]
    reference: np.ndarray | None = None  # (K, 3) [m]
    goal: np.ndarray | None = None  # (K, 3) [m]


@dataclass
class _Marker:
    ns: str
    id: int
    type: int
    scale: tuple[float, float, float]
    colour: tuple[float, float, float, float] | None  # None: per step
    pose: tuple[float, ...] | None = None  # position, x y z w; None: per step
    points: np.ndarray | int = 0  # constant points (m, 3), or how many per step


class MarkerLayout:
    """The marker arrays of one vehicle (module docstring); :meth:`pack_rows` gives their CDR bytes."""

    def __init__(self, vehicle: Vehicle, environment: Environment, path: np.ndarray, goal: np.ndarray, *,
                 rotor_speeds: bool, estimate: bool) -> None:
        """``path`` (P, 3) and ``goal`` (3,) world NED [m]; ``rotor_speeds``: the rotors' speeds are recorded
        (rotor actuation: thrust arrows and coloured discs); ``estimate``: an estimator runs."""
        self.vehicle = vehicle
        self.goal = np.asarray(goal, dtype=float)
        arm = vehicle.arm_length
        self.arm = arm
        n = vehicle.rotor_count
        self.rotor_speeds = rotor_speeds
        self.estimate = estimate
        shaft = (0.04 * arm, 0.08 * arm, 0.12 * arm)
        radius = vehicle.rotor_radius
        markers = [_Marker("arms", 0, LINE_LIST, (0.05 * arm, 0.0, 0.0), GREY, ORIGIN, 2 * n)]
        markers += [_Marker("rotors", i, CYLINDER, (2 * radius, 2 * radius, 0.1 * radius),
                            None if rotor_speeds else GREY) for i in range(n)]
        if rotor_speeds:
            markers += [_Marker("thrust", i, ARROW, shaft, THRUST_COLOUR, ORIGIN, 2) for i in range(n)]
        force = (0.06 * arm, 0.12 * arm, 0.18 * arm)
        markers.append(_Marker("force_true", 0, ARROW, force, TRUE_FORCE_COLOUR, ORIGIN, 2))
        if estimate:
            markers.append(_Marker("force_estimate", 0, ARROW, force, ESTIMATE_COLOUR, ORIGIN, 2))
        markers.append(_Marker("reference_position", 0, SPHERE, (0.15 * arm,) * 3, REFERENCE_COLOUR))
        markers.append(_Marker("goal_position", 0, SPHERE, (0.3 * arm,) * 3, GOAL_COLOUR))
        path = np.asarray(path, dtype=float).reshape(-1, 3)
        markers.append(_Marker("path", 0, LINE_STRIP, (0.02 * arm, 0.0, 0.0), PATH_COLOUR, ORIGIN, path))
        centre = path.mean(axis=0) if len(path) else np.zeros(3)
        reach = float(np.max(np.linalg.norm(path[:, :2] - centre[:2], axis=1))) if len(path) else 0.0
        side = 2.0 * reach + 2.0 + 20.0 * arm
        for name, surface, colour in (("ground", environment.ground, GROUND_COLOUR),
                                      ("ceiling", environment.ceiling, CEILING_COLOUR)):
            if surface.enabled:
                markers.append(_Marker(name, 0, CUBE, (side, side, 0.002), colour,
                                       (centre[0], centre[1], surface.height, *IDENTITY)))
        self.markers = markers
        self.layout = self._layout(markers)

    @staticmethod
    def _layout(markers: list[_Marker]) -> StampedNumbers:
        t = Template()
        t.uint32(len(markers))
        stamps, runs = [], []
        for marker in markers:
            stamps.append(t.header(WORLD_FRAME))
            t.string(marker.ns)
            t.int32(marker.id)
            t.int32(marker.type)
            t.int32(0)  # ADD
            pose = t.doubles(7)
            if marker.pose is None:
                runs.append((pose, 7, "<f8"))
            else:
                t.buffer[pose:pose + 56] = np.asarray(marker.pose, dtype="<f8").tobytes()
            scale = t.doubles(3)
            t.buffer[scale:scale + 24] = np.asarray(marker.scale, dtype="<f8").tobytes()
            colour = t.floats(4)
            if marker.colour is None:
                runs.append((colour, 4, "<f4"))
            else:
                t.buffer[colour:colour + 16] = np.asarray(marker.colour, dtype="<f4").tobytes()
            t.int32(0)  # lifetime 0: until replaced
            t.uint32(0)
            t.boolean(False)  # frame_locked
            constant = isinstance(marker.points, np.ndarray)
            count = len(marker.points) if constant else marker.points
            t.uint32(count)
            if count:
                points = t.doubles(3 * count)
                if constant:
                    t.buffer[points:points + 24 * count] = np.ascontiguousarray(marker.points, dtype="<f8").tobytes()
                else:
                    runs.append((points, 3 * count, "<f8"))
            t.uint32(0)  # colors
            t.string("")  # texture_resource
            t.header("")  # texture: sensor_msgs/CompressedImage (header, format, data)
            t.string("")
            t.uint32(0)
            t.uint32(0)  # uv_coordinates
            t.string("")  # text
            t.string("")  # mesh_resource
            t.string("")  # mesh_file: filename, data
            t.uint32(0)
            t.boolean(False)  # mesh_use_embedded_materials
        return StampedNumbers(t, stamps, runs)

    def values(self, inputs: MarkerInputs) -> np.ndarray:
        """The per-step numbers (K, value_count), in the layout's run order."""
        vehicle, arm = self.vehicle, self.arm
        k = len(inputs.stamps_ns)
        position = np.asarray(inputs.position, dtype=float).reshape(k, 3)
        rotation = rotations_from_quaternions(np.asarray(inputs.quaternion, dtype=float).reshape(k, 4))
        axes_body = np.broadcast_to(rotor_axes(vehicle, inputs.tilts), (k, vehicle.rotor_count, 3))
        centres = position[:, None, :] + np.einsum("kij,nj->kni", rotation, vehicle.positions)
        axes = np.einsum("kij,knj->kni", rotation, axes_body)
        columns = [np.concatenate((np.broadcast_to(position[:, None, :], centres.shape), centres), axis=2)
                   .reshape(k, -1)]  # arms: (centre, rotor) per rotor
        discs = np.concatenate((centres, axis_quaternions(axes)), axis=2)  # (k, n, 7)
        if self.rotor_speeds:
            speeds = _or_zeros(inputs.speeds, (k, vehicle.rotor_count))
            fraction = (speeds - vehicle.rotor_speed_min) / (vehicle.rotor_speed_max - vehicle.rotor_speed_min)
            colours = speed_colours(fraction)
            columns += [np.concatenate((discs[:, i], colours[:, i]), axis=1) for i in range(vehicle.rotor_count)]
            length = arm * vehicle.c_f * speeds ** 2 / (vehicle.weight / vehicle.rotor_count)
            tips = centres + axes * length[..., None]
            columns += [np.concatenate((centres[:, i], tips[:, i]), axis=1) for i in range(vehicle.rotor_count)]
        else:
            columns += [discs[:, i] for i in range(vehicle.rotor_count)]
        per_newton = arm / (FORCE_PER_ARM * vehicle.weight)
        forces = [inputs.force_true] + ([inputs.force_estimate] if self.estimate else [])
        for force in forces:
            world = np.einsum("kij,kj->ki", rotation, _or_zeros(force, (k, 3)))
            columns.append(np.concatenate((position, position + per_newton * world), axis=1))
        identity = np.broadcast_to(IDENTITY, (k, 4))
        reference = position if inputs.reference is None else np.asarray(inputs.reference, dtype=float)
        goal = np.broadcast_to(self.goal, (k, 3)) if inputs.goal is None else np.asarray(inputs.goal, dtype=float)
        columns += [np.concatenate((reference, identity), axis=1), np.concatenate((goal, identity), axis=1)]
        return np.concatenate(columns, axis=1)

    def pack_rows(self, inputs: MarkerInputs) -> np.ndarray:
        """The ``MarkerArray`` CDR of each step (uint8, (K, size))."""
        return self.layout.pack_rows(inputs.stamps_ns, self.values(inputs))


def speed_colours(fraction: np.ndarray) -> np.ndarray:
    """RGBA (..., 4) of speed fractions (clipped to [0, 1]): blue, grey at 0.5, red."""
    x = np.clip(np.nan_to_num(np.asarray(fraction, dtype=float)), 0.0, 1.0) * 2.0
    low = np.minimum(x, 1.0)[..., None]
    high = np.maximum(x - 1.0, 0.0)[..., None]
    return SPEED_COLOURS[0] + low * (SPEED_COLOURS[1] - SPEED_COLOURS[0]) + high * (SPEED_COLOURS[2] - SPEED_COLOURS[1])


def _or_zeros(values: np.ndarray | None, shape: tuple[int, ...]) -> np.ndarray:
    return np.zeros(shape) if values is None else np.asarray(values, dtype=float).reshape(shape)

