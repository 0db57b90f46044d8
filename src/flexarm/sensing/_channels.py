"""The sensor's compiled half: the raw signal, its delay line, noise and quantisation.

Internal module (plain names, unchecked compiled code): the layout of the
sensor's plain arrays (:class:`SensorArrays`; built, checked and documented for
users by :mod:`flexarm.sensing.channels`) and what the closed loop
(:mod:`flexarm.sim.loop`) and the environments' step (:mod:`flexarm.envs.step`)
call at every control instant and substep. Every function is inlined where it is
called, so the model's and the sensor's arrays never cross a call.

A sensor's signal has ``n_ch`` channels: the encoder angles then rates (rad,
rad/s), or a point's position then velocity (m, m/s). Per control instant:
:func:`sense` (true, undelayed) -> :func:`delayed_signal` (the exact delay's ring
buffer, or the discrete Padé filter's output) -> :func:`corrupt` (additive noise,
then quantisation). Per substep, around the integrator's step:
:func:`advance_pade` before it (the filter's input is held over the substep) and
:func:`record_sample` after it (the ring buffer's newest sample).
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np

from .._types import F64, I64
from ..model.arrays import ArmArrays
from ..model.dynamics._points import point_kinematics

__all__ = [
    "SensorArrays",
    "advance_pade",
    "collocated",
    "corrupt",
    "delayed_signal",
    "prime",
    "record_sample",
    "rigid_chain_point",
    "sense",
]


class SensorArrays(NamedTuple):
    """A sensor and its delay as plain arrays (fields documented in
    :mod:`flexarm.sensing.channels`, which builds them)."""

    link: I64
    rigid: I64
    distance: F64
    phi: F64
    levers: F64
    delay_steps: I64
    pade_ad: F64
    pade_bd: F64
    pade_cd: F64
    pade_dd: F64
    pade_gain: F64
    levels: F64
    resolution: F64


@nb.njit(cache=True, nogil=True, inline="always")
def collocated(q: F64, dq: F64, model: ArmArrays, i: int, n_links: int) -> tuple[float, float]:
    """Encoder angle and rate of joint ``i`` (rad, rad/s): the motor's with flexible
    joints."""
    if model.joint.shape[0] > 0:
        m = model.mode_start[n_links] + i
        return q[m], dq[m]
    return q[i], dq[i]


@nb.njit(cache=True, nogil=True, inline="always")
def rigid_chain_point(levers: F64, angles: F64, rates: F64, out: F64) -> None:
    """Position then velocity (``out[:4]``, m and m/s) of the point with these lever
    lengths on a rigid chain at these joint angles and rates (rad, rad/s): the
    paper's sensor model, and the point the loop forms from measured angles."""
    px = 0.0
    py = 0.0
    vx = 0.0
    vy = 0.0
    phi = 0.0
    phid = 0.0
    for i in range(levers.shape[0]):
        phi += angles[i]
        phid += rates[i]
        lever = levers[i]
        px += lever * np.cos(phi)
        py += lever * np.sin(phi)
        vx -= lever * np.sin(phi) * phid
        vy += lever * np.cos(phi) * phid
    out[0] = px
    out[1] = py
    out[2] = vx
    out[3] = vy


