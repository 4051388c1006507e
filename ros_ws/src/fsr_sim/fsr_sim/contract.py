"""The flight contract: every topic, frame id, joint name, status key, exit code and convention of an fsr
flight, declared once. Nodes, the recorder, the in-process recording, the analysis and the topic
table of docs/architecture.md derive from it (a test checks that none of these literals appears anywhere else).

Topics are relative names (a vehicle namespace moves them all) except ``/clock``. For each topic
(:class:`Topic`): its message type, the QoS profile the publisher and the subscribers use
(:mod:`fsr_sim.ros.qos` names), who publishes it, whether the recorder keeps it, whether it carries one
message per lockstep step (stamped with the step's state: what a recording must hold completely), and its
frame ids. The order of :data:`TOPICS` is the order in which the nodes publish within a step.

No ROS and no numpy here: a controller on a companion computer, the analysis and the tests import it alike.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, fields
from typing import Any

# ----- frames (docs/model.md §2) ---------------------------------------------------------------------------
WORLD_FRAME = "world_ned"  # x north, y east, z down
BODY_FRAME = "base_link_frd"  # x forward, y right, z down
MAP_FRAME = "map"  # ENU (REP 103: x east, y north, z up), the parent of WORLD_FRAME in /tf_static
BODY_FLU_FRAME = "base_link"  # x forward, y left, z up (REP 103), a child of BODY_FRAME in /tf_static


def rotor_frame(index: int) -> str:
    """Frame of rotor ``index`` (0-based), a child of BODY_FRAME at the rotor's centre, turned from the body by the
    shortest rotation that takes ``z_b`` to the rotor's thrust axis reversed (the identity for a rotor lifting
    along ``-z_b``)."""
    return f"rotor_{index + 1}_link"


def frame_prefix(namespace: str) -> str:
    """What a vehicle's frame ids start with in ``/tf`` and ``/tf_static`` (``uav1/`` under ``/uav1``, nothing at
    the root): several vehicles of one recording keep apart frames. WORLD_FRAME and MAP_FRAME are shared."""
    namespace = namespace.strip("/")
    return f"{namespace}/" if namespace else ""


# ----- the rotors' joint names in rotor_cmd ------------------------------------------------------------------
ROTOR, TILT = "rotor", "tilt"  # the two kinds of joint: rotor_i (velocity [rad/s]), tilt_i (position [rad])


def rotor_joint(index: int) -> str:
    """Joint name of rotor ``index`` (0-based): its speed [rad/s] is the joint's velocity."""
    return f"{ROTOR}_{index + 1}"


def tilt_joint(index: int) -> str:
    """Joint name of rotor ``index``'s tilt (0-based): the tilt angle [rad] is the joint's position."""
    return f"{TILT}_{index + 1}"


def parse_joint(name: str) -> tuple[str, int] | None:
    """``(ROTOR or TILT, 0-based index)`` of a ``rotor_cmd`` joint name; None for any other name."""
    kind, _, number = name.rpartition("_")
    if kind in (ROTOR, TILT) and number.isdigit() and int(number) >= 1:
        return kind, int(number) - 1
    return None


def joint_names(rotor_count: int, tilting: bool) -> list[str]:
    """``rotor_cmd``'s joint names: every rotor, then (tilting rotors) every tilt."""
    names = [rotor_joint(i) for i in range(rotor_count)]
    return names + [tilt_joint(i) for i in range(rotor_count)] if tilting else names


# ----- topics ----------------------------------------------------------------------------------------------
SIMULATOR, CONTROLLER, ESTIMATOR, USER = "simulator", "controller", "estimator", "user"
RECORDER = "recorder"  # the topics the recording derives from the others (fsr_bringup.recording.derived)


@dataclass(frozen=True)
class Topic:
    """One topic of the flight (module docstring)."""

    name: str
    type: str  # ROS message type, "package/msg/Type"
    qos: str  # STREAM, LATCHED, CLOCK, PROGRESS or GOAL (fsr_sim.ros.qos)
    publisher: str
    recorded: bool
    per_step: bool  # one message per lockstep step, stamped with the state it belongs to
    frame: str = ""  # header.frame_id ("" without a header)
    child_frame: str = ""  # Odometry's child_frame_id; the trajectory's one joint
    notes: str = ""  # what it carries (the topic table of docs/architecture.md)
    stamped_like: str = ""  # no header: message i has the stamp of the same publisher's message i on this topic


CLOCK = Topic("/clock", "rosgraph_msgs/msg/Clock", "CLOCK", SIMULATOR, True, True,
              notes="simulated time")
