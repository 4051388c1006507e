"""The sensor stage between the true state and ``odom`` (compiled core): what the simulator publishes as its
measurement of the state, in the simulator node and the in-process loop alike (:func:`fsr_sim.core.lockstep.
publish` applies it to the published row).

The model (:func:`measure`, :class:`SensorParams`): white Gaussian noise per published state, per channel, plus a
bias per channel that walks randomly, on position world NED [m], attitude as a body rotation vector ``n`` [rad]
(``R_meas = R Exp(n)``), body linear velocity [m/s] and body angular velocity [rad/s]; then a delay (in
published states) and a lower rate (a new measurement every ``every`` states, held between). With everything
zero (the default) the stage is off and ``odom`` is the true state, bit for bit. ``wrench_truth`` stays true.

The numbers come from a counter-based generator: the standard normal of (seed, step, channel) is a 32-bit integer
hash of the three (two uniforms, Box-Muller), so it depends on nothing else - not on who computes it, in which
process, or in which order - and the node graph and the in-process loop publish the same noisy ``odom``, compiled
and under CPython. (The hash is ``lowbias32``; integer products are masked to 32 bits, so int64 wrap-around in
compiled code and Python's unbounded integers give the same bits.)
"""

from __future__ import annotations

import math
from typing import NamedTuple

from fsr_sim.core.jit import jit, jit_inline

MASK32 = 0xFFFFFFFF
POSITION, ATTITUDE, VELOCITY, ANGULAR_VELOCITY = 0, 3, 6, 9  # first channel of each noise group


class SensorParams(NamedTuple):
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


MEMORY_STEP, MEMORY_BIAS, MEMORY_HELD, MEMORY_HISTORY = 0, 1, 13, 26  # sensor memory layout (see measure)
BIAS_CHANNEL = 12  # the bias walks' generator channels: 12 .. 23


def memory_size(delay: int) -> int:
    """Floats of :func:`measure`'s memory for a delay of ``delay`` states."""
    return MEMORY_HISTORY + 13 * (delay + 1)


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
def sense(params: SensorParams, step: int, out, bias) -> None:  # noqa: ANN001
    """Turn the true published ``odom`` (the first 13 numbers of ``out``, :mod:`fsr_sim.core.odometry`) of step
    ``step`` into the measured one: white noise plus ``bias`` (12,: position, attitude rotation vector,
    velocity, angular velocity); nothing when the stage is off."""
    if not params.enabled:
        return
    seed = params.seed
    for i in range(3):
        out[i] += params.position_std * standard_normal(seed, step, POSITION + i) + bias[POSITION + i]
        out[7 + i] += params.velocity_std * standard_normal(seed, step, VELOCITY + i) + bias[VELOCITY + i]
        out[10 + i] += (params.angular_velocity_std * standard_normal(seed, step, ANGULAR_VELOCITY + i)
                        + bias[ANGULAR_VELOCITY + i])
    nx = params.attitude_std * standard_normal(seed, step, ATTITUDE) + bias[ATTITUDE]
    ny = params.attitude_std * standard_normal(seed, step, ATTITUDE + 1) + bias[ATTITUDE + 1]
    nz = params.attitude_std * standard_normal(seed, step, ATTITUDE + 2) + bias[ATTITUDE + 2]
    angle = math.sqrt(nx * nx + ny * ny + nz * nz)
    if angle > 0.0:  # q (x) Exp(n): the rotation vector n in the body frame, quaternions [x, y, z, w]
        s = math.sin(0.5 * angle) / angle
        bx, by, bz, bw = nx * s, ny * s, nz * s, math.cos(0.5 * angle)
        ax, ay, az, aw = out[3], out[4], out[5], out[6]
        qx = aw * bx + ax * bw + ay * bz - az * by
        qy = aw * by - ax * bz + ay * bw + az * bx
        qz = aw * bz + ax * by - ay * bx + az * bw
        qw = aw * bw - ax * bx - ay * by - az * bz
        norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
        if qw < 0.0:  # odom's sign convention: w >= 0
            norm = -norm
        out[3], out[4], out[5], out[6] = qx / norm, qy / norm, qz / norm, qw / norm


@jit_inline
def measure(params: SensorParams, memory, step: int, out) -> None:  # noqa: ANN001
    """The whole sensor stage on the published row ``out`` of step ``step`` (``memory``: :func:`memory_size`
    floats, ``memory[MEMORY_STEP]`` = -1 at the start):

    1. bias random walks: per step, ``b <- b + walk sqrt(T) n`` per channel (once per step, however often the
       step is published), then white noise plus the bias (:func:`sense`);
    2. delay: the row published at step ``k`` is the measurement of step ``k - delay`` (of step 0 before);
    3. rate: a new measurement every ``every`` steps, held in between.
    ``wrench_truth`` (the rest of the row) stays the true one, of step ``k``."""
    if params.enabled:
        if step > memory[MEMORY_STEP]:
            scale = math.sqrt(params.period)
            for group in range(4):
                walk = params.walks[group] * scale
                if walk > 0.0:
                    for i in range(3):
                        channel = 3 * group + i
                        memory[MEMORY_BIAS + channel] += walk * standard_normal(params.seed, step,
                                                                                BIAS_CHANNEL + channel)
            memory[MEMORY_STEP] = step
        sense(params, step, out, memory[MEMORY_BIAS:MEMORY_HELD])
    if params.delay > 0:
        slots = params.delay + 1
        write = MEMORY_HISTORY + 13 * (step % slots)
        for i in range(13):
            memory[write + i] = out[i]
        read = MEMORY_HISTORY + (13 * ((step - params.delay) % slots) if step >= params.delay else 0)
        for i in range(13):
            out[i] = memory[read + i]
    if params.every > 1:
        if step % params.every == 0:
            for i in range(13):
                memory[MEMORY_HELD + i] = out[i]
        else:
            for i in range(13):
                out[i] = memory[MEMORY_HELD + i]
