"""Flight logs for the momentum observer: one validated container and its loaders and writer.

A :class:`FlightLog` holds, per sample k (uniform time base):

* ``time`` (N,) [s]
* ``eta`` (N, 3) ZYX Euler angles ``[roll, pitch, yaw]`` [rad]; ``eta_dot`` (N, 3) their rates [rad/s]
* ``velocity_world`` (N, 3) linear velocity in world NED [m/s]
* ``force_body`` (N, 3) actuator force in body FRD [N] (fixed rotors: ``[0, 0, -u_T]``)
* ``torque_body`` (N, 3) actuator torque in body FRD [N m]

Sources: the report's MATLAB log (:func:`load_mat`), our MCAP recordings (:func:`load_mcap`: topics
``odom`` and ``wrench_cmd`` paired by header stamp) and CSV files (:func:`load_csv`, columns in
``CSV_COLUMNS``). :func:`write_mcap` stores a log as a standard ROS 2 recording that :func:`load_mcap`
reads back (to rounding). Every refusal raises :class:`FlightLogError` naming the file and the problem.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from fsr_sim.contract import ODOM, WRENCH_CMD, force_z_of, resolve
from fsr_sim.model.so3 import (
    euler_rate_matrix,
    euler_rates,
    euler_zyx_from_rotation,
    rotation_from_euler_zyx,
    rotations_from_quaternions,
)

MIN_SAMPLES = 10
TIME_TOLERANCE = 1e-6  # relative deviation of a sample interval from the mean one that is accepted
MAT_FIELDS = ("attitude", "attitude_vel", "linear_vel", "thrust", "tau")
CSV_BASE_COLUMNS = ("time", "roll", "pitch", "yaw", "roll_rate", "pitch_rate", "yaw_rate", "vx", "vy", "vz",
                    "tx", "ty", "tz")
CSV_FORCE_COLUMNS = ("fx", "fy", "fz")
CSV_COLUMNS_HELP = (
    "CSV columns (header row, comma separated, SI units): time [s]; roll, pitch, yaw [rad] (ZYX Euler); "
    "roll_rate, pitch_rate, yaw_rate [rad/s] (Euler-angle rates); vx, vy, vz [m/s] (world NED velocity); "
    "either thrust [N] (fixed rotors, body force [0, 0, -thrust]) or fx, fy, fz [N] (body FRD force); "
    "tx, ty, tz [N m] (body FRD torque)."
)
ODOM_TOPIC = ODOM.name
WRENCH_TOPIC = WRENCH_CMD.name


class FlightLogError(ValueError):
    """A flight log that cannot be used; the message names the file and the reason."""


@dataclass
class FlightLog:
    """Validated observer inputs on a uniform time base (see the module docstring for frames and units)."""

    time: np.ndarray
    eta: np.ndarray
    eta_dot: np.ndarray
    velocity_world: np.ndarray
    force_body: np.ndarray
    torque_body: np.ndarray
    source: str = "flight log"
    truncated: bool = False  # an MCAP recording cut short (no footer): the samples stop before the flight ended

    def __post_init__(self) -> None:
        n = None
        for name in ("time", "eta", "eta_dot", "velocity_world", "force_body", "torque_body"):
            value = np.array(getattr(self, name), dtype=float)
            expected = (value.shape[0],) if name == "time" else (value.shape[0] if value.ndim else 0, 3)
            if value.ndim == 0 or value.shape != expected:
                wanted = "(N,)" if name == "time" else "(N, 3)"
                raise FlightLogError(f"{self.source}: {name}: expected shape {wanted}, got {value.shape}")
            if n is None:
                n = value.shape[0]
            elif value.shape[0] != n:
                raise FlightLogError(f"{self.source}: {name}: has {value.shape[0]} samples, time has {n}")
            bad = ~np.isfinite(value)
            if bad.any():
                first = int(np.argwhere(bad)[0][0])
                raise FlightLogError(f"{self.source}: {name}: NaN or inf at sample {first}")
            setattr(self, name, value)
        if n < MIN_SAMPLES:
            raise FlightLogError(f"{self.source}: too few samples ({n}); need at least {MIN_SAMPLES}")
        dt = np.diff(self.time)
        if np.any(dt <= 0.0):
            k = int(np.argmax(dt <= 0.0))
            raise FlightLogError(f"{self.source}: time: not increasing at sample {k + 1} "
                                 f"({self.time[k]:.9g} s -> {self.time[k + 1]:.9g} s)")
        sample_time = self.sample_time
        deviation = np.abs(dt - sample_time)
        if deviation.max() > TIME_TOLERANCE * sample_time:
            k = int(np.argmax(deviation))
            raise FlightLogError(
                f"{self.source}: time: non-uniform time base (interval {dt[k]:.9g} s at sample {k + 1}, "
                f"mean {sample_time:.9g} s); the observer needs a constant sample time"
            )

    @property
    def sample_time(self) -> float:
        """Mean sample time ``(t[-1] - t[0]) / (N - 1)`` [s]."""
        return float((self.time[-1] - self.time[0]) / (len(self.time) - 1))

    def __len__(self) -> int:
        return len(self.time)


def body_force_from_thrust(thrust: ArrayLike) -> np.ndarray:
    """Fixed rotors: total thrust ``u_T`` [N] (N,) along ``-z_b`` -> body force ``[0, 0, -u_T]`` (N, 3)."""
    u = np.asarray(thrust, dtype=float).reshape(-1)
    force = np.zeros((len(u), 3))
    force[:, 2] = force_z_of(u)
    return force


def load_flight_log(path: str | Path) -> FlightLog:
    """Load ``path`` by its extension: ``.mat`` (report layout), ``.mcap`` (our recordings) or ``.csv``."""
    path = Path(path)
    loaders = {".mat": load_mat, ".mcap": load_mcap, ".csv": load_csv}
    loader = loaders.get(path.suffix.lower())
    if loader is None:
        raise FlightLogError(f"{path}: unknown log format '{path.suffix}' (expected .mat, .mcap or .csv)")
    if not path.is_file():
        raise FlightLogError(f"{path}: no such file")
    return loader(path)


def load_mat(path: str | Path) -> FlightLog:
    """The report's MATLAB log: structs ``attitude`` (eta), ``attitude_vel`` (eta_dot), ``linear_vel``
    (world velocity), ``thrust`` (u_T), ``tau`` (body torque), each with ``.time`` and ``.signals.values``."""
    import scipy.io

    path = Path(path)
    try:
        data = scipy.io.loadmat(str(path))
    except (OSError, ValueError, NotImplementedError) as error:
        raise FlightLogError(f"{path}: not a readable MATLAB file ({error})") from None
    missing = [name for name in MAT_FIELDS if name not in data]
    if missing:
        raise FlightLogError(f"{path}: missing field(s) {', '.join(missing)} (expected {', '.join(MAT_FIELDS)})")
    times, values = {}, {}
    for name in MAT_FIELDS:
        times[name], values[name] = _mat_signal(data[name], name, path)
    time = times["attitude"]
    for name in MAT_FIELDS[1:]:
        if times[name].shape != time.shape or not np.allclose(times[name], time, rtol=0.0, atol=1e-9):
            raise FlightLogError(f"{path}: {name}.time differs from attitude.time")
    thrust = values["thrust"]
    if thrust.ndim == 2 and thrust.shape[1] == 1:
        thrust = thrust[:, 0]
    if thrust.ndim != 1:
        raise FlightLogError(f"{path}: thrust.signals.values: expected shape (N, 1), got {thrust.shape}")
    return FlightLog(time=time, eta=values["attitude"], eta_dot=values["attitude_vel"],
                     velocity_world=values["linear_vel"], force_body=body_force_from_thrust(thrust),
                     torque_body=values["tau"], source=str(path))


def _mat_signal(struct: object, name: str, path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(time (N,), values) of a Simulink 'structure with time' as loaded by scipy.io.loadmat."""
    try:
        record = struct[0, 0]  # type: ignore[index]
        time = np.asarray(record["time"], dtype=float).reshape(-1)
        values = np.asarray(record["signals"][0, 0]["values"], dtype=float)
    except (TypeError, ValueError, IndexError, KeyError) as error:
        raise FlightLogError(f"{path}: {name}: expected a struct with .time and .signals.values ({error})") from None
    return time, values


