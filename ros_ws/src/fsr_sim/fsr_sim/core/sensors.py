"""The sensor stages between the true plant and what the simulator publishes (compiled core): ``odom``'s
measurement of the state and the IMU's of the specific force and angular rate, in the simulator node and the
in-process loop alike (:func:`fsr_sim.core.lockstep.publish` applies them to the published row).

Odometry (:func:`measure_odometry`, :class:`OdometryParams`): white Gaussian noise per published state, per
channel, plus a bias per channel that walks randomly, on position world NED [m], attitude as a body rotation
vector ``n`` [rad] (``R_meas = R Exp(n)``), body linear velocity [m/s] and body angular velocity [rad/s]; then
a delay (in published states) and a lower rate (a new measurement every ``every`` states, held between). With
everything zero (the default) the stage is off and ``odom`` is the true state, bit for bit. ``wrench_truth``
stays true.

IMU (:func:`measure_imu`, :class:`ImuParams`): the true angular rate and specific force
(:mod:`fsr_sim.core.imu`) plus white Gaussian noise per sample and a bias per axis that starts at its initial
value and walks randomly, then a delay and a rate, as for the odometry (docs/model.md §3.9).

The numbers come from a counter-based generator: the standard normal of (seed, step, channel) is a 32-bit integer
hash of the three (two uniforms, Box-Muller), so it depends on nothing else - not on who computes it, in which
process, or in which order - and the node graph and the in-process loop publish the same noisy ``odom`` and
``imu``, compiled and under CPython. (The hash is ``lowbias32``; integer products are masked to 32 bits, so
int64 wrap-around in compiled code and Python's unbounded integers give the same bits.) The odometry uses the
channels 0 .. 23 and the IMU 24 .. 35, so one seed gives independent odometry and IMU noise.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from fsr_sim.core.jit import jit, jit_inline, zeroed_record
from fsr_sim.core.odometry import ODOM_ANGULAR_VELOCITY, ODOM_POSITION, ODOM_QUATERNION, ODOM_SIZE, ODOM_VELOCITY

MASK32 = 0xFFFFFFFF
POSITION, ATTITUDE, VELOCITY, ANGULAR_VELOCITY = 0, 3, 6, 9  # first channel of each noise group


class OdometryParams(NamedTuple):
    """``odom``'s sensor stage (:func:`measure_odometry`)."""

    enabled: bool  # any standard deviation or bias walk > 0
    seed: int  # 0 .. 2^32 - 1
    position_std: float  # [m], world NED
    attitude_std: float  # [rad], body rotation vector
    velocity_std: float  # [m/s], body
    angular_velocity_std: float  # [rad/s], body
    walks: tuple  # bias random walks (position, attitude, velocity, angular velocity) [unit / sqrt(s)]
    period: float  # [s] between published states
    delay: int  # published states the measurement is late by
    every: int  # a new measurement every this many published states (the others hold it)


BIAS_CHANNEL = 12  # the odometry's bias walks' generator channels: 12 .. 23

IMU_SIZE = 6  # an IMU sample: angular velocity [rad/s], then specific force [m/s^2], body FRD (imu's field order)
IMU_NOISE_CHANNEL, IMU_BIAS_CHANNEL = 24, 30  # the IMU's generator channels: white noise 24 .. 29, walks 30 .. 35


class ImuParams(NamedTuple):
    """The IMU's sensor stage (:func:`measure_imu`); each 6-tuple is gyro x y z, then accelerometer x y z."""

    enabled: bool  # imu is published (its row computed)
    noisy: bool  # any noise, bias walk or initial bias (else the true values, delayed and held)
    seed: int  # 0 .. 2^32 - 1
    noise_std: tuple  # white noise per sample: density sqrt(rate) [rad/s], [m/s^2]
    walk_std: tuple  # bias increment per published state: walk sqrt(period) [rad/s], [m/s^2]
    initial_bias: tuple  # [rad/s], [m/s^2]
    delay: int  # published states the measurement is late by
    every: int  # a new sample every this many published states (the others hold it)


class SensorParams(NamedTuple):
    """Both sensor stages (``PlantParams.sensors``)."""

    odometry: OdometryParams
    imu: ImuParams


