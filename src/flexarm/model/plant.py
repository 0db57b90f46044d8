"""What the simulator, the sensors and the controllers read of an arm: :class:`Plant`.

:class:`flexarm.FlexibleArm` is the plant flexarm builds; anything with these
attributes (an identified model, a user's own arm packed the same way) can be
simulated, sensed and controlled. The compiled parts read only
``Plant.arrays``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidTypeError
from .arrays import ArmArrays

__all__ = ["ModeShapes", "Plant", "check_plant"]

F64 = NDArray[np.float64]


class ModeShapes(Protocol):
    """One link's assumed modes (:class:`flexarm.model.beam.BeamModes`)."""

    @property
    def frequencies(self) -> F64:
        """Clamped natural frequencies, rad/s, shape (n_modes,)."""
        ...

    @property
    def tip_deflection(self) -> F64:
        """Mode shapes at the tip, shape (n_modes,)."""
        ...

    def shape(self, x: ArrayLike) -> F64:
        """Mode shapes at ``x`` (m along the link), shape (n_modes, len(x))."""
        ...


@runtime_checkable
class Plant(Protocol):
    """A planar arm as the simulator sees it (every length in m, angle in rad)."""

    @property
    def n_links(self) -> int: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def n_modes(self) -> tuple[int, ...]: ...
    @property
    def link_lengths(self) -> F64: ...
    @property
    def modes(self) -> Sequence[ModeShapes]: ...
    @property
    def link_frequencies(self) -> list[F64]: ...
    @property
    def arrays(self) -> ArmArrays: ...
    @property
    def has_flexible_joints(self) -> bool: ...
    @property
    def motor_slice(self) -> slice: ...
    @property
    def coordinate_names(self) -> list[str]: ...

    def tip_position(self, q: ArrayLike) -> F64:
        """End-effector position with deflection, shape (2,) or (m, 2)."""
        ...

    def inverse_kinematics(self, position: ArrayLike, elbow: str = ...) -> F64:
        """Joint angles of the rigid arm with its tip at ``position``."""
        ...

    def forward_dynamics(
        self, q: ArrayLike, dq: ArrayLike, tau: ArrayLike, *, backend: str = ...
    ) -> F64:
        """Accelerations ``qddot``, shape (n_dof,)."""
        ...


def check_plant(arm: object, owner: str) -> Plant:
    """``arm`` if it is a :class:`Plant` (a FlexibleArm, or alike); an
    InvalidTypeError naming ``owner`` otherwise (``simulate(arm="paper")`` gets a
    message, not an AttributeError)."""
    if not isinstance(arm, Plant):
        raise InvalidTypeError(
            f"The 'arm' parameter of {owner} must be a FlexibleArm (or another plant with "
            f"the attributes of flexarm.model.plant.Plant). Got {type(arm).__name__} instead."
        )
    return arm