ODOM = Topic("odom", "nav_msgs/msg/Odometry", "STREAM", SIMULATOR, True, True, WORLD_FRAME, BODY_FRAME,
             "pose of `base_link_frd` in `world_ned`; twist in `base_link_frd`")
ODOM_TRUTH = Topic("odom_truth", "nav_msgs/msg/Odometry", "STREAM", SIMULATOR, True, True, WORLD_FRAME, BODY_FRAME,
                   "the true state, as `odom` would carry it without a sensor stage; only when `odom` is measured "
                   "(`sensors.odometry` noise, bias, delay or rate): the tracking errors are taken on it")
WRENCH_TRUTH = Topic("wrench_truth", "geometry_msgs/msg/WrenchStamped", "STREAM", SIMULATOR, True, True, BODY_FRAME,
                     notes="true external wrench, body frame")
ROTOR_STATE = Topic("rotor_state", "sensor_msgs/msg/JointState", "STREAM", SIMULATOR, True, True, BODY_FRAME,
                    notes="the rotors' actual `rotor_i` velocity [rad/s] and `tilt_i` position [rad] of the "
                          "published state; only with actuator dynamics (a rotor or servo lag: docs/model.md "
                          "§3.2), else they are `rotor_cmd`'s, clamped")
IMU = Topic("imu", "sensor_msgs/msg/Imu", "STREAM", SIMULATOR, True, True, BODY_FRAME,
          notes="the IMU's angular velocity [rad/s] and specific force `R^T (p_ddot - g e3)` [m/s^2] of the published "
                "state (at rest: `[0, 0, -g]`), through its noise, bias walk, delay and rate (docs/model.md §3.9); "
                "covariances the white noise's, orientation not provided (`orientation_covariance[0] = -1`); only "
                "with an IMU (`sensors.imu`)")
SIM_STATUS = Topic("sim_status", "std_msgs/msg/String", "LATCHED", SIMULATOR, True, False,
                   notes="JSON of a `SimStatus`: `state` (running, then finished, diverged or stopped), `reason`, "
                         "`sim_time` [s] of the last published state, `steps`, and the lockstep's record "
                         "(`failsafe_steps`, `incidents`, `late_commands`, `longest_wait_s`)")
SIM_PROGRESS = Topic("sim_progress", "rosgraph_msgs/msg/Clock", "PROGRESS", SIMULATOR, False, False,
                     notes="simulated time every 100 steps and at the end (for progress displays)")
ROTOR_CMD = Topic("rotor_cmd", "sensor_msgs/msg/JointState", "STREAM", CONTROLLER, True, True, BODY_FRAME,
                  notes="`rotor_i` velocity [rad/s], `tilt_i` position [rad]; stamp = answered state")
WRENCH_CMD = Topic("wrench_cmd", "geometry_msgs/msg/WrenchStamped", "STREAM", CONTROLLER, True, True, BODY_FRAME,
                   notes="body wrench actually commanded (after allocation at the rotor limits); `force.z = -u_T`")
WRENCH_SHORTFALL = Topic("wrench_shortfall", "geometry_msgs/msg/WrenchStamped", "STREAM", CONTROLLER, True, True,
                         BODY_FRAME, notes="demanded minus commanded body wrench: which axis gave way at the rotor "
                                           "limits, by how much (zero when nothing saturates)")
REFERENCE = Topic("reference", "trajectory_msgs/msg/MultiDOFJointTrajectory", "STREAM", CONTROLLER, True, True,
                  WORLD_FRAME, BODY_FRAME, "one point: `R_d`, position; velocities/accelerations in the world "
                                           "frame (angular as `R_d w_d`)")
ATTITUDE_CMD = Topic("attitude_cmd", "geometry_msgs/msg/QuaternionStamped", "STREAM", CONTROLLER, True, True,
                     WORLD_FRAME, notes="commanded attitude `R_c` (body -> `world_ned`, `w >= 0`): the geometric "
                                        "controller's thrust-vector attitude, the Voliro controller's reference "
                                        "attitude; stamp = answered state")
WRENCH_DESIRED = Topic("wrench_desired", "geometry_msgs/msg/WrenchStamped", "STREAM", CONTROLLER, True, True,
                       BODY_FRAME, notes="body wrench the control law asked for, before allocation and rotor "
                                         "clamping")
GOAL = Topic("goal", "geometry_msgs/msg/PoseStamped", "GOAL", USER, True, False, WORLD_FRAME,
             notes="new target in `world_ned`, planned from the current reference; `header.frame_id` must be "
                   "`world_ned` or empty (no TF lookup: any other frame is dropped with a warning naming it)")