SENSOR_MEMORY = np.dtype([
    ("odometry_step", np.int64),  # the last step whose bias walk was taken (-1: none yet)
    ("odometry_bias", np.float64, (12,)),  # position, attitude rotation vector, velocity, angular velocity
    ("odometry_held", np.float64, (ODOM_SIZE,)),  # the measurement held between new ones (rate)
    ("imu_step", np.int64),  # the last step whose bias was moved (-1: none yet; the initial bias at the first)
    ("imu_bias", np.float64, (IMU_SIZE,)),
    ("imu_held", np.float64, (IMU_SIZE,)),
], align=True)
"""The fields of :attr:`SensorMemory.fields`, read and written in place as ``memory.fields[0].imu_bias``."""


class SensorMemory(NamedTuple):
    """What both sensor stages keep between published states (``PlantState.sensor_memory``)."""

    fields: np.ndarray  # (1,) SENSOR_MEMORY record
    odometry_history: np.ndarray  # (delay + 1, ODOM_SIZE) delay line: step k's measurement at row k % (delay + 1)
    imu_history: np.ndarray  # (delay + 1, IMU_SIZE) the IMU's


def new_sensor_memory(params: SensorParams) -> SensorMemory:
    """Both stages' memory at the start of a flight (no state measured yet: :func:`reset_sensor_memory`)."""
    memory = SensorMemory(zeroed_record(SENSOR_MEMORY),
                          np.zeros((params.odometry.delay + 1, ODOM_SIZE)),
                          np.zeros((params.imu.delay + 1, IMU_SIZE)))
    reset_sensor_memory(memory)
    return memory


@jit
def reset_sensor_memory(memory: SensorMemory) -> None:
    """Both stages' memory as at the start of a flight: nothing measured yet."""
    fields = memory.fields[0]
    fields.odometry_step = -1
    fields.imu_step = -1
    fields.odometry_bias[:] = 0.0
    fields.odometry_held[:] = 0.0
    fields.imu_bias[:] = 0.0
    fields.imu_held[:] = 0.0
    memory.odometry_history[:] = 0.0
    memory.imu_history[:] = 0.0


@jit
def mix32(x: int) -> int:
    """The ``lowbias32`` integer hash of ``x`` (taken mod 2^32): a 32-bit value."""
    x = x & MASK32
    x = x ^ (x >> 16)
    x = (x * 0x7FEB352D) & MASK32
    x = x ^ (x >> 15)
    x = (x * 0x846CA68B) & MASK32
    return x ^ (x >> 16)


@jit
def standard_normal(seed: int, step: int, channel: int) -> float:
    """A standard normal number determined by (seed, step, channel) alone (module docstring)."""
    key = mix32(mix32(mix32(seed) ^ (step & MASK32)) ^ (step >> 32))
    u1 = (mix32(key ^ (2 * channel)) + 0.5) * (1.0 / 4294967296.0)  # in (0, 1)
    u2 = (mix32(key ^ (2 * channel + 1)) + 0.5) * (1.0 / 4294967296.0)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@jit_inline
def sense(params: OdometryParams, step: int, out, bias) -> None:  # noqa: ANN001
    """Turn the true published ``odom`` (the first 13 numbers of ``out``, :mod:`fsr_sim.core.odometry`) of step
    ``step`` into the measured one: white noise plus ``bias`` (12,: position, attitude rotation vector,
    velocity, angular velocity); nothing when the stage is off."""
    if not params.enabled:
        return
    seed = params.seed
    for i in range(3):
        out[ODOM_POSITION + i] += (params.position_std * standard_normal(seed, step, POSITION + i)
                                   + bias[POSITION + i])
        out[ODOM_VELOCITY + i] += (params.velocity_std * standard_normal(seed, step, VELOCITY + i)
                                   + bias[VELOCITY + i])
        out[ODOM_ANGULAR_VELOCITY + i] += (params.angular_velocity_std
                                           * standard_normal(seed, step, ANGULAR_VELOCITY + i)
                                           + bias[ANGULAR_VELOCITY + i])
    nx = params.attitude_std * standard_normal(seed, step, ATTITUDE) + bias[ATTITUDE]
    ny = params.attitude_std * standard_normal(seed, step, ATTITUDE + 1) + bias[ATTITUDE + 1]
    nz = params.attitude_std * standard_normal(seed, step, ATTITUDE + 2) + bias[ATTITUDE + 2]
    angle = math.sqrt(nx * nx + ny * ny + nz * nz)
    if angle > 0.0:  # q (x) Exp(n): the rotation vector n in the body frame, quaternions [x, y, z, w]
        s = math.sin(0.5 * angle) / angle
        bx, by, bz, bw = nx * s, ny * s, nz * s, math.cos(0.5 * angle)
        q = ODOM_QUATERNION
        ax, ay, az, aw = out[q], out[q + 1], out[q + 2], out[q + 3]
        qx = aw * bx + ax * bw + ay * bz - az * by
        qy = aw * by - ax * bz + ay * bw + az * bx
        qz = aw * bz + ax * by - ay * bx + az * bw
        qw = aw * bw - ax * bx - ay * by - az * bz
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if qw < 0.0:  # odom's sign convention: w >= 0
            norm = -norm
        out[q], out[q + 1], out[q + 2], out[q + 3] = qx / norm, qy / norm, qz / norm, qw / norm


