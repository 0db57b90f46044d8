"""The sensor as compiled code sees it: plain arrays, built once from a sensor and a delay.

:func:`channel_arrays` turns a :class:`~flexarm.sensing.sensors.Sensor`, its
:class:`~flexarm.sensing.delays.DelayModel` and the integrator's substep into the
:class:`SensorArrays` that the closed loop (:func:`flexarm.simulate`) and the
Gymnasium environments read; their compiled half (raw signal, delay line, noise,
quantisation) is the internal module ``flexarm.sensing._channels``, shared by both. :func:`sense`
is the raw signal from Python, arguments checked (inside compiled code the same
name is the kernel, unchecked).

A signal has ``n_ch`` channels: for the joint encoders the angles then the rates
of the ``n_links`` joints (``n_ch = 2 n_links``; rad, rad/s), for a point its
position then velocity (``n_ch = 4``; m, m/s). Delays act at the integrator's
substep resolution ``h``: the exact delay is a ring buffer of the raw signal,
rounded to whole substeps; the Padé delay a discrete state-space filter,
discretised exactly over one substep (zero-order hold on its input). Noise is
added to the delayed signal, then each channel is rounded to its resolution.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .._compile import compiled_as
from .._types import F64
from ..errors import InvalidValueError
from ..model.arrays import ArmArrays
from ..model.kernel_checks import check_model, check_vector
from ..model.kinematics import lever_lengths
from ..model.plant import Plant
from . import _channels
from ._channels import SensorArrays
from .delays import DelayModel, discretize, pade_state_space
from .sensors import Sensor

__all__ = [
    "Channels",
    "SensorArrays",
    "channel_arrays",
    "check_sensor_arrays",
    "sense",
    "sensor_arrays",
]


SensorArrays.__doc__ = """The sensor and its delay as plain arrays (build with
:func:`sensor_arrays` or :func:`channel_arrays`).

Attributes
----------
link : int64 (1,)
    Link of the sensed point, -1 for the joint encoders.
rigid : int64 (1,)
    1: the point is the rigid kinematics of the encoder angles (the paper's
    sensor model), 0: the deflected point.
distance : (1,)
    Distance of the point along its link, m.
phi : (n_modes of link,)
    Mode shapes at the point (then, with geometric stiffening, the link's
    shortening matrix there: FlexibleArm.point_basis).
levers : (n_links,)
    Lever lengths of the rigid kinematics of the encoder angles (the link
    lengths for the joint encoders, the point's for the paper's model), m.
delay_steps : int64 (1,)
    Exact delay in substeps (0: none unless Padé).
pade_ad, pade_bd, pade_cd, pade_dd : (p, p), (p,), (p,), (1,)
    Discrete Padé filter of order p; p = 0 for no Padé.
pade_gain : (p,)
    Steady-state gain ``(I - Ad)^-1 Bd`` of the filter's state.
levels : (n_ch,)
    Standard deviation of each channel's additive noise (rad, rad/s, m, m/s).
resolution : (n_ch,)
    Quantisation steps (0: none).