WRENCH_ESTIMATE = Topic("wrench_estimate", "geometry_msgs/msg/WrenchStamped", "STREAM", ESTIMATOR, True, True,
                        BODY_FRAME, notes="body frame (`R_b^T f_e`, `Q^-T tau_e`): comparable with `wrench_truth`")
MASS_ESTIMATE = Topic("mass_estimate", "std_msgs/msg/Float64", "STREAM", ESTIMATOR, True, True,
                      notes="`m_model + f_e,z / g` [kg]; recorded at the stamp of the same state's `wrench_estimate`",
                      stamped_like="wrench_estimate")
TF = Topic("/tf", "tf2_msgs/msg/TFMessage", "STREAM", RECORDER, True, False,
           notes="`world_ned` -> `base_link_frd` of every `odom` (same stamp and pose); the frames of tilting rotors "
                 "with the markers. Over DDS while subscribed, where tf2_msgs is built (scripts/build_tf2_msgs.sh)")
TF_STATIC = Topic("/tf_static", "tf2_msgs/msg/TFMessage", "LATCHED", RECORDER, True, False,
                  notes="`map` (ENU) -> `world_ned`, `base_link_frd` -> `base_link` (FLU) and the fixed rotors' "
                        "frames, once at the start of the recording; over DDS every vehicle's in one message")
MARKERS = Topic("markers", "visualization_msgs/msg/MarkerArray", "STREAM", RECORDER, True, False, WORLD_FRAME,
                notes="the vehicle in `world_ned` at `visualization.marker_rate` [Hz] of simulated time: arms, "
                      "rotors (colour: speed between its limits), thrust arrows, true and estimated external force, "
                      "planned path, goal, reference, ground and ceiling")

TOPICS: tuple[Topic, ...] = (CLOCK, ODOM, ODOM_TRUTH, WRENCH_TRUTH, ROTOR_STATE, IMU, SIM_STATUS, SIM_PROGRESS,
                             ROTOR_CMD, WRENCH_CMD, WRENCH_SHORTFALL, REFERENCE, ATTITUDE_CMD, WRENCH_DESIRED, GOAL,
                             WRENCH_ESTIMATE, MASS_ESTIMATE, TF, TF_STATIC, MARKERS)
BY_NAME = {topic.name: topic for topic in TOPICS}


def resolve(name: str, namespace: str = "") -> str:
    """The absolute name of topic ``name`` under a vehicle ``namespace`` (``""`` or ``"/"``: the root)."""
    if name.startswith("/"):
        return name
    namespace = namespace.strip("/")
    return f"/{namespace}/{name}" if namespace else f"/{name}"


def topic_named(name: str) -> Topic | None:
    """The contract topic of a topic name, relative or absolute under any vehicle namespace (None: not one)."""
    return BY_NAME.get(name) or BY_NAME.get(name.rsplit("/", 1)[-1]) if "/" in name else BY_NAME.get(name)


def recorded_topics() -> dict[str, str]:
    """Relative name -> type of every topic the recorder subscribes to under a vehicle namespace (``/clock``
    apart; the derived topics, :func:`derived_topics`, are not subscribed to)."""
    return {t.name: t.type for t in TOPICS if t.recorded and t.name != CLOCK.name and t.publisher != RECORDER}


def derived_topics() -> dict[str, str]:
    """Name -> type of the topics a recording derives from the others (``/tf``, ``/tf_static``, ``markers``)."""
    return {t.name: t.type for t in TOPICS if t.publisher == RECORDER}


def recording_selection(text: str) -> frozenset[str]:
    """The topics to record from a comma-separated list of recorded topics (``odom,reference``; ``clock`` is
    ``/clock``, ``tf`` is ``/tf``): ``sim_status`` is always kept (how the flight ended). ValueError names an
    unknown one."""
    from fsr_sim.config.validation import did_you_mean

    topic_of = {name.lstrip("/"): name for name in (*recorded_topics(), CLOCK.name, *derived_topics())}
    chosen = {item.strip().lstrip("/") for item in text.split(",") if item.strip()}
    for name in sorted(chosen):
        if name not in topic_of:
            raise ValueError(f"unknown recorded topic '{name}' {did_you_mean(name, topic_of)}"
                             f"(recorded: {', '.join(topic_of)})")
    if not chosen:
        raise ValueError("no topic named (give a comma-separated list, e.g. odom,reference)")
    return frozenset({topic_of[name] for name in chosen} | {SIM_STATUS.name})


