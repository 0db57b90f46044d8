"""The sensor in compiled code: its plain arrays and the raw sensed signal.

:class:`SensorArrays` is a sensor (:mod:`flexarm.sensing.sensors`) with its delay
and noise as the plain arrays the compiled loop reads (build it with
:func:`sensor_arrays`); :func:`sense` forms the raw (true, undelayed) signal:
the encoder angles and rates, or a point's position and velocity (deflected,
or the paper's rigid kinematics of the encoder angles). The loop
(:mod:`flexarm.sim.loop`) delays, corrupts and quantises it.
"""

from __future__ import annotations

from typing import NamedTuple

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .._compile import compiled_as
from ..errors import InvalidValueError
from ..model.arrays import ArmArrays
from ..model.dynamics._points import point_kinematics
from ..model.kernel_checks import check_model, check_vector

__all__ = ["SensorArrays", "check_sensor_arrays", "sense", "sensor_arrays"]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]


class SensorArrays(NamedTuple):
    """The sensor as plain arrays (build with :func:`sensor_arrays`).

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
    noise : (n_steps + 1, n_channels)
        Additive noise per control instant, or (0, n_channels).
    resolution : (n_channels,)
        Quantisation steps (0: none).
    """

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
    noise: F64
    resolution: F64


def sensor_arrays(
    *,
    link: int,
    rigid: bool,
    distance: float,
    phi: F64,
    levers: F64,
    delay_steps: int,
    pade: tuple[F64, F64, F64, F64] | None,
    noise: F64,
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
    noise : ndarray, shape (n_rows, n_channels) or (0, n_channels)
        Additive noise per control instant.
    resolution : ndarray, shape (n_channels,)
        Quantisation steps (0: none).
    """
    n_ch = 4 if link >= 0 else 2 * int(np.asarray(levers).shape[0])
    ad, bd, cd, dd = (
        pade if pade is not None else (np.zeros((0, 0)), np.zeros(0), np.zeros(0), np.zeros(1))
    )
    out = SensorArrays(
        link=np.array([link], dtype=np.int64),
        rigid=np.array([int(bool(rigid))], dtype=np.int64),
        distance=np.array([distance], dtype=np.float64),
        phi=np.ascontiguousarray(phi, dtype=np.float64),
        levers=np.ascontiguousarray(levers, dtype=np.float64),
        delay_steps=np.array([delay_steps], dtype=np.int64),
        pade_ad=np.ascontiguousarray(ad, dtype=np.float64),
        pade_bd=np.ascontiguousarray(np.ravel(bd), dtype=np.float64),
        pade_cd=np.ascontiguousarray(np.ravel(cd), dtype=np.float64),
        pade_dd=np.ascontiguousarray(np.ravel(dd), dtype=np.float64),
        noise=np.ascontiguousarray(noise, dtype=np.float64),
        resolution=np.ascontiguousarray(resolution, dtype=np.float64),
    )
    p = out.pade_ad.shape[0]
    checks = {
        "pade": out.pade_ad.shape == (p, p)
        and out.pade_bd.shape == (p,)
        and out.pade_cd.shape == (p,)
        and out.pade_dd.shape == (1,),
        "noise": out.noise.ndim == 2 and out.noise.shape[1] == n_ch,
        "resolution": out.resolution.shape == (n_ch,),
        "delay_steps": delay_steps >= 0,
    }
    for name, ok in checks.items():
        if not ok:
            raise InvalidValueError(
                f"The '{name}' parameter of sensor_arrays does not fit a sensor with "
                f"{n_ch} channels and a Padé filter of order {p}."
            )
    return out


@nb.njit(cache=True, nogil=True, inline="always")
def _collocated(q: F64, dq: F64, model: ArmArrays, i: int, n_links: int) -> tuple[float, float]:
    """Encoder angle and rate of joint ``i``: the motor with flexible joints."""
    if model.joint.shape[0] > 0:
        m = model.mode_start[n_links] + i
        return q[m], dq[m]
    return q[i], dq[i]


@nb.njit(cache=True, nogil=True, inline="always")
def _rigid_chain_point(levers: F64, angles: F64, rates: F64, out: F64) -> None:
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
def _sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw (true, undelayed) sensed signal: the encoder angles then rates, or
    the point's position then velocity (deflected, or the paper's rigid
    kinematics of the encoder angles).

    Inlined where :func:`run` calls it (the model's and the sensor's arrays would
    otherwise be passed through a call at every control step).
    """
    n_links = model.link.shape[0]
    link = sensor.link[0]
    if link < 0:
        for i in range(n_links):
            a, r = _collocated(q, dq, model, i, n_links)
            out[i] = a
            out[n_links + i] = r
    elif sensor.rigid[0]:  # the paper's sensor model: rigid kinematics of the encoders
        e = model.mode_start[n_links] if model.joint.shape[0] > 0 else 0  # motors or joints
        _rigid_chain_point(sensor.levers, q[e : e + n_links], dq[e : e + n_links], out)
    else:
        point_kinematics(q, dq, model, link, sensor.distance[0], sensor.phi, out)


def check_sensor_arrays(sensor: SensorArrays, model: ArmArrays, owner: str) -> tuple[int, int]:
    """``(n_channels, pade order)`` of ``sensor`` for ``model``."""
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
    rows = sensor.noise.shape[0] if sensor.noise.ndim == 2 else -1
    check_vector(sensor.noise, "sensor.noise", owner, (rows, n_ch))
    check_vector(sensor.resolution, "sensor.resolution", owner, (n_ch,))
    return n_ch, p


def sense(q: F64, dq: F64, model: ArmArrays, sensor: SensorArrays, out: F64) -> None:
    """The raw sensed signal (``_sense``), arguments checked."""
    owner = "sense"
    _, n = check_model(model, owner)
    n_ch, _ = check_sensor_arrays(sensor, model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_vector(out, "out", owner, (n_ch,), writable=True)
    _sense(q, dq, model, sensor, out)


@compiled_as(sense)
def _sense_compiled(q, dq, model, sensor, out):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, sensor, out: _sense(q, dq, model, sensor, out)