@jit_inline
def _delayed_and_held(history, held, delay: int, every: int, step: int, out) -> None:  # noqa: ANN001
    """A stage's delay and rate on its measurement ``out`` (``history.shape[1]`` numbers) of step ``step``:
    published as the measurement of step ``step - delay`` (of step 0 before; ``history``: the delay line,
    ``delay + 1`` rows), then a new one every ``every`` steps, ``held`` in between."""
    size = history.shape[1]
    if delay > 0:
        slots = delay + 1
        write = step % slots
        for i in range(size):
            history[write, i] = out[i]
        read = (step - delay) % slots if step >= delay else 0
        for i in range(size):
            out[i] = history[read, i]
    if every > 1:
        if step % every == 0:
            for i in range(size):
                held[i] = out[i]
        else:
            for i in range(size):
                out[i] = held[i]


@jit_inline
def measure_odometry(params: OdometryParams, memory: SensorMemory, step: int, out) -> None:  # noqa: ANN001
    """The whole odometry stage on the published row ``out`` of step ``step`` (``memory``: both stages',
    :func:`new_sensor_memory`):

    1. bias random walks: per step, ``b <- b + walk sqrt(T) n`` per channel (once per step, however often the
       step is published), then white noise plus the bias (:func:`sense`);
    2. delay: the row published at step ``k`` is the measurement of step ``k - delay`` (of step 0 before);
    3. rate: a new measurement every ``every`` steps, held in between.
    ``wrench_truth`` (the rest of the row) stays the true one, of step ``k``."""
    fields = memory.fields[0]
    if params.enabled:
        if step > fields.odometry_step:
            scale = math.sqrt(params.period)
            for group in range(4):
                walk = params.walks[group] * scale
                if walk > 0.0:
                    for i in range(3):
                        channel = 3 * group + i
                        fields.odometry_bias[channel] += walk * standard_normal(params.seed, step,
                                                                                BIAS_CHANNEL + channel)
            fields.odometry_step = step
        sense(params, step, out, fields.odometry_bias)
    _delayed_and_held(memory.odometry_history, fields.odometry_held, params.delay, params.every, step, out)


@jit_inline
def measure_imu(params: ImuParams, memory: SensorMemory, step: int, out) -> None:  # noqa: ANN001
    """The IMU stage on ``out`` (6,): the true angular velocity [rad/s] and specific force [m/s^2] of step
    ``step`` in, what ``imu`` publishes out (``memory``: both stages', :func:`new_sensor_memory`):

    1. bias: its initial value at the first step, then per step ``b <- b + walk sqrt(T) n`` per axis; white
       noise ``density sqrt(rate) n`` plus the bias (nothing of either for an ideal IMU);
    2. delay: the sample published at step ``k`` is the measurement of step ``k - delay`` (of step 0 before);
    3. rate: a new sample every ``every`` steps, held in between."""
    fields = memory.fields[0]
    if params.noisy:
        if step > fields.imu_step:
            first = fields.imu_step < 0
            for i in range(IMU_SIZE):
                if first:
                    fields.imu_bias[i] = params.initial_bias[i]
                elif params.walk_std[i] > 0.0:
                    fields.imu_bias[i] += params.walk_std[i] * standard_normal(params.seed, step, IMU_BIAS_CHANNEL + i)
            fields.imu_step = step
        for i in range(IMU_SIZE):
            out[i] += (params.noise_std[i] * standard_normal(params.seed, step, IMU_NOISE_CHANNEL + i)
                       + fields.imu_bias[i])
    _delayed_and_held(memory.imu_history, fields.imu_held, params.delay, params.every, step, out)
