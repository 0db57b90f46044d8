"""The paper's matrix again, on a converged arm: do the verdicts survive the model?

:meth:`flexarm.FlexibleArm.paper` is the paper's model, one clamped-free mode
per link without geometric stiffening, and its link-1 deflection on the square
is off by 1.2 times its peak against a geometrically exact reference
(:mod:`flexarm.model.validity`). This part of the study reruns the paper's
matrix (both sensor models, both laws, the three sensors) on the converged arm,
three clamped-mass modes per link with geometric stiffening
(:data:`CONVERGED_ARM`), and judges the paper's claims there with the same rule
(:func:`flexarm.studies.reproduction.verdicts.claims`).

The converged arm's collocated loop is stiffer than the paper's model: under
the paper's gains its fastest closed-loop pole at the square's corners is about
-13,800 to -26,800 rad/s. Its control period is chosen by a stated rule, half
the zero-order-hold bound ``2 / |pole|`` at the worst corner, rounded down to
1, 2 or 5 times a power of ten (:func:`converged_period`), and never longer
than the study's own period.
"""

from __future__ import annotations

import html
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..._io import JSONValue
from .cases import CONVERGED_ARM_TABLE, MODEL_LABELS, CaseResult
from .verdicts import Claim

__all__ = ["CONVERGED_ARM", "Converged", "converged_period", "verdict_changes"]

CONVERGED_ARM = CONVERGED_ARM_TABLE
"""The converged arm in the scenario schema (:data:`~.cases.CONVERGED_ARM_TABLE`)."""


def converged_period(dt: float) -> float:
    """The converged arm's control period: half the zero-order-hold bound of its
    collocated loop under the paper's gains at the square's worst corner, rounded
    down to 1, 2 or 5 times a power of ten, and at most ``dt`` (s)."""
    from ...control.controllers import JacobianTransposePD
    from ...control.linearize import closed_loop_poles
    from ...control.trajectories import Square
    from ...model.arm import FlexibleArm

    arm = FlexibleArm.paper(n_modes=3, boundary="clamped-mass", geometric_stiffening=True)
    law = JacobianTransposePD.from_arm(arm)
    fastest = max(
        float(np.max(np.abs(closed_loop_poles(arm, law, corner)))) for corner in Square().corners
    )
    bound = 0.5 * 2.0 / fastest
    decade = 10.0 ** math.floor(math.log10(bound))
    step = max(m * decade for m in (1.0, 2.0, 5.0) if m * decade <= bound)
    return min(dt, step)


def verdict_changes(paper: Sequence[Claim], converged: Sequence[Claim]) -> list[str]:
    """One sentence per claim and sensor model whose verdict differs between the
    paper's model and the converged arm."""
    before = {(c["claim"], c["sensor_model"]): c["verdict"] for c in paper}
    out = []
    for c in converged:
        old = before.get((c["claim"], c["sensor_model"]))
        if old is not None and old != c["verdict"]:
            out.append(
                f"{c['claim']} [{c['sensor_model']} sensor model]: {old} on the paper's model, "
                f"{c['verdict']} on the converged arm"
            )
    return out


@dataclass
class Converged:
    """The matrix on the converged arm: its runs, its verdicts, and what changed.

    Attributes
    ----------
    dt_s : float
        The converged arm's control period, s (:func:`converged_period`).
    cases : list of CaseResult
        The matrix's runs on the converged arm, in the matrix's order.
    claims : list of Claim
        The paper's claims judged on them.
    changes : list of str
        The verdicts that differ from the paper's model's (:func:`verdict_changes`).
    """

    dt_s: float
    cases: list[CaseResult]
    claims: list[Claim]
    changes: list[str]

    def summary(self) -> dict[str, JSONValue]:
        """JSON-ready: the arm, its period, its runs, its verdicts and what changed."""
        claims: list[JSONValue] = [
            {k: c[k] for k in ("claim", "sensor_model", "verdict", "evidence")} for c in self.claims
        ]
        return {
            "arm": dict(CONVERGED_ARM),
            "dt_s": self.dt_s,
            "cases": [dict(c.row()) for c in self.cases],
            "claims": claims,
            "changes": list(self.changes),
        }

    def text_lines(self) -> list[str]:
        """The verdicts on the converged arm, for the console summary."""
        lines = [
            f"on a converged arm (3 clamped-mass modes per link, geometric stiffening, "
            f"control period {self.dt_s:g} s):"
        ]
        for c in self.claims:
            lines.append(
                f"  - [{c['sensor_model']} sensor model] {c['claim']}: {c['verdict'].upper()}"
            )
            lines.append(f"      {c['evidence']}")
        lines.append(
            "  verdicts that change: " + ("; ".join(self.changes) if self.changes else "none")
        )
        return lines

    def html(self) -> str:
        """The report's section: the runs and the verdicts on the converged arm (tables
        in their own scroll boxes)."""
        from .html import case_table, table

        rows = [
            [
                c["claim"],
                MODEL_LABELS.get(c["sensor_model"], c["sensor_model"]),
                c["verdict"],
                c["evidence"],
            ]
            for c in self.claims
        ]
        changed = "; ".join(self.changes) if self.changes else "none"
        return "\n".join(
            [
                "<h2>On a converged arm</h2>",
                "<p>The paper's matrix rerun on the paper's links with three clamped-mass "
                f"modes per link and geometric stiffening (control period {self.dt_s:g} s), "
                "judged by the same rule.</p>",
                case_table(self.cases),
                table(
                    ("claim", "sensor model", "verdict", "evidence"),
                    rows,
                    numeric=(False, False, False, False),
                    wrap=(True, False, False, True),
                ),
                f"<p>Verdicts that change: {html.escape(changed)}.</p>",
            ]
        )
