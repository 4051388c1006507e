"""The topics a recording derives from the others: ``/tf_static``, ``/tf`` and ``markers``
(:mod:`fsr_bringup.visualization`).

The recorder node (the graph) and the in-process recording hand every CDR message they write to
:class:`DerivedTopics`, which answers with the derived messages: the same numbers from the same messages,
so the graph and an in-process flight record the same derived topics.

* ``/tf_static`` once, at the start (log time 0): :func:`fsr_bringup.visualization.frames.static_frames`;
* ``/tf`` with every ``odom``: ``world_ned -> base_link_frd`` with its stamp and pose;
* ``markers`` (and, for rotors on servos, their frames in ``/tf``) at each marker step: the steps ``k`` (stamp
  ``k`` control periods) with ``k`` a multiple of the marker stride, once the messages of that stamp of each
  source (``odom``, ``wrench_truth``, ``reference``, the rotors' ``rotor_state`` or ``rotor_cmd``, ``wrench_estimate``
  when an estimator runs; those the recording keeps) are in. A ``goal`` moves the goal marker.

Markers need the scenario (vehicle, surfaces, plan) and its ``visualization.markers`` (default true); without a
usable scenario a recording gets ``/tf_static`` (without rotor frames) and ``/tf`` only.
"""

from __future__ import annotations

import sys
from collections.abc import Collection, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fsr_bringup.visualization.config import VisualizationConfig, visualization_config
from fsr_bringup.visualization.frames import body_frame, rotor_frames, rotor_transforms, static_frames, tf_message
from fsr_bringup.visualization.markers import MarkerInputs, MarkerLayout
from fsr_sim.config.scenario import Scenario, SimulationConfig, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import (
    BY_NAME,
    GOAL,
    MARKERS,
    ODOM,
    REFERENCE,
    ROTOR_CMD,
    ROTOR_STATE,
    TF,
    TF_STATIC,
    WRENCH_ESTIMATE,
    WRENCH_TRUTH,
    frame_prefix,
    resolve,
)
from fsr_sim.model.plant import actuator_lags
from fsr_sim.recording.cdr_columns import Columns, LayoutError, decode_columns

PATH_POINTS = 200  # samples of the planned path
DERIVED_SOURCES = frozenset((ODOM.name, GOAL.name, WRENCH_TRUTH.name, REFERENCE.name, ROTOR_CMD.name, ROTOR_STATE.name,
                             WRENCH_ESTIMATE.name))  # the topics derived ones are drawn from
POSE_FIELDS = ("pose.pose.position.", "pose.pose.orientation.")
FIELDS = {ODOM.name: POSE_FIELDS, GOAL.name: ("pose.position.",), WRENCH_TRUTH.name: ("wrench.force.",),
          WRENCH_ESTIMATE.name: ("wrench.force.",), REFERENCE.name: ("points.0.transforms.0.translation.",),
          ROTOR_CMD.name: ("position", "velocity"), ROTOR_STATE.name: ("position", "velocity")}  # what is drawn
POSITION = ("x", "y", "z")
QUATERNION = ("x", "y", "z", "w")


@dataclass(frozen=True)
class _Scene:
    """What the markers of a scenario need."""

    simulation: SimulationConfig
    visualization: VisualizationConfig
    estimate: bool
    path: np.ndarray  # (P, 3) world NED [m]


def _scene(scenario: Scenario | None) -> _Scene | None:
    """The scenario's vehicle, surfaces and plan (None: no scenario, or one that cannot be used)."""
    if scenario is None:
        return None
    try:
        from fsr_control.config.controller_config import controller_config
        from fsr_estimation.config.estimator_config import estimator_config

        simulation = simulation_config(scenario)
        visualization = visualization_config(scenario)
        estimate = estimator_config(scenario).enabled
        controller = controller_config(scenario)
        initial = simulation.initial
        trajectory = controller.trajectory(simulation.vehicle, simulation.actuation, initial.position,
                                           initial.rotation)
        times = np.linspace(0.0, trajectory.end_time, PATH_POINTS)
        path = np.array([trajectory.evaluate(t).position for t in times])
    except (ConfigError, ValueError) as error:
        _warn(f"no markers in the recording: {error}")
        return None
    return _Scene(simulation, visualization, estimate, path)