def load_csv(path: str | Path) -> FlightLog:
    """A CSV file with a header row naming the columns of ``CSV_COLUMNS_HELP`` (any order, extra columns ignored)."""
    path = Path(path)
    try:
        with open(path, newline="", encoding="utf-8") as stream:
            header = next(csv.reader(stream), None)
    except (OSError, UnicodeDecodeError) as error:
        raise FlightLogError(f"{path}: cannot read CSV ({error})") from None
    if not header:
        raise FlightLogError(f"{path}: empty file (expected a header row: {CSV_COLUMNS_HELP})")
    names = [h.strip() for h in header]
    force_columns = CSV_FORCE_COLUMNS if all(c in names for c in CSV_FORCE_COLUMNS) else ("thrust",)
    missing = [c for c in (*CSV_BASE_COLUMNS, *force_columns) if c not in names]
    if missing:
        raise FlightLogError(f"{path}: missing column(s) {', '.join(missing)}. {CSV_COLUMNS_HELP}")
    try:
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except ValueError as error:
        raise FlightLogError(f"{path}: not numeric CSV ({error})") from None
    if table.shape[1] != len(names):
        raise FlightLogError(f"{path}: rows have {table.shape[1]} values, the header names {len(names)} columns")

    def columns(*wanted: str) -> np.ndarray:
        return table[:, [names.index(c) for c in wanted]]

    force = columns(*CSV_FORCE_COLUMNS) if force_columns == CSV_FORCE_COLUMNS else body_force_from_thrust(
        columns("thrust"))
    return FlightLog(time=table[:, names.index("time")], eta=columns("roll", "pitch", "yaw"),
                     eta_dot=columns("roll_rate", "pitch_rate", "yaw_rate"), velocity_world=columns("vx", "vy", "vz"),
                     force_body=force, torque_body=columns("tx", "ty", "tz"), source=str(path))


