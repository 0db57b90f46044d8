"""The compiled integrator shared by the closed and the open loop.

Classical fourth-order Runge–Kutta on ``qdd = f(q, dq, tau)`` with the arm's
compiled dynamics (:mod:`flexarm.model.dynamics`), in place, allocating nothing:
:func:`rk4_step` for any arm, :func:`rk4_step_two_links_one_mode` for the
paper's structure (same operations, in registers). The torque may vary over a
step (start, middle and end values, for an input interpolated in time).
:func:`diverged` is the divergence test both loops apply after every step.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._compile import compiled_as
from ..errors import InvalidValueError
from ..model.arrays import ArmArrays, Workspace
from ..model.dynamics import is_two_links_one_mode
from ..model.kernel_checks import check_model, check_vector, check_workspace
from . import _rk4
from ._rk4 import DIVERGENCE_RATE

__all__ = ["DIVERGENCE_RATE", "diverged", "rk4_step", "rk4_step_two_links_one_mode"]

F64 = NDArray[np.float64]


# ------------------------------------------------------------------ checked public faces
# From Python each name checks its arguments first; inside compiled code (the
# loops) it is the kernel itself.
def _check_step(q: F64, dq: F64, taus: tuple[F64, F64, F64], model: ArmArrays, owner: str) -> int:
    n_links, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,), writable=True)
    check_vector(dq, "dq", owner, (n,), writable=True)
    for name, tau in zip(("tau0", "tau_mid", "tau1"), taus, strict=True):
        check_vector(tau, name, owner, (n_links,))
    return n


def rk4_step(
    q: F64,
    dq: F64,
    tau0: F64,
    tau_mid: F64,
    tau1: F64,
    h: float,
    model: ArmArrays,
    ws: Workspace,
    s: F64,
) -> None:
    """One classical RK4 step of ``qdd = f(q, dq, tau)`` in place, arguments checked.

    ``tau0``, ``tau_mid``, ``tau1`` (N m, shape (n_links,)) are the torques at the
    start, the middle and the end of the step (the same array three times for a
    torque held over the step); ``h`` the step, s; ``ws`` the dynamics' workspace;
    ``s`` (6, n_dof) scratch. Inside compiled code the same name is the kernel,
    unchecked.
    """
    owner = "rk4_step"
    n = _check_step(q, dq, (tau0, tau_mid, tau1), model, owner)
    check_workspace(ws, n, owner)
    check_vector(s, "s", owner, (6, n), writable=True)
    _rk4.rk4_step(q, dq, tau0, tau_mid, tau1, float(h), model, ws, s)


def rk4_step_two_links_one_mode(
    q: F64, dq: F64, tau0: F64, tau_mid: F64, tau1: F64, h: float, model: ArmArrays
) -> None:
    """:func:`rk4_step` for two links with one mode each and rigid joints (the paper's
    structure), in scalars: the same operations in the same order, the stage states
    and sums in registers. Arguments checked."""
    owner = "rk4_step_two_links_one_mode"
    n = _check_step(q, dq, (tau0, tau_mid, tau1), model, owner)
    if n != 4 or not is_two_links_one_mode(model):
        raise InvalidValueError(
            f"The 'model' parameter of {owner} must have two links with one mode each and "
            "rigid joints (without rotors or friction). Got another structure instead."
        )
    _rk4.rk4_step_two_links_one_mode(q, dq, tau0, tau_mid, tau1, float(h), model)


def diverged(q: F64, dq: F64, model: ArmArrays, max_deflection: F64) -> bool:
    """Whether the state is non-finite, a rate exceeds :data:`DIVERGENCE_RATE`, or a
    link's tip deflection exceeds ``max_deflection`` (m, shape (n_links,));
    arguments checked."""
    owner = "diverged"
    n_links, n = check_model(model, owner)
    check_vector(q, "q", owner, (n,))
    check_vector(dq, "dq", owner, (n,))
    check_vector(max_deflection, "max_deflection", owner, (n_links,))
    return bool(_rk4.diverged(q, dq, model, max_deflection))


@compiled_as(rk4_step)
def _rk4_step_compiled(q, dq, tau0, tau_mid, tau1, h, model, ws, s):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau0, tau_mid, tau1, h, model, ws, s: _rk4.rk4_step(
        q, dq, tau0, tau_mid, tau1, h, model, ws, s
    )


@compiled_as(rk4_step_two_links_one_mode)
def _rk4_step_two_links_compiled(q, dq, tau0, tau_mid, tau1, h, model):  # type: ignore[no-untyped-def]
    return lambda q, dq, tau0, tau_mid, tau1, h, model: _rk4.rk4_step_two_links_one_mode(
        q, dq, tau0, tau_mid, tau1, h, model
    )


@compiled_as(diverged)
def _diverged_compiled(q, dq, model, max_deflection):  # type: ignore[no-untyped-def]
    return lambda q, dq, model, max_deflection: _rk4.diverged(q, dq, model, max_deflection)