@nb.njit(cache=True, nogil=True, inline="always")
def sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw (true, undelayed) signal into ``out`` (n_ch,): the encoder angles then
    rates, or the point's position then velocity (deflected, or the paper's rigid
    kinematics of the encoder angles)."""
    n_links = model.link.shape[0]
    link = sensor.link[0]
    if link < 0:
        for i in range(n_links):
            a, r = collocated(q, dq, model, i, n_links)
            out[i] = a
            out[n_links + i] = r
    elif sensor.rigid[0]:  # the paper's sensor model: rigid kinematics of the encoders
        e = model.mode_start[n_links] if model.joint.shape[0] > 0 else 0  # motors or joints
        rigid_chain_point(sensor.levers, q[e : e + n_links], dq[e : e + n_links], out)
    else:
        point_kinematics(q, dq, model, link, sensor.distance[0], sensor.phi, out)


@nb.njit(cache=True, nogil=True, inline="always")
def delayed_signal(
    sensor: SensorArrays, buffer: F64, pade_x: F64, cursor: int, raw: F64, out: F64
) -> None:
    """The delayed signal into ``out`` (n_ch,) from the raw one (``raw``, just sensed):
    the ring ``buffer`` (shape (delay_steps + 1, n_ch)) read ``delay_steps``
    substeps behind ``cursor`` (substeps integrated so far; before the start, its
    first sample), or the Padé filter's output from its state ``pade_x`` (n_ch, p),
    or ``raw`` itself."""
    n_ch = out.shape[0]
    n_buf = buffer.shape[0]
    order = sensor.pade_ad.shape[0]
    if n_buf > 1:
        src = cursor - (n_buf - 1)
        if src < 0:
            src = 0
        for c in range(n_ch):
            out[c] = buffer[src % n_buf, c]
    elif order > 0:
        for c in range(n_ch):
            acc = sensor.pade_dd[0] * raw[c]
            for j in range(order):
                acc += sensor.pade_cd[j] * pade_x[c, j]
            out[c] = acc
    else:
        for c in range(n_ch):
            out[c] = raw[c]


@nb.njit(cache=True, nogil=True, inline="always")
def corrupt(sensor: SensorArrays, noisy: bool, z: F64, signal: F64) -> None:
    """Noise and quantisation in place on ``signal`` (n_ch,): if ``noisy``, ``levels *
    z`` added (``z`` standard normal draws, (n_ch,); not read otherwise), then each
    channel rounded to a multiple of its resolution (where > 0)."""
    for c in range(signal.shape[0]):
        v = signal[c]
        if noisy:
            v += sensor.levels[c] * z[c]
        res = sensor.resolution[c]
        if res > 0.0:
            v = np.round(v / res) * res
        signal[c] = v


@nb.njit(cache=True, nogil=True, inline="always")
def advance_pade(
    q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, pade_x: F64, raw: F64, x_new: F64
) -> None:
    """Before a substep: the Padé filter's state ``x <- Ad x + Bd u`` over it, its
    input ``u`` the raw signal at the substep's start (held). ``raw`` (n_ch,) and
    ``x_new`` (p,) are scratch. Nothing without a Padé filter."""
    order = sensor.pade_ad.shape[0]
    if order == 0:
        return
    sense(q, dq, model, sensor, raw)
    for c in range(raw.shape[0]):
        for j in range(order):
            acc = sensor.pade_bd[j] * raw[c]
            for i2 in range(order):
                acc += sensor.pade_ad[j, i2] * pade_x[c, i2]
            x_new[j] = acc
        for j in range(order):
            pade_x[c, j] = x_new[j]


@nb.njit(cache=True, nogil=True, inline="always")
def record_sample(
    q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, buffer: F64, cursor: int, raw: F64
) -> None:
    """After a substep (``cursor`` substeps integrated, counting it): the raw signal
    into the ring ``buffer``'s slot ``cursor``. Nothing without an exact delay."""
    n_buf = buffer.shape[0]
    if n_buf > 1:
        sense(q, dq, model, sensor, raw)
        slot = cursor % n_buf
        for c in range(raw.shape[0]):
            buffer[slot, c] = raw[c]


@nb.njit(cache=True, nogil=True, inline="always")
def prime(
    q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, buffer: F64, pade_x: F64, raw: F64
) -> None:
    """The delay line at steady state on the signal sensed at ``q, dq``: every slot
    of the ring ``buffer`` holds it, the Padé state is ``(I - Ad)^-1 Bd`` times it."""
    sense(q, dq, model, sensor, raw)
    n_ch = raw.shape[0]
    for s in range(buffer.shape[0]):
        for c in range(n_ch):
            buffer[s, c] = raw[c]
    order = sensor.pade_gain.shape[0]
    for c in range(n_ch):
        for j in range(order):
            pade_x[c, j] = raw[c] * sensor.pade_gain[j]