def load_mcap(path: str | Path) -> FlightLog:
    """An fsr MCAP recording: ``odom`` (pose world NED, twist body FRD) and ``wrench_cmd`` (body wrench)
    paired by header stamp. ``v = R v_b``, ``eta`` from ``R``, ``eta_dot = Q(eta)^-1 omega_b``.

    A file without its MCAP footer (recorder killed, copy cut short) is read up to its last complete chunk
    and the log is flagged ``truncated``; the caller decides whether a partial flight is acceptable."""
    try:
        from fsr_sim.recording.reader import RecordingError, open_recording
    except ModuleNotFoundError as error:  # fsr_sim installed without its 'recording' extra
        raise FlightLogError(f"{path}: {error}") from None

    path = Path(path)
    try:
        recording = open_recording(path)
        odom_stamps, odom = _topic_arrays(recording, ODOM_TOPIC)
        wrench_stamps, wrench = _topic_arrays(recording, WRENCH_TOPIC)
    except RecordingError as error:
        raise FlightLogError(str(error)) from None
    stamps, odom_index, wrench_index = np.intersect1d(odom_stamps, wrench_stamps, return_indices=True)
    if len(stamps) < MIN_SAMPLES:
        raise FlightLogError(
            f"{path}: only {len(stamps)} samples with both '{ODOM_TOPIC}' and '{WRENCH_TOPIC}' at the same stamp "
            f"({len(odom_stamps)} odom, {len(wrench_stamps)} wrench_cmd); need at least {MIN_SAMPLES}")
    odom, wrench = odom[odom_index], wrench[wrench_index]
    quaternion = odom[:, 3:7]
    bad = ~np.isfinite(quaternion).all(axis=1) | (np.einsum("ki,ki->k", quaternion, quaternion) < 1e-12)
    if bad.any():
        raise FlightLogError(f"{path}: odom: invalid orientation at stamp {stamps[np.argmax(bad)]} ns")
    rotation = rotations_from_quaternions(quaternion)
    eta = euler_zyx_from_rotation(rotation)
    return FlightLog(
        time=stamps * 1e-9,
        eta=eta,
        eta_dot=euler_rates(eta, odom[:, 10:13]),
        velocity_world=np.einsum("kij,kj->ki", rotation, odom[:, 7:10]),
        force_body=wrench[:, :3],
        torque_body=wrench[:, 3:6],
        source=str(path),
        truncated=recording.truncated,
    )


