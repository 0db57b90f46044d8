"""Linear time-invariant models: :class:`StateSpace`.

``x' = A x + B u, y = C x + D u`` in continuous time, or
``x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k]`` with a sample period
``dt``. What flexarm's linear analysis returns (:func:`flexarm.control.linearize.linearize`)
and what its designs (:mod:`flexarm.control.design`) take: poles, transmission
zeros, zero-order-hold discretisation, closed loops with static or dynamic
linear controllers, and export to python-control (``control.ss``, named
signals) when that package is installed (``pip install flexarm[control]``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._types import F64
from .._validation import check_array, check_real
from ..errors import InvalidValueError
from ..sensing.delays import state_space_matrices

if TYPE_CHECKING:
    import control

__all__ = ["StateSpace"]

C128 = NDArray[np.complex128]
_OWNER = "StateSpace"


def _names(value: Sequence[str] | None, n: int, prefix: str, name: str) -> tuple[str, ...]:
    if value is None:
        return tuple(f"{prefix}{i}" for i in range(n))
    names = tuple(value)
    if len(names) != n or not all(isinstance(s, str) for s in names):
        raise InvalidValueError(
            f"The '{name}' parameter of {_OWNER} must hold {n} strings. Got {value!r} instead."
        )
    return names


class StateSpace:
    """A linear model ``(A, B, C, D)``, continuous (``dt`` None) or sampled.

    Parameters
    ----------
    A : array_like, shape (n, n)
    B : array_like, shape (n, m)
    C : array_like, shape (p, n)
    D : array_like, shape (p, m), optional
        Zero by default.
    dt : float, optional
        Sample period, s (None: continuous time).
    state_names, input_names, output_names : sequence of str, optional
        Signal names (default ``x0, ...``, ``u0, ...``, ``y0, ...``).

    The matrices are stored as read-only float arrays; a model is not changed
    after construction (every method returns a new one).

    Examples
    --------
    >>> sys = StateSpace([[0.0, 1.0], [0.0, 0.0]], [[0.0], [1.0]], [[1.0, 0.0]])
    >>> sys.poles().tolist()
    [0j, 0j]
    >>> sys.discretize(0.1).A.round(3).tolist()
    [[1.0, 0.1], [0.0, 1.0]]
    """

    A: F64
    B: F64
    C: F64
    D: F64
    dt: float | None
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def __init__(
        self,
        A: ArrayLike,
        B: ArrayLike,
        C: ArrayLike,
        D: ArrayLike | None = None,
        dt: float | None = None,
        state_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
    ) -> None:
        a, b, c, d = state_space_matrices(A, B, C, D, _OWNER)
        n, m, p = a.shape[0], b.shape[1], c.shape[0]
        for name, arr in (("A", a), ("B", b), ("C", c), ("D", d)):
            arr = np.array(arr, dtype=np.float64)
            arr.flags.writeable = False
            setattr(self, name, arr)
        self.dt = None if dt is None else check_real(dt, "dt", _OWNER, positive=True)
        self.state_names = _names(state_names, n, "x", "state_names")
        self.input_names = _names(input_names, m, "u", "input_names")
        self.output_names = _names(output_names, p, "y", "output_names")

    def __repr__(self) -> str:
        base = "continuous" if self.dt is None else f"dt = {self.dt:g} s"
        return (
            f"StateSpace({self.n_states} states, {self.n_inputs} inputs, {self.n_outputs} "
            f"outputs, {base})"
        )

    # ------------------------------------------------------------------ sizes
    @property
    def n_states(self) -> int:
        return int(self.A.shape[0])

    @property
    def n_inputs(self) -> int:
        return int(self.B.shape[1])

    @property
    def n_outputs(self) -> int:
        return int(self.C.shape[0])

    @property
    def is_continuous(self) -> bool:
        return self.dt is None

    # ------------------------------------------------------------------ analysis
    def poles(self) -> C128:
        """Eigenvalues of ``A`` (rad/s, or z for a sampled model), largest real part
        (or modulus) first."""
        lam = np.asarray(np.linalg.eigvals(self.A), dtype=np.complex128)
        key = -lam.real if self.dt is None else -np.abs(lam)
        return lam[np.lexsort((lam.imag, key))]

    def is_stable(self, margin: float = 0.0) -> bool:
        """Every pole has real part < ``-margin`` (continuous) or modulus
        < ``1 - margin`` (sampled)."""
        lam = self.poles()
        if self.dt is None:
            return bool(np.all(lam.real < -margin))
        return bool(np.all(np.abs(lam) < 1.0 - margin))

    def transmission_zeros(
        self, inputs: Sequence[int] | None = None, outputs: Sequence[int] | None = None
    ) -> C128:
        """Transmission zeros of the square subsystem from ``inputs`` to ``outputs``.

        The finite generalised eigenvalues of the Rosenbrock pencil
        ``[[A, B], [C, D]] - s [[I, 0], [0, 0]]``. Without ``inputs`` and
        ``outputs`` the system itself must be square.

        Parameters
        ----------
        inputs, outputs : sequence of int, optional
            Indices of the inputs and outputs kept (as many of each).

        Returns
        -------
        ndarray of complex
            Sorted by real part, largest first.
        """
        import scipy.linalg

        ins = list(range(self.n_inputs)) if inputs is None else [int(i) for i in inputs]
        outs = list(range(self.n_outputs)) if outputs is None else [int(i) for i in outputs]
        if len(ins) != len(outs):
            raise InvalidValueError(
                f"The 'outputs' parameter of {_OWNER}.transmission_zeros must select as many "
                f"outputs as inputs ({len(ins)}). Got {len(outs)} instead."
            )
        for name, idx, size in (("inputs", ins, self.n_inputs), ("outputs", outs, self.n_outputs)):
            if any(not 0 <= i < size for i in idx):
                raise InvalidValueError(
                    f"The '{name}' parameter of {_OWNER}.transmission_zeros must index "
                    f"0..{size - 1}. Got {idx} instead."
                )
        n, k = self.n_states, len(ins)
        b, c, d = self.B[:, ins], self.C[outs, :], self.D[np.ix_(outs, ins)]
        pencil = np.block([[self.A, b], [c, d]])
        e = np.zeros((n + k, n + k))
        e[:n, :n] = np.eye(n)
        z = scipy.linalg.eigvals(pencil, e)
        z = z[np.isfinite(z) & (np.abs(z) < 1e12)]
        return np.asarray(z[np.argsort(-z.real, kind="stable")], dtype=np.complex128)

    # ------------------------------------------------------------------ transforms
    def discretize(self, dt: float) -> StateSpace:
        """Exact zero-order-hold discretisation at the period ``dt`` (s)."""
        from ..sensing.delays import discretize

        if self.dt is not None:
            raise InvalidValueError(
                f"{_OWNER}.discretize needs a continuous model. Got one sampled at "
                f"{self.dt} s instead."
            )
        ad, bd, cd, dd = discretize(self.A, self.B, self.C, self.D, dt)
        return StateSpace(ad, bd, cd, dd, dt, self.state_names, self.input_names, self.output_names)

    def feedback(self, controller: StateSpace | ArrayLike) -> StateSpace:
        """The closed loop with ``u = -K y`` (a static gain ``K``, shape (m, p)) or with a
        linear controller (a :class:`StateSpace` from ``y`` to ``u``, same time
        base), negative feedback; its output is ``y``.

        Returns
        -------
        StateSpace
            States: the plant's, then the controller's.
        """
        if isinstance(controller, StateSpace):
            ctrl = controller
            if ctrl.dt != self.dt:
                raise InvalidValueError(
                    f"The 'controller' parameter of {_OWNER}.feedback must have the plant's "
                    f"time base (dt = {self.dt}). Got dt = {ctrl.dt} instead."
                )
        else:
            k = check_array(controller, "controller", f"{_OWNER}.feedback")
            if k.shape != (self.n_inputs, self.n_outputs):
                raise InvalidValueError(
                    f"The 'controller' parameter of {_OWNER}.feedback must be of shape "
                    f"({self.n_inputs}, {self.n_outputs}). Got shape {k.shape} instead."
                )
            ctrl = StateSpace(
                np.zeros((0, 0)),
                np.zeros((0, self.n_outputs)),
                np.zeros((self.n_inputs, 0)),
                k,
                self.dt,
            )
        if ctrl.n_inputs != self.n_outputs or ctrl.n_outputs != self.n_inputs:
            raise InvalidValueError(
                f"The 'controller' parameter of {_OWNER}.feedback must map the plant's "
                f"{self.n_outputs} outputs to its {self.n_inputs} inputs. Got "
                f"{ctrl.n_inputs} inputs and {ctrl.n_outputs} outputs instead."
            )
        # u = -(Cc xc + Dc y), y = C x + D u  =>  (I + D Dc) y = C x - D Cc xc
        eye_p = np.eye(self.n_outputs)
        solve = np.linalg.solve(eye_p + self.D @ ctrl.D, np.hstack([self.C, -self.D @ ctrl.C]))
        cy = solve  # y = cy @ [x; xc]
        cu = -(
            ctrl.C @ np.hstack([np.zeros((ctrl.n_states, self.n_states)), np.eye(ctrl.n_states)])
            + ctrl.D @ cy
        )
        a = np.zeros((self.n_states + ctrl.n_states,) * 2)
        a[: self.n_states, : self.n_states] = self.A
        a[self.n_states :, self.n_states :] = ctrl.A
        a[: self.n_states] += self.B @ cu
        a[self.n_states :] += ctrl.B @ cy
        names = [*self.state_names, *(f"controller.{s}" for s in ctrl.state_names)]
        return StateSpace(
            a, np.zeros((a.shape[0], 0)), cy, None, self.dt, names, [], self.output_names
        )

    # ------------------------------------------------------------------ export
    def to_control(self, name: str | None = None) -> control.StateSpace:
        """This model as ``control.ss`` with its signal names (python-control must be
        installed: ``pip install flexarm[control]``)."""
        try:
            import control
        except ImportError as exc:  # pragma: no cover - depends on the environment
            raise ImportError(
                "StateSpace.to_control needs python-control: pip install 'flexarm[control]'"
            ) from exc
        kwargs = {"name": name} if name is not None else {}
        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            self.dt if self.dt is not None else 0,
            states=list(self.state_names),
            inputs=list(self.input_names),
            outputs=list(self.output_names),
            **kwargs,
        )
