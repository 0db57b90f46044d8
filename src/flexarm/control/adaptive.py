"""The fuzzy adaptive Jacobian-transpose law (the paper's Sec. V.D).

A Mamdani system (by default :func:`flexarm.fuzzy.paper_system`) reads the
links' tip deflections and its output ``lambda`` scales the paper's
operational-space PD law. The paper prints the adapted law as
``tau = K_s(lambda) J' [Kp e + Kd de]`` and says a gain ``K_s`` "adjusts the
membership functions' base widths"; the exact form is lost. Our reading, every
part of it a parameter:

* The FLS inputs are the tip deflections ``delta_i = sum_j phi_ij(L_i) eta_ij``
  of the links in m (from the modal coordinates in the measurement, see
  :mod:`flexarm.control.signals`), multiplied by ``ks``: the membership functions'
  bases are ``1/ks`` times as wide as printed. ``ks = 1`` is the paper's
  universe of +-5 m; ``ks = 0`` switches the adaptation off.
* The output sets the gain relative to its value at rest,
  ``g = lambda / lambda0`` with ``lambda0 = fls(0, ..., 0)`` (1/6 for the
  paper's system, where ``g`` then spans ``[1, 5]``), so the adapted law *is*
  the nonadaptive law while the links are straight, and the comparison of the
  two is a comparison of the adaptation alone.
* ``law="scaled"`` (default, the paper's printed form): the whole law is
  scaled, ``tau = g J' [Kp e + Kd de]``.
  ``law="damping"`` (alternative): only the damping is adapted,
  ``tau = J' [Kp e + g Kd de]`` — more damping while the links bend, the
  stiffness untouched.

The default is the paper's printed form because it is the only reading with
the text's support; :func:`flexarm.studies.reproduction.reproduce` reports both, over a
range of ``ks``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba as nb
import numpy as np
from numba.core.ccallback import CFunc
from numpy.typing import ArrayLike

from .._types import F64
from .._validation import check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..fuzzy import CompiledFuzzySystem, FuzzySystem, paper_system, workspace_size
from ..fuzzy._kernels import evaluate_into_kernel, unpack_system_kernel
from ..fuzzy.compiled import pack_system
from ..model.plant import Plant
from ..sensing.sensors import Sensor
from ._gains import gain_matrix
from .controllers import (
    Controller,
    JacobianTransposePD,
    jacobian_transpose_law,
    operational_lengths,
    wrap_control_function,
)
from .options import ADAPTATION_LAWS
from .signals import y_modes

__all__ = ["ADAPTATION_LAWS", "FuzzyAdaptiveJTPD", "tip_deflections"]


# params layout (all float64; integer arrays are stored bit for bit):
#   [0:4] Kp (row-major 2x2), [4:8] Kd, [8:8+N] link lengths,
#   then law, ks, lambda0, M (modal coordinates), the (N, M) tip-deflection
#   matrix, the FLS sizes (T, R, n_in, K) and its arrays in CompiledFuzzySystem order.
_HEAD = 4


@nb.njit(cache=True, nogil=True)
def _fuzzy_jt_pd(
    t: float, y: F64, r: F64, p: F64, s: F64, tau: F64
) -> None:  # pragma: no cover - compiled
    n = tau.shape[0]
    o = 8 + n
    law = p[o]
    ks = p[o + 1]
    lam0 = p[o + 2]
    m = int(p[o + 3])
    o += _HEAD
    system = unpack_system_kernel(p, o + n * m)
    # scratch: s[0] = last lambda, s[1] = last gain, s[2:2+n] = FLS inputs, then the workspace
    x = s[2 : 2 + n]
    modal = y[y_modes(n) :]
    for i in range(n):
        acc = 0.0
        for j in range(m):
            acc += p[o + i * m + j] * modal[j]
        x[i] = ks * acc
    lam = evaluate_into_kernel(system, x, s[2 + n :])
    g = lam / lam0
    s[0] = lam
    s[1] = g
    jacobian_transpose_law(y, r, p, g if law == 0.0 else 1.0, g, tau)


fuzzy_jt_pd_cfunc = wrap_control_function(_fuzzy_jt_pd, cache=True)


def tip_deflections(arm: Plant) -> F64:
    """The matrix mapping the modal coordinates to the links' tip deflections.

    Returns
    -------
    ndarray, shape (n_links, n_modes_total)
        Row ``i`` holds ``phi_ij(L_i)`` in the columns of link ``i``'s modes, so
        ``tip_deflections(arm) @ eta`` is each link's tip deflection in m
        (perpendicular to its clamped axis).
    """
    n_total = sum(arm.n_modes)
    out = np.zeros((arm.n_links, n_total))
    start = 0
    for i, modes in enumerate(arm.modes):
        k = len(modes.frequencies)
        out[i, start : start + k] = modes.tip_deflection
        start += k
    return out


@dataclass(frozen=True)
class FuzzyAdaptiveJTPD(Controller):
    """The paper's fuzzy adaptive Jacobian-transpose PD law (module docstring).

    Parameters
    ----------
    kp : float or array_like, shape (2,) or (2, 2)
        Stiffness of the nonadaptive law, N/m.
    kd : float or array_like, shape (2,) or (2, 2)
        Damping of the nonadaptive law, N s/m.
    ks : float
        Membership-width gain (>= 0): the FLS sees ``ks`` times the tip
        deflections in m. 1 is the paper's +-5 m universe; 0 turns the
        adaptation off (the law is then exactly :class:`JacobianTransposePD`).
    law : {"scaled", "damping"}
        Scale the whole law, or its damping only, by ``lambda / lambda0``.
    fls : FuzzySystem, optional
        One input per link, centroid defuzzifier, ``fls(0, ..., 0) > 0``;
        default :func:`flexarm.fuzzy.paper_system`.

    Notes
    -----
    The controller state records the last ``lambda`` (``state[0]``) and gain
    (``state[1]``); ``result.info["controller_state"]`` holds its final value.
    """

    kp: ArrayLike = 150.79
    kd: ArrayLike = 17.364
    ks: float = 1.0
    law: str = "scaled"
    fls: FuzzySystem | None = None
    name = "fuzzy"

    def __post_init__(self) -> None:
        owner = "FuzzyAdaptiveJTPD"
        object.__setattr__(self, "ks", check_real(self.ks, "ks", owner, nonnegative=True))
        check_option(self.law, "law", owner, ADAPTATION_LAWS)
        if self.fls is not None and not isinstance(self.fls, FuzzySystem):
            raise InvalidTypeError(
                f"The 'fls' parameter of {owner} must be a flexarm.fuzzy.FuzzySystem. "
                f"Got {type(self.fls).__name__} instead."
            )

    @classmethod
    def from_arm(
        cls, arm: Plant, zeta: float = 0.707, *, ks: float = 1.0, law: str = "scaled"
    ) -> FuzzyAdaptiveJTPD:
        """The paper's gains (as :meth:`JacobianTransposePD.from_arm`) with adaptation."""
        base = JacobianTransposePD.from_arm(arm, zeta)
        return cls(kp=base.kp, kd=base.kd, ks=ks, law=law)

    @property
    def system(self) -> FuzzySystem:
        """The fuzzy system in use."""
        return paper_system() if self.fls is None else self.fls

    @property
    def lambda0(self) -> float:
        """``lambda`` with straight links, ``fls(0, ..., 0)``."""
        fls = self.system
        return float(fls(*([0.0] * len(fls.inputs))))

    def gain(self, deflections: ArrayLike) -> F64:
        """The adapted gain ``lambda / lambda0`` for tip deflections in m.

        Parameters
        ----------
        deflections : array_like, shape (..., n_links)

        Returns
        -------
        ndarray, shape (...)
        """
        d = np.asarray(deflections, dtype=float) * self.ks
        return np.asarray(self.system(*np.moveaxis(d, -1, 0)), dtype=float) / self.lambda0

    @property
    def cfunc(self) -> CFunc:
        return fuzzy_jt_pd_cfunc

    def _checked_system(self, arm: Plant) -> CompiledFuzzySystem:
        owner = "FuzzyAdaptiveJTPD"
        fls = self.system
        if len(fls.inputs) != arm.n_links:
            raise InvalidValueError(
                f"The 'fls' parameter of {owner} must have one input per link "
                f"({arm.n_links}). Got {len(fls.inputs)} inputs instead."
            )
        lam0 = self.lambda0
        if not (np.isfinite(lam0) and lam0 > 0):
            raise InvalidValueError(
                f"The 'fls' parameter of {owner} must give a positive output with straight "
                f"links (the gain is lambda / lambda0). Got lambda0 = {lam0!r} instead."
            )
        return fls.compiled()

    def parameters(self, arm: Plant) -> F64:
        return self.parameters_for(arm, None)

    def parameters_for(self, arm: Plant, sensor: Sensor | None) -> F64:
        owner = "FuzzyAdaptiveJTPD"
        kp = gain_matrix(self.kp, "kp", owner)
        kd = gain_matrix(self.kd, "kd", owner)
        compiled = self._checked_system(arm)
        lengths = operational_lengths(arm, sensor)
        tips = tip_deflections(arm)
        head = [ADAPTATION_LAWS.index(self.law), self.ks, self.lambda0, tips.shape[1]]
        return np.concatenate(
            [
                kp.ravel(),
                kd.ravel(),
                lengths,
                np.array(head, float),
                tips.ravel(),
                pack_system(compiled),
            ]
        )

    def initial_state(self, arm: Plant) -> F64:
        compiled = self._checked_system(arm)
        state = np.zeros(2 + arm.n_links + int(workspace_size(compiled)))
        state[0] = self.lambda0
        state[1] = 1.0
        return state