ODOMETRY_FIELDS = tuple(f"pose.pose.{part}" for part in (
    "position.x", "position.y", "position.z", "orientation.x", "orientation.y", "orientation.z", "orientation.w",
)) + tuple(f"twist.twist.{part}.{axis}" for part in ("linear", "angular") for axis in "xyz")
WRENCH_FIELDS = tuple(f"wrench.{part}.{axis}" for part in ("force", "torque") for axis in "xyz")


def _topic_arrays(recording: object, topic: str) -> tuple[np.ndarray, np.ndarray]:
    """(stamps [ns] (N,), values) of ``odom`` -> (N, 13) ``[p, q_xyzw, v_body, omega_body]`` or
    ``wrench_cmd`` -> (N, 6) ``[force, torque]``, through the one whole-topic decoder
    (:func:`fsr_sim.recording.cdr_columns.stamped_columns`, also used by ``fsr-analyze``). A repeated stamp
    keeps its first message."""
    from fsr_sim.recording.cdr_columns import LayoutError, stamped_columns
    from fsr_sim.recording.reader import RecordingError

    wanted = ODOMETRY_FIELDS if topic == ODOM_TOPIC else WRENCH_FIELDS
    try:
        stamps, columns = stamped_columns(recording, topic)
        values = np.column_stack([columns.get(name) for name in wanted]).astype(float, copy=False)
    except (LayoutError, KeyError) as error:
        raise RecordingError(f"{recording.path}: cannot decode '{topic}': {error}") from None  # type: ignore[attr-defined]
    stamps, first = np.unique(stamps, return_index=True)
    return stamps, values[first]


def write_mcap(log: FlightLog, path: str | Path, metadata: dict[str, dict[str, str]] | None = None) -> Path:
    """Write ``log`` as a ROS 2 MCAP recording with ``/odom`` and ``/wrench_cmd`` (standard messages).

    ``odom``: stamp = the sample time (ns), pose in ``world_ned`` (orientation from ``eta``; position the
    integral of the velocity from the origin, which the observer does not use), twist in ``base_link_frd``
    (``R^T v``, ``omega_b = Q(eta) eta_dot``). ``wrench_cmd``: body force and torque, same stamp.
    """
    from fsr_sim.recording.writer import RecordingWriter
    from fsr_sim.ros.conversions import odometry_from_state, wrench_stamped

    stamps = np.round(log.time * 1e9).astype(np.int64)
    rotation = rotation_from_euler_zyx(log.eta)
    omega_body = np.einsum("kij,kj->ki", euler_rate_matrix(log.eta), log.eta_dot)
    position = np.zeros_like(log.velocity_world)
    position[1:] = np.cumsum(log.velocity_world[:-1] * np.diff(log.time)[:, None], axis=0)
    info = {"fsr_flight_log": {"source": Path(log.source).name, "samples": str(len(log))}}
    info.update(metadata or {})
    with RecordingWriter(path, metadata=info) as writer:
        odom_topic, wrench_topic = resolve(ODOM.name), resolve(WRENCH_CMD.name)
        writer.add_topic(odom_topic, ODOM.type)
        writer.add_topic(wrench_topic, WRENCH_CMD.type)
        for k, stamp in enumerate(stamps):
            stamp = int(stamp)
            odom = odometry_from_state(stamp, position[k], rotation[k], log.velocity_world[k], omega_body[k])
            writer.write_message(odom_topic, odom, stamp)
            writer.write_message(wrench_topic, wrench_stamped(stamp, log.force_body[k], log.torque_body[k]), stamp)
    return Path(path)
