"""The recording's frames as ``tf2_msgs/msg/TFMessage`` CDR (no tf2_msgs package needed).

Tree (frame ids: :mod:`fsr_sim.contract`; a vehicle's own frames start with its namespace,
:func:`fsr_sim.contract.frame_prefix`)::

    map (ENU, REP 103) -> world_ned -> base_link_frd -> base_link (FLU)
                                                     -> rotor_i_link (one per rotor)

``map -> world_ned`` is the fixed NED-ENU rotation (a point ``(n, e, d)`` of ``world_ned`` is ``(e, n, -d)`` in
``map``), ``base_link_frd -> base_link`` the fixed FRD-FLU rotation (``(x, y, z) -> (x, -y, -z)``); both, and the
frames of fixed rotors, are in ``/tf_static``. ``world_ned -> base_link_frd`` is in ``/tf`` with the stamp and the
pose of every ``odom``; the frames of rotors on servos move with their tilt and go into ``/tf`` with the
markers. A rotor's frame sits at its centre, turned from the body by the shortest rotation taking ``z_b`` to
its thrust axis reversed.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fsr_sim.contract import BODY_FLU_FRAME, BODY_FRAME, MAP_FRAME, WORLD_FRAME, frame_prefix, rotor_frame
from fsr_sim.model.rotors import rotor_axes
from fsr_sim.model.vehicle import Vehicle
from fsr_sim.ros.cdr_pack import StampedNumbers, Template

NED_TO_ENU = np.array(((0.0, 1.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, -1.0)))  # (n, e, d) -> (e, n, -d)
# x y z w of NED_TO_ENU, pi about (1, 1, 0)/sqrt(2), to the bit as quaternion_from_rotation gives it (a literal:
# computing it at import loads compiled code into every process that imports the figures)
WORLD_IN_MAP = np.array((0.7071067811865475, 0.7071067811865476, 0.0, 0.0))
FLU_IN_FRD = np.array((1.0, 0.0, 0.0, 0.0))  # pi about x: (x, y, z) -> (x, -y, -z)
TRANSFORM_VALUES = 7  # translation (3), rotation x y z w (4)


def tf_message(frames: Sequence[tuple[str, str]]) -> StampedNumbers:
    """The layout of a ``TFMessage`` holding one transform per (parent, child): values = per transform its
    translation [m] (3) and rotation quaternion x y z w (4), all stamped alike."""
    t = Template()
    t.uint32(len(frames))
    stamps, runs = [], []
    for parent, child in frames:
        stamps.append(t.header(parent))
        t.string(child)
        runs.append((t.doubles(TRANSFORM_VALUES), TRANSFORM_VALUES, "<f8"))
    return StampedNumbers(t, stamps, runs)


def axis_quaternions(axes: np.ndarray) -> np.ndarray:
    """Quaternions x y z w (..., 4) of the shortest rotations taking ``z = (0, 0, 1)`` to unit ``axes`` (..., 3)
    (pi about x for ``-z``)."""
    axes = np.asarray(axes, dtype=float)
    q = np.stack((-axes[..., 1], axes[..., 0], np.zeros(axes.shape[:-1]), 1.0 + axes[..., 2]), axis=-1)
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    opposite = norm[..., 0] < 1e-9
    q[opposite] = (1.0, 0.0, 0.0, 0.0)
    norm[opposite] = 1.0
    return q / norm


def rotor_frames(vehicle: Vehicle, prefix: str) -> list[tuple[str, str]]:
    """(parent, child) of every rotor's frame."""
    return [(prefix + BODY_FRAME, prefix + rotor_frame(i)) for i in range(vehicle.rotor_count)]


def rotor_transforms(vehicle: Vehicle, tilts: np.ndarray | None) -> np.ndarray:
    """Values of :func:`rotor_frames` (..., 7 n): each rotor's centre and the turn from the body to its frame."""
    axes = rotor_axes(vehicle, tilts)
    rotation = axis_quaternions(-axes)
    translation = np.broadcast_to(vehicle.positions, rotation.shape[:-1] + (3,))
    return np.concatenate((translation, rotation), axis=-1).reshape(*rotation.shape[:-2], -1)


def static_frames(vehicle: Vehicle | None, namespace: str, moving_rotors: bool = False
                  ) -> tuple[StampedNumbers, np.ndarray]:
    """``/tf_static``'s message layout and values: ``map -> world_ned``, ``base_link_frd -> base_link`` and, for a
    known vehicle whose rotors do not move (``moving_rotors``: their tilts are recorded), each rotor's frame."""
    prefix = frame_prefix(namespace)
    frames = [(MAP_FRAME, WORLD_FRAME), (prefix + BODY_FRAME, prefix + BODY_FLU_FRAME)]
    values = [np.zeros(3), WORLD_IN_MAP, np.zeros(3), FLU_IN_FRD]
    if vehicle is not None and not moving_rotors:
        frames += rotor_frames(vehicle, prefix)
        values.append(rotor_transforms(vehicle, None))
    return tf_message(frames), np.concatenate(values)


def body_frame(namespace: str) -> StampedNumbers:
    """``/tf``'s message of one state: ``world_ned -> base_link_frd``; values = the ``odom`` pose (position,
    orientation x y z w)."""
    return tf_message([(WORLD_FRAME, frame_prefix(namespace) + BODY_FRAME)])
