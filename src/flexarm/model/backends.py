"""Where a public call of :class:`flexarm.FlexibleArm` is evaluated: :class:`Backends`.

:meth:`~Backends.forward_dynamics`, :meth:`~Backends.mass_matrix`,
:meth:`~Backends.point_position` and :meth:`~Backends.tip_position` take a
``backend``:

``"compiled"``
    The Numba kernels (:mod:`flexarm.model.dynamics`) through the arm's packed
    form (:mod:`flexarm.model.packed`, built on first use): about a microsecond
    a call from Python for the paper's arm, a batch of states (2-D arrays) in
    one compiled call, the kernels' results bit for bit. Real input only.
``"numpy"``
    The readable NumPy reference of :mod:`flexarm.model.arm`; it also takes
    complex input (the complex-step derivatives of ``M``).
``"auto"`` (the default)
    ``"compiled"`` for real input, ``"numpy"`` for complex input.

C-contiguous, writable float64 arrays go straight to the compiled entry point,
which checks their shapes and finiteness; anything else (lists, other dtypes,
strided or read-only views) is checked and converted first
(:func:`flexarm.model.kernel_checks.checked_state`). NumPy only: Numba is
loaded by the first compiled call.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_option
from ..errors import InvalidTypeError, InvalidValueError
from .arrays import LEN, ArmArrays
from .beam import BeamModes
from .kernel_checks import checked_coordinates, checked_state, shape_message
from .kinematics import point_position_reference

if TYPE_CHECKING:  # Numba is loaded on first use of the packed arm
    from .packed import PackedArm

__all__ = ["BACKENDS", "Backends"]

BACKENDS = ("auto", "compiled", "numpy")

_OWNER = "FlexibleArm"
_FLOAT64 = np.dtype(np.float64)
_empty = np.empty  # a global lookup less than np.empty in the calls' fast paths


class Backends:
    """The public calls of :class:`flexarm.FlexibleArm` that have a compiled and a
    NumPy backend (module docstring); a base of the arm, which supplies the
    sizes, the packed arrays and the NumPy references."""

    _derived: dict[str, Any]

    @property
    def n_dof(self) -> int:
        raise NotImplementedError

    @property
    def n_links(self) -> int:
        raise NotImplementedError

    @property
    def arrays(self) -> ArmArrays:
        raise NotImplementedError

    @property
    def modes(self) -> tuple[BeamModes, ...]:
        raise NotImplementedError

    def point_basis(self, link: int, distance: float) -> NDArray[np.float64]:
        raise NotImplementedError

    def _check_point(self, link: int, distance: float) -> tuple[int, float]:
        raise NotImplementedError

    def _mass_matrix_numpy(self, q: NDArray[Any]) -> NDArray[Any]:
        raise NotImplementedError

    def _forward_dynamics_numpy(
        self, q: NDArray[Any], dq: NDArray[Any], tau: NDArray[Any]
    ) -> NDArray[Any]:
        raise NotImplementedError

    def _packed(self) -> PackedArm:
        """The arm packed for cheap compiled calls from Python
        (:mod:`flexarm.model.packed`), built on first use (which loads Numba)."""
        packed: PackedArm | None = self._derived.get("packed")
        if packed is None:
            from .packed import PackedArm

            last = self.n_links - 1
            length = float(self.arrays.link[last, LEN])
            tip = self.point_basis(last, length)
            packed = self._derived["packed"] = PackedArm.from_arrays(self.arrays, tip)
        return packed

    def mass_matrix(self, q: ArrayLike, *, backend: str = "auto") -> NDArray[Any]:
        """Mass matrix ``M(q)``, symmetric positive definite.

        Parameters
        ----------
        q : array_like, shape (n_dof,) or (m, n_dof)
            Coordinates (joint angles in rad, then modal coordinates); a 2-D
            array is a batch of ``m`` configurations.
        backend : {"auto", "compiled", "numpy"}
            As for :meth:`forward_dynamics`: ``"auto"`` (default) takes the
            compiled kernel (:func:`flexarm.model.dynamics.mass_and_bias`) for
            real ``q`` and the NumPy reference for complex ``q`` (complex-step
            derivatives).

        Returns
        -------
        ndarray, shape (n_dof, n_dof) or (m, n_dof, n_dof)
            kg m**2 for the joint angles; modal units for the modes.
        """
        if backend == "auto" or backend == "compiled":
            try:
                packed: PackedArm = self._derived["packed"]
            except KeyError:
                packed = self._packed()
            out = packed.mass_matrix(q)
            if out is not None:
                return out
        check_option(backend, "backend", _OWNER, BACKENDS)
        q = checked_coordinates(q, self.n_dof, real=backend == "compiled")
        if backend == "numpy" or q.dtype.kind == "c":
            return _rows(self._mass_matrix_numpy, q)
        return self._packed().mass_matrix(q)  # type: ignore[return-value]

    def forward_dynamics(
        self,
        q: ArrayLike,
        dq: ArrayLike,
        tau: ArrayLike,
        *,
        backend: str = "auto",
        out: NDArray[Any] | None = None,
    ) -> NDArray[Any]:
        """Accelerations ``qddot = M^-1 (Q(q, dq, tau) - C dq)`` with ``Q`` from
        :meth:`generalized_forces`.

        Parameters
        ----------
        q, dq : array_like, shape (n_dof,) or (m, n_dof)
            Coordinates and rates (rad, rad/s; modal units); 2-D arrays are a
            batch of ``m`` states, evaluated in one compiled call.
        tau : array_like, shape (n_links,) or (m, n_links)
            Joint (motor) torques, N m.
        backend : {"auto", "compiled", "numpy"}
            ``"compiled"`` calls the Numba kernel
            :func:`flexarm.model.dynamics.forward_dynamics` (compiled on first
            use, cached on disk) through the arm's packed form
            (:mod:`flexarm.model.packed`): well under a microsecond from Python
            for the paper's arm, equal to the kernel bit for bit; real input only.
            ``"numpy"`` is the readable reference. ``"auto"`` (default) is
            ``"compiled"`` for real input and ``"numpy"`` for complex input
            (complex-step differentiation).
        out : ndarray, shape (n_dof,) or (m, n_dof), optional
            Where to write the result (rad/s**2; modal units per s**2), which is
            then returned: a writable array the result can be cast to safely. It
            may be one of ``q, dq`` (the state is read before it is written). A
            float64, C-contiguous ``out`` for one state saves the allocation of
            a new array each call.

        Returns
        -------
        ndarray, shape (n_dof,) or (m, n_dof)
            rad/s**2; modal units per s**2. ``out`` if given.

        Notes
        -----
        C-contiguous float64 arrays go straight to the kernel; anything else
        (lists, other dtypes, strided views) is checked and converted first.
        """
        if backend == "auto" or backend == "compiled":
            try:
                packed: PackedArm = self._derived["packed"]
            except KeyError:
                packed = self._packed()
            entry = packed.one_state  # None for an arm too large for the stack
            try:  # one state, float64 vectors: PackedArm.forward_dynamics's first case, inline
                if (
                    out is None
                    and q.dtype is _FLOAT64  # type: ignore[union-attr]
                    and dq.dtype is _FLOAT64  # type: ignore[union-attr]
                    and tau.dtype is _FLOAT64  # type: ignore[union-attr]
                    and q.ndim == 1  # type: ignore[union-attr]
                    and dq.ndim == 1  # type: ignore[union-attr]
                    and tau.ndim == 1  # type: ignore[union-attr]
                    and entry is not None
                ):
                    fresh = _empty(packed.n_dof)
                    if not entry(packed.buf, q, dq, tau, fresh):
                        return fresh
            except (AttributeError, TypeError):  # not arrays: checked below
                pass
            done = packed.forward_dynamics(q, dq, tau, out)
            if done is not None:
                return done
        check_option(backend, "backend", _OWNER, BACKENDS)
        n, real = self.n_dof, backend == "compiled"
        q, dq, tau = checked_state(q, dq, tau, n, self.n_links, real=real)
        if backend == "numpy" or "c" in (q.dtype.kind, dq.dtype.kind, tau.dtype.kind):
            result = _rows(self._forward_dynamics_numpy, q, dq, tau)
        else:
            result = self._packed().forward_dynamics(q, dq, tau)  # type: ignore[assignment]
        return result if out is None else _into(out, result)

    def point_position(
        self, q: ArrayLike, link: int, distance: float, *, backend: str = "auto"
    ) -> NDArray[np.float64]:
        """Position of the point ``distance`` m along link ``link``, deflection included.

        Parameters
        ----------
        q : array_like, shape (n_dof,) or (m, n_dof)
            One configuration or a time series of them.
        link : int
            0-based link index.
        distance : float
            Distance from the link's joint along the undeformed link, m, in
            ``[0, L]``.
        backend : {"auto", "compiled", "numpy"}
            ``"compiled"`` (real ``q``; what ``"auto"`` takes for it) evaluates
            :func:`flexarm.model.dynamics.point_kinematics` through the packed
            arm, the point's mode shapes kept for the next call; ``"numpy"``
            is the reference.

        Returns
        -------
        ndarray, shape (2,) or (m, 2)
            ``(x, y)`` in m, base frame.
        """
        if backend == "auto" or backend == "compiled":
            try:
                packed: PackedArm = self._derived["packed"]
            except KeyError:
                packed = self._packed()
            phi = packed.bases.get((link, distance))
            if phi is not None and type(link) is int:
                out = packed.point_position(q, link, distance, phi)
                if out is not None:
                    return out
        check_option(backend, "backend", _OWNER, BACKENDS)
        link, distance = self._check_point(link, distance)
        q = checked_coordinates(q, self.n_dof, real=backend == "compiled")
        if backend == "numpy" or q.dtype.kind == "c":
            return point_position_reference(self.modes[link], self.arrays, q, link, distance)
        packed = self._packed()
        phi = packed.bases.get((link, distance))
        if phi is None:
            phi = self.point_basis(link, distance)
            packed.remember_basis(link, distance, phi)
        return packed.point_position(q, link, distance, phi)  # type: ignore[return-value]

    def tip_position(self, q: ArrayLike, *, backend: str = "auto") -> NDArray[np.float64]:
        """End-effector position with deflection, shape ``(2,)`` or ``(m, 2)``, m
        (:meth:`point_position` of the last link's tip; ``q`` of shape
        ``(n_dof,)`` or ``(m, n_dof)``)."""
        if backend == "auto" or backend == "compiled":
            try:
                packed: PackedArm = self._derived["packed"]
            except KeyError:
                packed = self._packed()
            tip = packed.tip
            if tip is not None:
                out = packed.point_position(q, packed.n_links - 1, packed.tip_distance, tip)
                if out is not None:
                    return out
        last = self.n_links - 1
        return self.point_position(q, last, float(self.arrays.link[last, LEN]), backend=backend)


def _into(out: object, result: NDArray[Any], name: str = "out") -> NDArray[Any]:
    """``result`` written into ``out`` (checked: an ndarray of ``result``'s shape, writable,
    of a dtype ``result`` casts to safely), which is returned."""
    if not isinstance(out, np.ndarray):
        raise InvalidTypeError(
            f"The '{name}' parameter of {_OWNER} must be a NumPy array. "
            f"Got {type(out).__name__} instead."
        )
    if out.shape != result.shape:
        raise InvalidValueError(shape_message(name, _OWNER, str(result.shape), out.shape))
    if not out.flags.writeable:
        raise InvalidValueError(
            f"The '{name}' parameter of {_OWNER} must be writable. Got a read-only array instead."
        )
    if not np.can_cast(result.dtype, out.dtype, "safe"):
        raise InvalidTypeError(
            f"The '{name}' parameter of {_OWNER} must have a dtype that {result.dtype} casts to "
            f"safely. Got {out.dtype} instead."
        )
    out[...] = result
    return out


def _rows(fn: Callable[..., NDArray[Any]], *arrays: NDArray[Any]) -> NDArray[Any]:
    """``fn`` of one state, or of every row of a batch stacked (the NumPy reference
    takes one state at a time)."""
    if arrays[0].ndim == 1:
        return fn(*arrays)
    return np.stack([fn(*row) for row in zip(*arrays, strict=True)])
