"""The paper's claims and their verdicts: pure functions of the case results.

The rule is stated, not tuned. A run *tracks well* when it completes without
diverging and its RMS end-effector error is at most ``tolerance_m``
(:func:`tracks_well`). A claim about several runs (or sensors) is
``"supported"`` when it holds for all of them, ``"not supported"`` when it holds
for none, ``"partly supported"`` otherwise (:func:`verdict`). The claims:

1. *Nonadaptive control tracks poorly with collocated and noncollocated
   sensors*: holds for each nonadaptive run of the matrix that does not track
   well.
2. *Fuzzy adaptive control tracks well regardless of sensor location*: holds
   for each fuzzy run of the matrix that tracks well.
3. *Fuzzy adaptation improves on the nonadaptive law*: holds for each sensor
   where the fuzzy run's RMS error is strictly lower than the nonadaptive
   run's (a diverged run counts as an infinite error, so two diverged runs are
   no improvement); counted over the fuzzy runs.
4. (With a ``ks`` study) *Some setting of the fuzzy law tracks well with every
   sensor*: holds for each sensor where at least one run of the study tracks
   well.

Every verdict carries its evidence: the numbers of the runs behind it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypedDict

from .cases import SENSOR_CASES, SENSOR_LABELS, CaseResult

__all__ = ["VERDICTS", "Claim", "claims", "describe", "tracks_well", "verdict"]

VERDICTS = ("supported", "partly supported", "not supported")


class Claim(TypedDict):
    """One claim of the paper with the model's verdict and the numbers behind it."""

    claim: str
    verdict: str
    evidence: str


def tracks_well(result: CaseResult, tolerance_m: float) -> bool:
    """Whether a run completed and its RMS error is at most ``tolerance_m`` (m)."""
    return result.status == "ok" and result.rms <= tolerance_m


def verdict(hits: int, total: int) -> str:
    """``"supported"`` if ``hits == total``, ``"not supported"`` if none, else partly."""
    if hits == total:
        return "supported"
    return "not supported" if hits == 0 else "partly supported"


def describe(result: CaseResult) -> str:
    """The sensor, the outcome (RMS error or divergence time) and the linearised poles."""
    pole = f"linearised poles up to Re {result.max_real_pole:+.3g} rad/s"
    sensor = SENSOR_LABELS[result.case.sensor]
    if result.status != "ok":
        return f"{sensor}: diverged at t = {result.diverged_at_s:.3g} s ({pole})"
    return f"{sensor}: RMS {result.rms:.3g} m ({pole})"


def claims(
    cases: Sequence[CaseResult], ks_study: Sequence[CaseResult], tolerance_m: float
) -> list[Claim]:
    """The verdict on each claim (module docstring).

    Parameters
    ----------
    cases : sequence of CaseResult
        The paper's matrix: nonadaptive (``"pd"``) and fuzzy runs, one per sensor.
    ks_study : sequence of CaseResult
        The fuzzy law over ``ks`` and the adaptation laws; empty: no claim 4.
    tolerance_m : float
        "Tracks well" means RMS error <= ``tolerance_m``, m.

    Returns
    -------
    list of Claim
        Three claims, four with a ``ks`` study.
    """
    tail = f" (tracks well: completes with RMS <= {tolerance_m:.3g} m)."
    pd = [c for c in cases if c.case.controller == "pd"]
    fz = [c for c in cases if c.case.controller == "fuzzy"]
    poor = [c for c in pd if not tracks_well(c, tolerance_m)]
    out = [
        Claim(
            claim="Nonadaptive control tracks poorly with collocated and noncollocated sensors",
            verdict=verdict(len(poor), len(pd)),
            evidence="; ".join(describe(c) for c in pd) + tail,
        ),
        Claim(
            claim="Fuzzy adaptive control tracks well regardless of sensor location",
            verdict=verdict(sum(tracks_well(c, tolerance_m) for c in fz), len(fz)),
            evidence="; ".join(describe(c) for c in fz) + tail,
        ),
    ]
    pairs = [(a, b) for a in fz for b in pd if a.case.sensor == b.case.sensor]
    better = [a for a, b in pairs if a.rms < b.rms]
    out.append(
        Claim(
            claim="Fuzzy adaptation improves on the nonadaptive law",
            verdict=verdict(len(better), len(fz)),
            evidence="sensors where the adaptive RMS error is lower: "
            + (", ".join(SENSOR_LABELS[a.case.sensor] for a in better) or "none")
            + " (adaptive vs nonadaptive: "
            + "; ".join(
                f"{SENSOR_LABELS[a.case.sensor]}: {a.rms:.4g} vs {b.rms:.4g} m" for a, b in pairs
            )
            + ", inf = diverged).",
        )
    )
    if ks_study:
        best = []
        for sensor in SENSOR_CASES:
            runs = [c for c in ks_study if c.case.sensor == sensor]
            best.append(
                (
                    sensor,
                    min(runs, key=lambda c: c.rms),
                    any(tracks_well(c, tolerance_m) for c in runs),
                )
            )
        out.append(
            Claim(
                claim="Some setting of the fuzzy law (any ks, either law) tracks well "
                "with every sensor",
                verdict=verdict(sum(ok for _, _, ok in best), len(best)),
                evidence="best over the ks study: "
                + "; ".join(
                    f"{SENSOR_LABELS[s]}: "
                    + (
                        f"RMS {b.rms:.3g} m at ks = {b.case.ks:g} ({b.case.law})"
                        if b.status == "ok"
                        else "every setting diverged"
                    )
                    for s, b, _ in best
                )
                + ".",
            )
        )
    return out