def _warn(text: str) -> None:
    print(f"{Path(sys.argv[0]).name or 'fsr'}: warning: {text}", file=sys.stderr, flush=True)


def _xyz(columns: Columns, prefix: str, names: Sequence[str] = POSITION) -> np.ndarray:
    return np.column_stack([columns.get(f"{prefix}.{name}") for name in names])


class DerivedTopics:
    """The derived topics of one vehicle namespace (module docstring)."""

    def __init__(self, scenario: Scenario | None, namespace: str = "/", recorded: Collection[str] | None = None
                 ) -> None:
        """``recorded``: the relative names of the topics the recording keeps, derived ones included
        (:func:`fsr_sim.contract.recording_selection`; None: all)."""
        self.namespace = namespace

        def kept(name: str) -> bool:
            return recorded is None or name in recorded

        scene = _scene(scenario)
        self.scene = scene
        vehicle = None if scene is None else scene.simulation.vehicle
        self.vehicle = vehicle
        self.tf_static = kept(TF_STATIC.name)
        self.tf = kept(TF.name) and kept(ODOM.name)
        self.markers = scene is not None and scene.visualization.markers and kept(MARKERS.name) and kept(ODOM.name)
        rotor_source = None
        if scene is not None and scene.simulation.actuation == "rotors":
            rotor_source = ROTOR_STATE.name if any(actuator_lags(scene.simulation.plant_vehicle, "rotors")) \
                else ROTOR_CMD.name
            rotor_source = rotor_source if kept(rotor_source) else None
        self.rotor_source = rotor_source
        self.moving_rotors = vehicle is not None and vehicle.has_servos and rotor_source is not None
        self.sources: tuple[str, ...] = ()
        if self.markers:
            wanted = [ODOM.name, WRENCH_TRUTH.name, REFERENCE.name, rotor_source,
                      WRENCH_ESTIMATE.name if scene.estimate else None]
            self.sources = tuple(name for name in wanted if name is not None and kept(name))
            self.layout = MarkerLayout(vehicle, scene.simulation.environment, scene.path, scene.path[-1],
                                       rotor_speeds=rotor_source is not None,
                                       estimate=WRENCH_ESTIMATE.name in self.sources)
            self.step_ns = int(round(scene.simulation.control_period * 1e9))
            self.stride = scene.visualization.marker_stride(scene.simulation.control_period)
            if self.moving_rotors:
                self.rotor_tf = tf_message(rotor_frames(vehicle, frame_prefix(namespace)))
        self.body_tf = body_frame(namespace)
        self.goal: np.ndarray | None = None
        self.pending: dict[int, dict[str, bytes]] = {}  # marker stamp [ns] -> source topic -> payload

    def topics(self) -> dict[str, str]:
        """Absolute name -> type of the derived topics this recording gets."""
        found = {}
        if self.tf_static:
            found[TF_STATIC.name] = TF_STATIC.type
        if self.tf or self.moving_rotors and self.markers:
            found[TF.name] = TF.type
        if self.markers:
            found[resolve(MARKERS.name, self.namespace)] = MARKERS.type
        return found

    def static(self) -> list[tuple[str, np.ndarray, np.ndarray]]:
        """``(topic, stamps, payload rows)`` of ``/tf_static`` (stamp 0), or nothing."""
        if not self.tf_static:
            return []
        layout, values = static_frames(self.vehicle, self.namespace, moving_rotors=self.moving_rotors)
        stamps = np.zeros(1, dtype=np.int64)
        return [(TF_STATIC.name, stamps, layout.pack_rows(stamps, values[None, :]))]

    def take(self, topic: str, stamps_ns: np.ndarray, payloads: Sequence[bytes]) -> list[tuple[str, np.ndarray,
                                                                                                np.ndarray]]:
        """The derived messages that messages ``payloads`` (CDR) of ``topic`` (relative), stamped ``stamps_ns``
        (in order), complete: ``(absolute topic, stamps, payload rows (K, size))``, in order of appearance."""
        out: list[tuple[str, np.ndarray, np.ndarray]] = []
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        if not len(stamps):
            return out
        if topic == ODOM.name and self.tf:
            columns = self._decode(payloads, ODOM.type, FIELDS[ODOM.name])
            if columns is not None:
                pose = np.column_stack((_xyz(columns, "pose.pose.position"),
                                        _xyz(columns, "pose.pose.orientation", QUATERNION)))
                out.append((TF.name, stamps, self.body_tf.pack_rows(stamps, pose)))
        if topic == GOAL.name and self.markers:
            columns = self._decode(payloads, GOAL.type, FIELDS[GOAL.name])
            if columns is not None:
                self.goal = _xyz(columns, "pose.position")[-1]
        if topic in self.sources:
            steps = np.rint(stamps / self.step_ns).astype(np.int64)
            for index in np.flatnonzero(steps % self.stride == 0).tolist():
                self.pending.setdefault(int(stamps[index]), {})[topic] = bytes(payloads[index])
            complete = sorted(stamp for stamp, held in self.pending.items() if len(held) == len(self.sources))
            if complete:
                out += self._markers(complete)
        return out

    def _decode(self, payloads: Sequence[bytes] | np.ndarray, type_name: str, fields: tuple[str, ...]
                ) -> Columns | None:
        """The ``fields`` (path prefixes) of ``payloads``, or None (with a warning) if they cannot be decoded."""
        try:
            return decode_columns(payloads if isinstance(payloads, np.ndarray) else [bytes(p) for p in payloads],
                                  type_name, fields)
        except (LayoutError, KeyError) as error:
            _warn(f"cannot draw from {type_name}: {error}")
            return None

    def _markers(self, complete: list[int]) -> list[tuple[str, np.ndarray, np.ndarray]]:
        held = [self.pending.pop(stamp) for stamp in complete]
        stamps = np.array(complete, dtype=np.int64)
        decoded = {}
        for topic in self.sources:
            columns = self._decode([one[topic] for one in held], BY_NAME[topic].type, FIELDS[topic])
            if columns is None:
                return []
            decoded[topic] = columns
        odom = decoded[ODOM.name]
        inputs = MarkerInputs(stamps, _xyz(odom, "pose.pose.position"),
                              _xyz(odom, "pose.pose.orientation", QUATERNION))
        if WRENCH_TRUTH.name in decoded:
            inputs.force_true = _xyz(decoded[WRENCH_TRUTH.name], "wrench.force")
        if WRENCH_ESTIMATE.name in decoded:
            inputs.force_estimate = _xyz(decoded[WRENCH_ESTIMATE.name], "wrench.force")
        if REFERENCE.name in decoded:
            inputs.reference = _xyz(decoded[REFERENCE.name], "points.0.transforms.0.translation")
        if self.goal is not None:
            inputs.goal = np.broadcast_to(self.goal, (len(stamps), 3))
        out = []
        if self.rotor_source is not None:
            joints = decoded[self.rotor_source]
            n = self.vehicle.rotor_count
            inputs.speeds = joints.get("velocity")[:, :n]
            if self.vehicle.has_servos:
                inputs.tilts = joints.get("position")[:, n:2 * n]
            if self.moving_rotors:
                out.append((TF.name, stamps, self.rotor_tf.pack_rows(stamps, rotor_transforms(self.vehicle,
                                                                                             inputs.tilts))))
        out.insert(0, (resolve(MARKERS.name, self.namespace), stamps, self.layout.pack_rows(inputs)))
        return out
