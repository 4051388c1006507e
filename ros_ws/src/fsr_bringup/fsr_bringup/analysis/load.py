"""A recording as numpy arrays per topic, on the simulation clock, ready for metrics and figures.

Times are the messages' header stamps (simulated time t_k, seconds) where the type has a header, the
recorder's log time otherwise (``mass_estimate``; the recorder logs it at its latest simulated time).
Messages are sorted by stamp. Frames (docs/model.md §4): positions and the reference in ``world_ned``, odometry
twist and wrenches in ``base_link_frd``. With a sensor stage on, ``odom`` is the measurement and ``odom_truth`` the
true state (:attr:`RecordedFlight.true_odom`: what the tracking errors are taken on). The reference
(fsr_control.nodes.messages) is all world-frame: linear velocity and acceleration ``p_dot_d``, ``p_ddot_d`` and
angular velocity ``R_d omega_d``.

A missing topic is ``None`` with a note in :attr:`RecordedFlight.notes`; nothing here raises for a topic that is
absent or that cannot be decoded.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fsr_bringup.recording.metadata import scenario_from_text
from fsr_control.compensation import CompensationConfig
from fsr_control.config.controller_config import ControllerConfig, controller_config
from fsr_estimation.config.estimator_config import EstimatorConfig, estimator_config
from fsr_sim.config.scenario import Scenario, SimulationConfig, simulation_config
from fsr_sim.config.validation import ConfigError
from fsr_sim.contract import (
    ATTITUDE_CMD,
    CLOCK,
    IMU,
    MASS_ESTIMATE,
    ODOM,
    ODOM_TRUTH,
    REFERENCE,
    ROTOR,
    ROTOR_CMD,
    ROTOR_STATE,
    SIM_STATUS,
    TILT,
    WRENCH_CMD,
    WRENCH_DESIRED,
    WRENCH_ESTIMATE,
    WRENCH_SHORTFALL,
    WRENCH_TRUTH,
    SimStatus,
    parse_joint,
    recorded_topics,
    resolve,
    rotor_joint,
)
from fsr_sim.model.so3 import rotations_from_quaternions
from fsr_sim.recording.cdr_columns import Columns, LayoutError, stamped_columns
from fsr_sim.recording.reader import Recording, open_recording

NS_PER_S = 1_000_000_000
STANDARD_TOPICS = tuple(recorded_topics())


@dataclass(frozen=True)
class RecordingName:
    """What the analysis needs of a recording besides its messages (its path, in the figures' metadata and
    ``metrics.json``): what a figure worker gets, and what a flight analysed in memory names."""

    path: Path | None
    truncated: bool = False


@dataclass
class Odometry:
    stamp_ns: np.ndarray  # (n,) int64
    t: np.ndarray  # (n,) s
    position: np.ndarray  # (n, 3) world NED [m]
    quaternion: np.ndarray  # (n, 4) [x, y, z, w], body FRD -> world NED
    rotation: np.ndarray  # (n, 3, 3)
    velocity_world: np.ndarray  # (n, 3) [m/s]
    angular_velocity: np.ndarray  # (n, 3) body [rad/s]


@dataclass
class Reference:
    stamp_ns: np.ndarray
    t: np.ndarray
    position: np.ndarray  # (n, 3) world [m]
    quaternion: np.ndarray  # (n, 4)
    rotation: np.ndarray  # (n, 3, 3)
    velocity: np.ndarray  # (n, 3) world [m/s]
    acceleration: np.ndarray  # (n, 3) world [m/s^2]
    angular_velocity_world: np.ndarray  # (n, 3) ``R_d omega_d`` [rad/s]


@dataclass
class Attitude:
    """``attitude_cmd``: the commanded attitude ``R_c`` (body FRD -> world NED)."""

    stamp_ns: np.ndarray
    t: np.ndarray
    quaternion: np.ndarray  # (n, 4) [x, y, z, w]
    rotation: np.ndarray  # (n, 3, 3)


@dataclass
class Wrench:
    stamp_ns: np.ndarray
    t: np.ndarray
    force: np.ndarray  # (n, 3) [N], frame of the message (body FRD for every fsr topic)
    torque: np.ndarray  # (n, 3) [N m]


@dataclass
class Imu:
    """``imu``: what the IMU measured, body FRD."""

    stamp_ns: np.ndarray
    t: np.ndarray
    angular_velocity: np.ndarray  # (n, 3) [rad/s]
    linear_acceleration: np.ndarray  # (n, 3) specific force [m/s^2]


@dataclass
class RotorCommand:
    stamp_ns: np.ndarray
    t: np.ndarray
    speeds: np.ndarray  # (n, rotors) [rad/s]
    tilts: np.ndarray | None  # (n, rotors) [rad] for tilting vehicles


@dataclass
class Scalar:
    stamp_ns: np.ndarray
    t: np.ndarray
    value: np.ndarray  # (n,)


@dataclass
class RecordedFlight:
    """Everything the analysis needs from one recording (``None`` where a topic is missing)."""

    recording: Recording
    namespace: str
    scenario_name: str
    config: SimulationConfig | None
    estimator: EstimatorConfig | None = None  # the observer's model (mass, inertia) and filter, from the scenario
    compensation: CompensationConfig | None = None  # controller.compensation: estimate (None: none or unknown)
    compensation_mode: str | None = None  # the scenario's controller.compensation (None without a scenario)
    plan_adjustments: list[dict] | None = None  # the legs the planner shaped or stretched (None: no scenario)
    plan: dict | None = None  # the scenario's plan: {"kind": trajectory.kind, "end_s": when it comes to rest}
    controller: ControllerConfig | None = None  # the scenario's validated controller section (None: unknown)
    odom: Odometry | None = None
    odom_truth: Odometry | None = None  # the true state, recorded only when odom is measured (sensors.odometry)
    reference: Reference | None = None
    wrench_truth: Wrench | None = None
    wrench_cmd: Wrench | None = None
    wrench_shortfall: Wrench | None = None  # demanded - commanded body wrench (which axis gave way)
    attitude_cmd: Attitude | None = None
    wrench_desired: Wrench | None = None
    wrench_estimate: Wrench | None = None
    rotor_cmd: RotorCommand | None = None
    rotor_state: RotorCommand | None = None  # the rotors' actual speeds and tilts (only with actuator dynamics)
    imu: Imu | None = None  # the IMU's measurements (only with an IMU)
    mass_estimate: Scalar | None = None
    sim_status: list[SimStatus] = field(default_factory=list)
    message_counts: dict[str, int] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def truncated(self) -> bool:
        return self.recording is not None and self.recording.truncated

    @property
    def true_odom(self) -> Odometry | None:
        """The true state: ``odom_truth`` where ``odom`` is a measurement (it is recorded then), else ``odom``."""
        return self.odom_truth if self.odom_truth is not None else self.odom

    @property
    def odom_measured(self) -> bool:
        """``odom`` is a measurement (noise, bias, delay or rate: ``odom_truth`` holds the true state)."""
        return self.odom_truth is not None


def zero_order_hold(stamp_ns: np.ndarray, values: np.ndarray, target_ns: np.ndarray) -> np.ndarray:
    """Zero-order hold of ``values`` (sorted by ``stamp_ns``) at ``target_ns``: the last value at or
    before each target; NaN before the first sample. Exact stamp matches (lockstep) pick that sample."""
    if stamp_ns is target_ns:  # the same stamps (a flight in memory): every sample is its own partner
        return np.array(values, dtype=float)
    index = np.searchsorted(stamp_ns, target_ns, side="right") - 1
    out = values[np.clip(index, 0, None)].astype(float)
    out[index < 0] = np.nan
    return out


def detect_namespace(recording: Recording) -> tuple[str, str | None]:
    """The vehicle namespace to analyse (``/`` or ``/uav1``) and a note when there was a choice."""
    suffix = "/" + ODOM.name
    candidates = sorted(topic[: -len(suffix)] or "/" for topic in recording.topics if topic.endswith(suffix))
    if not candidates or "/" in candidates:
        return "/", None
    note = None
    if len(candidates) > 1:
        note = f"several vehicles recorded ({', '.join(candidates)}); analysing {candidates[0]} (use --namespace)"
    return candidates[0], note


def load_flight(recording: Recording | str | Path, namespace: str | None = None) -> RecordedFlight:
    """Decode the standard topics of ``recording`` (under ``namespace``, detected if None)."""
    if not isinstance(recording, Recording):
        recording = open_recording(recording)
    notes: list[str] = []
    if namespace is None:
        namespace, note = detect_namespace(recording)
        if note:
            notes.append(note)
    namespace = "/" + namespace.strip("/") if namespace.strip("/") else "/"
    scenario = recorded_scenario(recording, namespace, notes)
    config, scenario_name, estimator = _scenario(scenario, recording.path.stem, notes)
    flight = RecordedFlight(recording, namespace, scenario_name, config, estimator, notes=notes)
    (flight.compensation_mode, flight.compensation, flight.plan_adjustments, flight.plan,
     flight.controller) = controller_side(scenario, notes)
    if recording.truncated:
        notes.append("recording is truncated (writer did not close it): analysed up to its last complete chunk")
    for topic in sorted({*recording.topics, *(resolve(name, namespace) for name in (CLOCK.name, *STANDARD_TOPICS))}):
        flight.message_counts[topic] = recording.count(topic)
    for contract_topic, loader in LOADERS.items():
        name = contract_topic.name
        topic = resolve(name, namespace)
        if not recording.has(topic) or recording.count(topic) == 0:
            notes.append(f"no messages on {topic}")
            continue
        try:
            setattr(flight, name, loader(recording, topic))
        except (LayoutError, KeyError, ValueError) as error:
            notes.append(f"cannot decode {topic}: {error}")
    for contract_topic, loader in ((ROTOR_STATE, _rotor_command), (IMU, _imu), (ODOM_TRUTH, _odometry)):
        topic = resolve(contract_topic.name, namespace)  # published only with actuator dynamics, an IMU, a
        # measured odom: no note without
        if recording.has(topic) and recording.count(topic):
            try:
                setattr(flight, contract_topic.name, loader(recording, topic))
            except (LayoutError, KeyError, ValueError) as error:
                notes.append(f"cannot decode {topic}: {error}")
    status_topic = resolve(SIM_STATUS.name, namespace)
    if recording.has(status_topic):
        flight.sim_status = _statuses(recording, status_topic, notes)
    else:
        notes.append(f"no messages on {status_topic}")
    return flight


def recorded_scenario(recording: Recording, namespace: str, notes: list[str]) -> Scenario | None:
    """The scenario the recording's metadata holds for the vehicle under ``namespace`` (``/`` or ``/uav1``)
    (:func:`fsr_bringup.recording.metadata.scenario_from_text`); None, with a note saying why, when there is none."""
    scenario, note = scenario_from_text(recording.scenario_yaml, namespace, f"{recording.path} (fsr_scenario metadata)",
                                        recording.path.parent)
    if note is not None:
        notes.append(note)
    return scenario


def _scenario(scenario: Scenario | None, fallback: str,
              notes: list[str]) -> tuple[SimulationConfig | None, str, EstimatorConfig | None]:
    """(plant-side config, scenario name, estimator config) of the recorded scenario."""
    if scenario is None:
        return None, fallback, None
    try:
        config = simulation_config(scenario)
    except ConfigError as error:
        notes.append(f"scenario in the metadata cannot be used: {error}")
        return None, scenario.name, None
    try:
        estimator = estimator_config(scenario)
    except ConfigError as error:
        notes.append(f"estimator section of the scenario cannot be used: {error}")
        estimator = None
    return config, scenario.name, estimator


def controller_side(scenario: Scenario | None, notes: list[str]
                    ) -> tuple[str | None, CompensationConfig | None, list[dict] | None, dict | None,
                               ControllerConfig | None]:
    """(``controller.compensation`` of the recorded scenario, its validated settings or None, the legs its
    planner shaped or stretched: :attr:`fsr_control.config.controller_config.ControllerConfig.plan_adjustments`
    as plain values, its plan's kind and end time, and the validated controller section)."""
    if scenario is None:
        return None, None, None, None, None
    try:
        config = controller_config(scenario)
    except ConfigError as error:
        notes.append(f"controller section of the scenario cannot be used: {error}")
        return None, None, None, None, None
    adjustments = [item.as_dict() | {"text": item.text()} for item in config.plan_adjustments]
    plan = {"kind": config.trajectory_kind, "end_s": config.plan_end_time}
    return ("estimate" if config.compensation else "none"), config.compensation, adjustments, plan, config


def _columns(recording: Recording, topic: str) -> tuple[np.ndarray, Columns]:
    """Decoded columns of ``topic`` sorted by header stamp (log time where there is no header)."""
    return stamped_columns(recording, topic)


def _vector(columns: Columns, prefix: str, keys: str = "xyz") -> np.ndarray:
    return np.stack([columns.get(f"{prefix}.{k}").astype(float) for k in keys], axis=1)


def _odometry(recording: Recording, topic: str) -> Odometry:
    stamp, c = _columns(recording, topic)
    quaternion = _vector(c, "pose.pose.orientation", "xyzw")
    rotation = rotations_from_quaternions(quaternion)
    velocity_body = _vector(c, "twist.twist.linear")
    return Odometry(
        stamp, stamp / NS_PER_S, _vector(c, "pose.pose.position"), quaternion, rotation,
        np.einsum("nij,nj->ni", rotation, velocity_body), _vector(c, "twist.twist.angular"),
    )


def _reference(recording: Recording, topic: str) -> Reference:
    stamp, c = _columns(recording, topic)
    point = "points.0"

    def optional(prefix: str) -> np.ndarray:
        return _vector(c, prefix) if f"{prefix}.x" in c.numbers else np.full((c.n, 3), np.nan)

    quaternion = _vector(c, f"{point}.transforms.0.rotation", "xyzw")
    return Reference(
        stamp, stamp / NS_PER_S, _vector(c, f"{point}.transforms.0.translation"), quaternion,
        rotations_from_quaternions(quaternion), optional(f"{point}.velocities.0.linear"),
        optional(f"{point}.accelerations.0.linear"), optional(f"{point}.velocities.0.angular"),
    )


def _attitude(recording: Recording, topic: str) -> Attitude:
    stamp, c = _columns(recording, topic)
    quaternion = _vector(c, "quaternion", "xyzw")
    return Attitude(stamp, stamp / NS_PER_S, quaternion, rotations_from_quaternions(quaternion))


def _wrench(recording: Recording, topic: str) -> Wrench:
    stamp, c = _columns(recording, topic)
    return Wrench(stamp, stamp / NS_PER_S, _vector(c, "wrench.force"), _vector(c, "wrench.torque"))


def _imu(recording: Recording, topic: str) -> Imu:
    stamp, c = _columns(recording, topic)
    return Imu(stamp, stamp / NS_PER_S, _vector(c, "angular_velocity"), _vector(c, "linear_acceleration"))


def _rotor_command(recording: Recording, topic: str) -> RotorCommand:
    """Rotor speeds from ``rotor_i`` velocities and tilts from ``tilt_i`` positions (by name, docs/model.md §4)."""
    stamp, c = _columns(recording, topic)
    velocity = c.numbers.get("velocity", np.empty((c.n, 0)))
    position = c.numbers.get("position", np.empty((c.n, 0)))
    names = [c.strings[key] for key in sorted(c.strings, key=_name_index) if key.startswith("name.")]
    speeds = _by_name(names, velocity, ROTOR, c.n)
    tilts = _by_name(names, position, TILT, c.n)
    if speeds.shape[1] == 0:
        raise ValueError(f"no '{rotor_joint(0)}', '{rotor_joint(1)}', ... joints in the rotor command")
    return RotorCommand(stamp, stamp / NS_PER_S, speeds, tilts if tilts.shape[1] else None)


def _name_index(key: str) -> int:
    return int(key.split(".")[1]) if key.count(".") == 1 and key.split(".")[1].isdigit() else -1


def _by_name(names: list[np.ndarray], values: np.ndarray, kind: str, n: int) -> np.ndarray:
    """Columns of ``values`` for the joints of ``kind`` (contract.ROTOR or TILT), in index order (names may differ
    between messages)."""
    indices = [{name: joint[1] for name in set(column) - {None}
                if (joint := parse_joint(name)) is not None and joint[0] == kind} for column in names]
    count = max((index + 1 for found in indices for index in found.values()), default=0)
    out = np.full((n, count), np.nan)
    for j, (column, found) in enumerate(zip(names, indices, strict=True)):
        if j >= values.shape[1]:
            break
        for name, index in found.items():
            rows = column == name
            out[rows, index] = values[rows, j]
    return out


def _scalar(recording: Recording, topic: str) -> Scalar:
    stamp, c = _columns(recording, topic)
    return Scalar(stamp, stamp / NS_PER_S, c.get("data").astype(float))


def final_sim_time(recording: Recording | str | Path, namespaces: list[str]) -> float | None:
    """Simulated time [s] of the last ``sim_status`` recorded under ``namespaces`` (the latest vehicle's), the
    stop time the analysis reports; None when none was recorded."""
    if not isinstance(recording, Recording):
        recording = open_recording(recording)
    times = [statuses[-1].sim_time for namespace in namespaces
             if (statuses := _statuses(recording, resolve(SIM_STATUS.name, namespace or "/"), []))]
    return max(times) if times else None


def _statuses(recording: Recording, topic: str, notes: list[str]) -> list[SimStatus]:
    """The ``sim_status`` messages (few: one per state change), in order."""
    statuses = []
    for _log_time, msg in recording.messages(topic):
        status = SimStatus.from_json(msg.data)
        if status is None:
            notes.append(f"{topic}: a message is not a status: {str(msg.data)[:60]!r}")
        else:
            statuses.append(status)
    return statuses


LOADERS = {  # topic -> its decoder (a note where it has no messages); the RecordedFlight attribute has its name
    ODOM: _odometry, REFERENCE: _reference, WRENCH_TRUTH: _wrench, WRENCH_CMD: _wrench,
    WRENCH_SHORTFALL: _wrench, WRENCH_ESTIMATE: _wrench, ROTOR_CMD: _rotor_command, MASS_ESTIMATE: _scalar,
    ATTITUDE_CMD: _attitude, WRENCH_DESIRED: _wrench,
}
