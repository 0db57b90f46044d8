"""python-control interop: the nonlinear arm as a ``control.NonlinearIOSystem``.

:func:`to_nlsys` gives the plant ``x' = f(x, u)``, ``x = (q, dq)``, ``u`` the joint
torques (N m), as python-control's ``nlsys`` with named signals, its update
function calling the compiled dynamics (:func:`flexarm.model.dynamics.forward_dynamics`)
through the arm's packed form (:mod:`flexarm.model.packed`: about a microsecond a
call, a workspace of its own per call). It simulates with
``control.input_output_response`` and linearises with ``control.linearize``;
the linearised arm at rest is also :func:`flexarm.control.linearize.linearize`
(``.to_control()`` gives it as ``control.ss`` with the same signal names), so the
two can be held against each other.

python-control is imported on demand (``pip install "flexarm[control]"``).

Examples
--------
>>> import numpy as np, control
>>> import flexarm as fa
>>> sys = to_nlsys(fa.FlexibleArm.paper(), output="tip")
>>> sys.input_labels, sys.output_labels
(['tau1', 'tau2'], ['x_tip', 'y_tip'])
>>> t = np.linspace(0.0, 0.1, 11)
>>> resp = control.input_output_response(sys, t, np.ones((2, 11)))
>>> resp.outputs.shape
(2, 11)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._types import F64
from .._validation import check_option
from ..errors import InvalidTypeError
from ..model.plant import Plant, check_plant

if TYPE_CHECKING:
    import control

__all__ = ["NLSYS_OUTPUTS", "signal_names", "to_nlsys"]

_OWNER = "to_nlsys"

NLSYS_OUTPUTS = ("state", "joints", "tip")
"""Outputs of :func:`to_nlsys`: the whole state, the link-side joint angles, or the
deflected end effector."""


def signal_names(arm: Plant, output: str = "state") -> tuple[list[str], list[str], list[str]]:
    """``(states, inputs, outputs)`` names, as :func:`flexarm.control.linearize.linearize`
    gives them: the coordinates then their rates prefixed ``d``; ``tau1..tauN``;
    the state's names, ``theta1..thetaN`` or ``x_tip, y_tip``."""
    check_option(output, "output", _OWNER, NLSYS_OUTPUTS)
    coords = list(arm.coordinate_names)
    states = [*coords, *(f"d{c}" for c in coords)]
    inputs = [f"tau{i + 1}" for i in range(arm.n_links)]
    if output == "state":
        outputs = list(states)
    elif output == "joints":
        outputs = [f"theta{i + 1}" for i in range(arm.n_links)]
    else:
        outputs = ["x_tip", "y_tip"]
    return states, inputs, outputs


def to_nlsys(
    arm: Plant, *, output: str = "state", name: str = "flexarm"
) -> control.NonlinearIOSystem:
    """The arm as a python-control nonlinear input/output system.

    Parameters
    ----------
    arm : FlexibleArm
        The plant (any :class:`flexarm.model.plant.Plant`).
    output : {"state", "joints", "tip"}
        ``y = x``; the link-side joint angles (rad); or the deflected end
        effector's position (m).
    name : str
        The system's name in python-control.

    Returns
    -------
    control.NonlinearIOSystem
        States ``(q, dq)`` (shape (2 n_dof,), rad, modal units and their
        rates), inputs the joint torques (N m, shape (n_links,)), continuous
        time. The update function evaluates the compiled dynamics through the
        packed arm (:class:`flexarm.model.packed.PackedArm`, built once here);
        it returns a new array each call (the integrator keeps them) and keeps
        no state between calls, so one system may run in several threads.
    """
    try:
        import control
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError("to_nlsys needs python-control: pip install 'flexarm[control]'") from exc
    from ..model.packed import PackedArm

    arm = check_plant(arm, _OWNER)
    if not isinstance(name, str):
        raise InvalidTypeError(
            f"The 'name' parameter of {_OWNER} must be a str. Got {type(name).__name__} instead."
        )
    states, inputs, outputs = signal_names(arm, output)
    n, n_links = arm.n_dof, arm.n_links
    packed = PackedArm.from_arrays(arm.arrays)

    def update(t: float, x: ArrayLike, u: ArrayLike, params: object = None) -> F64:
        xs = np.array(x, dtype=np.float64)  # a C-contiguous, writable copy
        tau = np.empty(n_links)
        tau[:] = np.ravel(u)
        ddq = packed.forward_dynamics(xs[:n], xs[n:], tau)
        assert ddq is not None  # float64 C-contiguous arrays always take the compiled call
        return np.concatenate((xs[n:], ddq))

    def out(t: float, x: ArrayLike, u: ArrayLike, params: object = None) -> F64:
        xs = np.asarray(x, dtype=np.float64)
        if output == "state":
            return xs.copy()
        if output == "joints":
            return xs[:n_links].copy()
        return np.asarray(arm.tip_position(xs[:n]), dtype=np.float64)

    return control.nlsys(
        update, out, states=states, inputs=inputs, outputs=outputs, name=name, dt=0
    )