def stamped_streams() -> tuple[str, ...]:
    """The per-step topics with a header stamp (a recording holds one message per step of each that started)."""
    return tuple(t.name for t in TOPICS if t.per_step and t.frame and t.name != CLOCK.name)


def topic_table() -> str:
    """The topic table of docs/architecture.md (Markdown), generated from :data:`TOPICS`
    (``python -m fsr_sim.contract``)."""
    rows = ["| topic | type | from | QoS | recorded | frame_id | what it carries |", "|---|---|---|---|---|---|---|"]
    for t in TOPICS:
        frame = f"`{t.frame}`" if t.frame else "-"
        if t.child_frame:
            frame += f" -> `{t.child_frame}`"
        rows.append(f"| `{t.name}` | {t.type.replace('/msg/', '/')} | {t.publisher} | {t.qos.lower()} | "
                    f"{'yes' if t.recorded else 'no'} | {frame} | {t.notes} |")
    return "\n".join(rows) + "\n"


# ----- sim_status ------------------------------------------------------------------------------------------
RUNNING, FINISHED, DIVERGED, STOPPED = "running", "finished", "diverged", "stopped"
FINAL_STATES = (FINISHED, DIVERGED, STOPPED)
STAMP_TOLERANCE_NS = 1000  # sim_time is a float of seconds; steps are >= 1 us apart


@dataclass(frozen=True)
class SimStatus:
    """What ``sim_status`` carries (JSON): the flight's state and why, the simulated time [s] of the last
    published state and the steps taken; the lockstep's record (steps on the failsafe, incidents, commands that
    arrived too late, the longest wait for one [s]) is zero in one process."""

    state: str
    reason: str
    sim_time: float
    steps: int
    failsafe_steps: int = 0
    incidents: int = 0
    late_commands: int = 0
    longest_wait_s: float = 0.0

    def as_dict(self) -> dict:
        return asdict(self)

    def to_json(self) -> str:
        return json.dumps(asdict(self))

    @classmethod
    def from_dict(cls, data: object) -> SimStatus | None:
        """The status held by a decoded ``sim_status`` JSON object (None if it is not one)."""
        if not isinstance(data, dict):
            return None
        try:
            status = cls(**{f.name: data[f.name] for f in fields(cls) if f.name in data})
            float(status.sim_time)
        except (TypeError, ValueError):
            return None
        return status

    @classmethod
    def from_json(cls, text: str | bytes) -> SimStatus | None:
        """The status of a ``sim_status`` text (None if it is not one)."""
        try:
            return cls.from_dict(json.loads(text))
        except ValueError:
            return None

    @property
    def final(self) -> bool:
        return self.state in FINAL_STATES

    @property
    def stamp_ns(self) -> int:
        """Stamp [ns] of the last published state."""
        return int(round(float(self.sim_time) * 1e9))


# ----- exit codes (every command and node) -----------------------------------------------------------------
EXIT_OK = 0
EXIT_FAILURE = 1  # a node failed (or a file could not be written)
EXIT_CONFIG_ERROR = 2  # invalid scenario, parameter or argument; nothing was started
EXIT_DIVERGED = 3  # the flight diverged (NaN state, beyond physical bounds, crash)
EXIT_INTERRUPTED = 130  # fsr-fly stopped by SIGINT/SIGTERM (128 + SIGINT, the shell's convention)
EXIT_CODES = {EXIT_OK: "done", EXIT_FAILURE: "a node failed or a file could not be written",
              EXIT_CONFIG_ERROR: "invalid scenario, parameter or argument (nothing was started)",
              EXIT_DIVERGED: "the flight diverged", EXIT_INTERRUPTED: "interrupted (SIGINT/SIGTERM)"}


# ----- the thrust convention (docs/model.md §2) -------------------------------------------------------------
def thrust_of(force_z: Any) -> Any:
    """``u_T = -f_z`` [N]: the thrust along ``-z_b`` of a body force's z component (a float or an array)."""
    return -force_z


def force_z_of(thrust: Any) -> Any:
    """``f_z = -u_T`` [N]: the body force's z component of a thrust along ``-z_b`` (a float or an array)."""
    return -thrust


def body_force_of_thrust(thrust: float) -> tuple[float, float, float]:
    """``f_b = [0, 0, -u_T]`` [N] of a thrust along ``-z_b``."""
    return (0.0, 0.0, force_z_of(float(thrust)))


if __name__ == "__main__":
    print(topic_table(), end="")
