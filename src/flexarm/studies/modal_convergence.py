"""How many modes does your arm need? :func:`convergence_check`.

An assumed-mode model is only as good as its basis. This runs the same motion
on copies of an arm that keep more and more modes per link
(:meth:`flexarm.FlexibleArm.with_modes`) and compares each run's link tip
deflections (in each link's frame) and end-effector position with the richest
basis's, as python-control's ``input_output_response`` compares systems on the
same input. The recommendation is the fewest modes whose errors are within a
tolerance of the peak deflection — provided the two richest bases agree within
it too (otherwise the richest is not converged and no recommendation is made).

What it measured on the paper's two-link arm against Exudyn's geometrically
exact ANCF cables (``benchmarks/exudyn_study.py``, BENCHMARKS.md): with
clamped-mass modes and geometric stiffening, the link-1 tip deflection on the
default square is 10 % off its peak with one mode per link, 0.2 % with two
and 0.03 % with three; with the paper's clamped-free modes 120 %, 42 % and
28 % with one, three and five.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._io import JSONValue
from .._types import F64
from .._validation import check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import BOUNDARIES, FlexibleArm
from ..sim.open_loop import TorqueFunction, simulate_open_loop
from ..sim.prescribed import JointMotion, simulate_prescribed
from ..sim.results import SimulationError, SimulationResult

__all__ = ["ConvergenceCase", "ModalConvergence", "convergence_check"]

_OWNER = "convergence_check"


class ConvergenceCase(NamedTuple):
    """One basis against the richest.

    Attributes
    ----------
    n_modes : tuple of int
        Modes per link.
    deflection_error : (n_links,)
        Largest ``|tip deflection - richest's|`` over time, m.
    relative_deflection_error : (n_links,)
        The same over the richest's peak deflection.
    tip_error : float
        Largest ``|end effector - richest's|`` over time, m.
    relative_tip_error : float
        The same over the last link's peak deflection.
    n_dof : int
        Coordinates of the model.
    wall_time_s : float
        The run's wall time, s.
    diverged : bool
        Whether the run diverged (errors are then infinite).
    """

    n_modes: tuple[int, ...]
    deflection_error: F64
    relative_deflection_error: F64
    tip_error: float
    relative_tip_error: float
    n_dof: int
    wall_time_s: float
    diverged: bool


@dataclass(frozen=True)
class ModalConvergence:
    """What :func:`convergence_check` found.

    Attributes
    ----------
    cases : list of ConvergenceCase
        Every basis tried, fewest modes first; the last is the reference.
    tolerance : float
        Allowed error over the peak deflection.
    boundary : str
        The modes' boundary conditions.
    converged : bool
        Whether the two richest bases agree within ``tolerance``.
    recommended : tuple of int or None
        The fewest modes per link within ``tolerance`` (None if not converged).
    peak_deflection : ndarray, shape (n_links,)
        The richest run's peak tip deflection of each link, m.
    """

    cases: list[ConvergenceCase]
    tolerance: float
    boundary: str
    converged: bool
    recommended: tuple[int, ...] | None
    peak_deflection: F64

    def text(self) -> str:
        """A table and the recommendation, for a terminal."""
        lines = [
            f"modal convergence ({self.boundary} modes; errors against the richest basis, "
            f"over its peak deflection)",
            f"{'modes':>10} {'n_dof':>6} {'deflection error (each link)':>32} "
            f"{'tip error':>12} {'wall s':>8}",
        ]
        for c in self.cases:
            modes = "x".join(str(k) for k in c.n_modes)
            if c.diverged:
                lines.append(f"{modes:>10} {c.n_dof:>6} {'diverged':>32}")
                continue
            defl = ", ".join(f"{e:.2%}" for e in c.relative_deflection_error)
            lines.append(
                f"{modes:>10} {c.n_dof:>6} {defl:>32} {c.relative_tip_error:>12.2%} "
                f"{c.wall_time_s:>8.2f}"
            )
        if self.recommended is None:
            lines.append(
                f"not converged: the two richest bases differ by more than {self.tolerance:.1%} "
                "of the peak deflection; add modes"
            )
        else:
            lines.append(
                f"recommended: {'x'.join(str(k) for k in self.recommended)} modes per link "
                f"(within {self.tolerance:.1%} of the peak deflection)"
            )
        return "\n".join(lines)

    def to_dict(self) -> dict[str, JSONValue]:
        """JSON-able summary."""
        return {
            "boundary": self.boundary,
            "tolerance": self.tolerance,
            "converged": self.converged,
            "recommended": None if self.recommended is None else list(self.recommended),
            "peak_deflection_m": self.peak_deflection.tolist(),
            "cases": [
                {
                    "n_modes": list(c.n_modes),
                    "n_dof": c.n_dof,
                    "diverged": c.diverged,
                    "deflection_error_m": _finite_or_none(c.deflection_error),
                    "relative_deflection_error": _finite_or_none(c.relative_deflection_error),
                    "tip_error_m": _finite_or_none(np.array([c.tip_error]))[0],
                    "relative_tip_error": _finite_or_none(np.array([c.relative_tip_error]))[0],
                    "wall_time_s": c.wall_time_s,
                }
                for c in self.cases
            ],
        }


def _finite_or_none(a: F64) -> list[float | None]:
    return [float(x) if np.isfinite(x) else None for x in np.asarray(a, dtype=float)]


def convergence_check(
    arm: FlexibleArm,
    t: ArrayLike | None = None,
    *,
    torque: ArrayLike | TorqueFunction | None = None,
    motion: JointMotion | None = None,
    run: Callable[[FlexibleArm], SimulationResult] | None = None,
    n_modes: Sequence[int] = (1, 2, 3, 5),
    boundary: str | None = None,
    tolerance: float = 0.01,
    substeps: int = 4,
) -> ModalConvergence:
    """Run one motion on ``arm`` with more and more modes per link and compare.

    Parameters
    ----------
    arm : FlexibleArm
        Your arm; its links' ``n_modes`` are replaced by each entry of ``n_modes``
        (everything else kept, geometric stiffening included).
    t : array_like, shape (K,), optional
        Evenly spaced times, s, for ``torque`` or ``motion``.
    torque : array_like or callable, optional
        Joint torques as :func:`flexarm.simulate_open_loop` takes them.
    motion : callable, optional
        Prescribed joint motion as
        :func:`flexarm.sim.prescribed.simulate_prescribed` takes it.
    run : callable, optional
        Any run, ``run(arm) -> SimulationResult`` (e.g. a closed loop:
        ``lambda a: flexarm.simulate(a, controller, trajectory, duration=5)``),
        sampled on the same times for every basis. Give exactly one of
        ``torque``, ``motion`` and ``run``.
    n_modes : sequence of int
        Modes per link to try, increasing (>= 2 entries); the last is the reference.
    boundary : {"clamped-free", "clamped-mass"}, optional
        The modes' boundary conditions (default: the arm's).
    tolerance : float
        Allowed error over the peak deflection (> 0; default 1 %).
    substeps : int
        RK4 steps per interval of ``t`` (for ``torque`` and ``motion``).

    Returns
    -------
    ModalConvergence
        ``.recommended`` and ``.text()``.

    Examples
    --------
    >>> import numpy as np
    >>> import flexarm as fa
    >>> arm = fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335)] * 2)
    >>> t = np.linspace(0.0, 1.0, 201)
    >>> pulse = lambda s: [5.0 * np.sin(np.pi * s) ** 2, -2.0 * np.sin(np.pi * s) ** 2]
    >>> check = convergence_check(arm, t, torque=pulse)   # 1, 2, 3 and 5 modes per link
    >>> check.recommended
    (3, 3)
    >>> print(check.text())  # doctest: +SKIP
    """
    if not isinstance(arm, FlexibleArm):
        raise InvalidTypeError(
            f"The 'arm' parameter of {_OWNER} must be a FlexibleArm. "
            f"Got {type(arm).__name__} instead."
        )
    given = [
        name for name, v in (("torque", torque), ("motion", motion), ("run", run)) if v is not None
    ]
    if len(given) != 1:
        raise InvalidValueError(
            f"The 'torque', 'motion' and 'run' parameters of {_OWNER}: give exactly one. "
            f"Got {given or 'none'} instead."
        )
    if run is None and t is None:
        raise InvalidValueError(f"The 't' parameter of {_OWNER} is needed with {given[0]}.")
    counts = [int(k) for k in n_modes]
    if len(counts) < 2 or any(k < 0 for k in counts) or counts != sorted(set(counts)):
        raise InvalidValueError(
            f"The 'n_modes' parameter of {_OWNER} must hold at least two increasing counts "
            f">= 0. Got {list(n_modes)} instead."
        )
    boundary = arm.boundary if boundary is None else boundary
    if boundary not in BOUNDARIES:
        raise InvalidValueError(
            f"The 'boundary' parameter of {_OWNER} must be one of {BOUNDARIES}. "
            f"Got {boundary!r} instead."
        )
    tol = check_real(tolerance, "tolerance", _OWNER, positive=True)

    def simulate(a: FlexibleArm) -> SimulationResult:
        if run is not None:
            return run(a)
        assert t is not None
        if motion is not None:
            return simulate_prescribed(a, t, motion, substeps=substeps)
        assert torque is not None
        return simulate_open_loop(a, t, torque, substeps=substeps)

    results: list[tuple[FlexibleArm, SimulationResult | None, float]] = []
    for k in counts:
        variant = arm.with_modes(k, boundary=boundary)
        start = time.perf_counter()
        try:
            res: SimulationResult | None = simulate(variant)
        except SimulationError:
            res = None
        results.append((variant, res, time.perf_counter() - start))
    ref = results[-1][1]
    if ref is None:
        raise InvalidValueError(
            f"The run of {_OWNER} diverged with {counts[-1]} modes per link, the reference."
        )
    peak = np.abs(ref.link_deflections).max(axis=0)
    scale = np.where(peak > 0, peak, 1.0)
    cases = []
    for variant, res, wall in results:
        if res is None or res.t.shape != ref.t.shape:
            inf = np.full(arm.n_links, np.inf)
            cases.append(
                ConvergenceCase(
                    n_modes=variant.n_modes,
                    deflection_error=inf,
                    relative_deflection_error=inf,
                    tip_error=np.inf,
                    relative_tip_error=np.inf,
                    n_dof=variant.n_dof,
                    wall_time_s=wall,
                    diverged=True,
                )
            )
            continue
        err = np.abs(res.link_deflections - ref.link_deflections).max(axis=0)
        tip = float(np.linalg.norm(res.tip - ref.tip, axis=1).max())
        cases.append(
            ConvergenceCase(
                n_modes=variant.n_modes,
                deflection_error=err,
                relative_deflection_error=err / scale,
                tip_error=tip,
                relative_tip_error=tip / float(scale[-1]),
                n_dof=variant.n_dof,
                wall_time_s=wall,
                diverged=False,
            )
        )

    def within(c: ConvergenceCase) -> bool:
        return bool(np.all(c.relative_deflection_error <= tol) and c.relative_tip_error <= tol)

    converged = within(cases[-2])
    recommended = next((c.n_modes for c in cases if within(c)), None) if converged else None
    return ModalConvergence(
        cases=cases,
        tolerance=tol,
        boundary=boundary,
        converged=converged,
        recommended=recommended,
        peak_deflection=peak,
    )