"""


def sensor_arrays(
    *,
    link: int,
    rigid: bool,
    distance: float,
    phi: F64,
    levers: F64,
    delay_steps: int,
    pade: tuple[F64, F64, F64, F64] | None,
    levels: F64,
    resolution: F64,
) -> SensorArrays:
    """The one way to build :class:`SensorArrays`: by keyword, shapes checked.

    Parameters
    ----------
    link : int
        Link of the sensed point (0-based), or -1 for the joint encoders.
    rigid : bool
        The point is the rigid kinematics of the encoder angles (``levers``).
    distance : float
        Distance of the point along its link, m (0 for the encoders).
    phi : ndarray, shape (n_modes of link,) or (n_modes + n_modes**2,)
        Mode shapes at the point (empty for the encoders).
    levers : ndarray, shape (n_links,)
        Lever lengths of the rigid kinematics of the encoder angles, m.
    delay_steps : int
        Exact transport delay in substeps (>= 0).
    pade : tuple of ndarray, optional
        Discrete Padé filter ``(Ad (p, p), Bd (p,), Cd (p,), Dd (1,))``.
    levels : ndarray, shape (n_ch,)
        Noise standard deviation of each channel (0: none).
    resolution : ndarray, shape (n_ch,)
        Quantisation steps (0: none).
    """
    n_ch = 4 if link >= 0 else 2 * int(np.asarray(levers).shape[0])
    ad, bd, cd, dd = (
        pade if pade is not None else (np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(1))
    )
    ad = np.ascontiguousarray(ad, dtype=np.float64)
    bd = np.ascontiguousarray(np.ravel(bd), dtype=np.float64)
    p = ad.shape[0]
    checks = {
        "pade": ad.shape == (p, p)
        and bd.shape == (p,)
        and np.shape(np.ravel(cd)) == (p,)
        and np.shape(np.ravel(dd)) == (1,),
        "levels": np.shape(levels) == (n_ch,),
        "resolution": np.shape(resolution) == (n_ch,),
        "delay_steps": delay_steps >= 0,
    }
    for name, ok in checks.items():
        if not ok:
            raise InvalidValueError(
                f"The '{name}' parameter of sensor_arrays does not fit a sensor with "
                f"{n_ch} channels and a Padé filter of order {p}."
            )
    gain = np.linalg.solve(np.eye(p) - ad, bd) if p else np.zeros(0)
    return SensorArrays(
        link=np.array([link], dtype=np.int64),
        rigid=np.array([int(bool(rigid))], dtype=np.int64),
        distance=np.array([distance], dtype=np.float64),
        phi=np.ascontiguousarray(phi, dtype=np.float64),
        levers=np.ascontiguousarray(levers, dtype=np.float64),
        delay_steps=np.array([delay_steps], dtype=np.int64),
        pade_ad=ad,
        pade_bd=bd,
        pade_cd=np.ascontiguousarray(np.ravel(cd), dtype=np.float64),
        pade_dd=np.ascontiguousarray(np.ravel(dd), dtype=np.float64),
        pade_gain=np.ascontiguousarray(gain, dtype=np.float64),
        levels=np.ascontiguousarray(levels, dtype=np.float64),
        resolution=np.ascontiguousarray(resolution, dtype=np.float64),
    )


class Channels(NamedTuple):
    """A sensor ready for compiled code: its arrays and the delay they realise.

    Attributes
    ----------
    arrays : SensorArrays
    n_ch : int
        Channels of the signal.
    delay : float
        The delay actually realised, s (the exact delay rounded to whole substeps).
    noisy : bool
        Whether any channel has noise (the run then draws a row per instant).
    """

    arrays: SensorArrays
    n_ch: int
    delay: float
    noisy: bool


def channel_arrays(arm: Plant, sensor: Sensor, delay: DelayModel, h: float) -> Channels:
    """``sensor`` with ``delay`` on ``arm``, at substep resolution ``h`` (s), as plain
    arrays: the one place a sensor becomes what the compiled code reads."""
    link, distance, phi = sensor.resolve(arm)
    n_ch = 2 * arm.n_links if link < 0 else 4
    half = n_ch // 2
    levels = np.r_[np.full(half, sensor.noise_std), np.full(half, sensor.rate_noise_std)]
    resolution = np.r_[np.full(half, sensor.quantization), np.full(half, sensor.rate_quantization)]
    delay_steps, pade, effective = 0, None, 0.0
    if delay.delay > 0:
        if delay.method == "exact":
            delay_steps = round(delay.delay / h)
            effective = delay_steps * h
        else:
            ad, bd, cd, dd = discretize(*pade_state_space(delay.delay, delay.order), h)
            pade = (ad, bd[:, 0], cd[0], dd[0])
            effective = delay.delay
    rigid = link >= 0 and sensor.model == "paper"
    lengths = np.asarray(arm.link_lengths, dtype=float)
    arrays = sensor_arrays(
        link=link,
        rigid=rigid,
        distance=distance,
        phi=phi,
        levers=lever_lengths(lengths, link, distance) if rigid else lengths,
        delay_steps=delay_steps,
        pade=pade,
        levels=levels,
        resolution=resolution,
    )
    return Channels(arrays=arrays, n_ch=n_ch, delay=effective, noisy=bool(np.any(levels > 0)))


def check_sensor_arrays(sensor: SensorArrays, model: ArmArrays, owner: str) -> tuple[int, int]:
    """``(n_ch, pade order)`` of ``sensor`` for ``model``, every array it holds checked."""
    if not isinstance(sensor, SensorArrays):
        raise InvalidValueError(
            f"The 'sensor' parameter of {owner} must be a SensorArrays (sensor_arrays)."
        )
    n_links, _ = check_model(model, owner)
    for name in ("link", "rigid", "delay_steps"):
        check_vector(getattr(sensor, name), f"sensor.{name}", owner, (1,), dtype=np.int64)
    check_vector(sensor.distance, "sensor.distance", owner, (1,))
    link = int(sensor.link[0])
    if not -1 <= link < n_links:
        raise InvalidValueError(
            f"The 'sensor.link' parameter of {owner} must be -1 (encoders) or a link of the "
            f"model (< {n_links}). Got {link} instead."
        )
    n_ch = 2 * n_links if link < 0 else 4
    if link >= 0:
        modes = int(model.mode_start[link + 1] - model.mode_start[link])
        if sensor.phi.shape not in ((modes,), (modes + modes * modes,)):
            raise InvalidValueError(
                f"The 'sensor.phi' parameter of {owner} must fit link {link}'s {modes} modes. "
                f"Got shape {sensor.phi.shape} instead."
            )
    check_vector(sensor.phi, "sensor.phi", owner, sensor.phi.shape)
    check_vector(sensor.levers, "sensor.levers", owner, (n_links,))
    p = sensor.pade_ad.shape[0] if sensor.pade_ad.ndim == 2 else -1
    check_vector(sensor.pade_ad, "sensor.pade_ad", owner, (p, p))
    check_vector(sensor.pade_bd, "sensor.pade_bd", owner, (p,))
    check_vector(sensor.pade_cd, "sensor.pade_cd", owner, (p,))
    check_vector(sensor.pade_dd, "sensor.pade_dd", owner, (1,))
    check_vector(sensor.pade_gain, "sensor.pade_gain", owner, (p,))
    check_vector(sensor.levels, "sensor.levels", owner, (n_ch,))
    check_vector(sensor.resolution, "sensor.resolution", owner, (n_ch,))
    return n_ch, p


def sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw (true, undelayed) sensed signal into ``out``, arguments checked.

    Parameters
    ----------
    q, dq : ndarray, shape (n_dof,)
        The arm's state.
    model : ArmArrays
        The arm's arrays (``FlexibleArm.arrays``).
    sensor : SensorArrays
    out : ndarray, shape (n_ch,)
        The encoder angles then rates (rad, rad/s), or the point's position then
        velocity (m, m/s).
    """
    owner = "sense"
    _, n = check_model(model, owner)
    n_ch, _ = check_sensor_arrays(sensor, model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_vector(out, "out", owner, (n_ch,), writable=True)
    _channels.sense(q, dq, model, sensor, out)


@compiled_as(sense)
def _sense_compiled(q, dq, model, sensor, out):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, sensor, out: _channels.sense(q, dq, model, sensor, out)
