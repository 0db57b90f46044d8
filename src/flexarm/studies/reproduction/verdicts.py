"""The paper's claims and their verdicts: pure functions of the case results.

The rule is stated, not tuned. A run *tracks well* when it completes without
diverging and its RMS end-effector error is at most ``tolerance_m``
(:func:`tracks_well`).

Vocabulary. Each claim is judged on each sensor model separately, and is made of
one or more *parts*, each about a set of runs; a part holds when it holds for
**every** run it speaks of (a claim about every sensor holds only if it holds
for each sensor):

``"supported"``
    every part of the claim holds;
``"not supported"``
    no part holds;
``"partly supported"``
    some parts hold and others do not — possible only for a claim the paper
    states in parts (claim 1: collocated *and* noncollocated sensors).

The claims, with their parts:

1. *Nonadaptive control tracks poorly with collocated and noncollocated
   sensors*: (a) every nonadaptive run with the joint sensor does not track
   well; (b) every nonadaptive run with a noncollocated sensor does not.
2. *Fuzzy adaptive control tracks well regardless of sensor location*: every
   fuzzy run of the matrix tracks well.
3. *Fuzzy adaptation improves on the nonadaptive law*: with every sensor the
   fuzzy run's RMS error is strictly lower than the nonadaptive run's (a
   diverged run counts as an infinite error: two diverged runs are no
   improvement).
4. (With a ``ks`` study) *Some setting of the fuzzy law tracks well with every
   sensor*: one setting (``ks``, adaptation law) tracks well with every sensor.

Every verdict carries its evidence: the numbers of the runs behind it (errors in
mm to three significant figures, :mod:`~flexarm.studies.reproduction.units`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, TypedDict

from .cases import MODEL_LABELS, SENSOR_CASES, SENSOR_LABELS, CaseResult
from .units import mm, sig

__all__ = ["VERDICTS", "Claim", "Part", "claims", "describe", "judge", "tracks_well"]

VERDICTS = ("supported", "partly supported", "not supported")


class Claim(TypedDict):
    """One claim of the paper with the model's verdict and the numbers behind it."""

    claim: str
    sensor_model: str
    verdict: str
    evidence: str


class Part(NamedTuple):
    """One part of a claim: whether it holds, and why."""

    name: str
    holds: bool
    evidence: str


def tracks_well(result: CaseResult, tolerance_m: float) -> bool:
    """Whether a run completed and its RMS error is at most ``tolerance_m`` (m)."""
    return result.status == "ok" and result.rms <= tolerance_m


def judge(parts: Sequence[Part]) -> str:
    """The verdict on a claim made of ``parts`` (module docstring)."""
    held = sum(p.holds for p in parts)
    if held == len(parts):
        return "supported"
    return "not supported" if held == 0 else "partly supported"


def describe(result: CaseResult) -> str:
    """The sensor, the outcome (RMS error or divergence time) and the linearised poles."""
    pole = f"linearised poles up to Re {result.max_real_pole:+.3g} rad/s"
    sensor = SENSOR_LABELS[result.case.sensor]
    if result.status != "ok":
        return f"{sensor}: diverged at t = {sig(result.diverged_at_s)} s ({pole})"
    return f"{sensor}: RMS {mm(result.rms)} ({pole})"


def _all(name: str, runs: Sequence[CaseResult], test: bool) -> Part:
    return Part(name=name, holds=bool(runs) and test, evidence="; ".join(describe(c) for c in runs))


def _claim(text: str, model: str, parts: Sequence[Part], tail: str) -> Claim:
    if len(parts) == 1:
        evidence = parts[0].evidence
    else:
        evidence = " | ".join(
            f"{p.name} ({'holds' if p.holds else 'does not hold'}): {p.evidence}" for p in parts
        )
    return Claim(claim=text, sensor_model=model, verdict=judge(parts), evidence=evidence + tail)


def claims(
    cases: Sequence[CaseResult], ks_study: Sequence[CaseResult], tolerance_m: float
) -> list[Claim]:
    """The verdict on each claim under each sensor model of ``cases`` (module docstring).

    Parameters
    ----------
    cases : sequence of CaseResult
        The paper's matrix: nonadaptive (``"pd"``) and fuzzy runs, one per sensor
        and sensor model.
    ks_study : sequence of CaseResult
        The fuzzy law over ``ks`` and the adaptation laws; empty: no claim 4.
    tolerance_m : float
        "Tracks well" means RMS error <= ``tolerance_m``, m.

    Returns
    -------
    list of Claim
        Per sensor model (in the order the cases give them): three claims, four
        with a ``ks`` study.
    """
    models = list(dict.fromkeys(c.case.sensor_model for c in cases))
    out: list[Claim] = []
    for model in models:
        mine = [c for c in cases if c.case.sensor_model == model]
        study = [c for c in ks_study if c.case.sensor_model == model]
        out += _claims_of_model(model, mine, study, tolerance_m)
    return out


def _claims_of_model(
    model: str, cases: Sequence[CaseResult], ks_study: Sequence[CaseResult], tol: float
) -> list[Claim]:
    tail = f" (tracks well: completes with RMS <= {mm(tol)}; {MODEL_LABELS[model]})."
    pd = [c for c in cases if c.case.controller == "pd"]
    fz = [c for c in cases if c.case.controller == "fuzzy"]
    collocated = [c for c in pd if c.case.sensor == "joint"]
    distant = [c for c in pd if c.case.sensor != "joint"]
    out = [
        _claim(
            "Nonadaptive control tracks poorly with collocated and noncollocated sensors",
            model,
            [
                _all("collocated", collocated, not any(tracks_well(c, tol) for c in collocated)),
                _all("noncollocated", distant, not any(tracks_well(c, tol) for c in distant)),
            ],
            tail,
        ),
        _claim(
            "Fuzzy adaptive control tracks well regardless of sensor location",
            model,
            [_all("every sensor", fz, all(tracks_well(c, tol) for c in fz))],
            tail,
        ),
    ]
    pairs = [(a, b) for a in fz for b in pd if a.case.sensor == b.case.sensor]
    better = [a for a, b in pairs if a.rms < b.rms]
    out.append(
        _claim(
            "Fuzzy adaptation improves on the nonadaptive law",
            model,
            [
                Part(
                    name="every sensor",
                    holds=bool(pairs) and len(better) == len(pairs),
                    evidence="sensors where the adaptive RMS error is lower: "
                    + (", ".join(SENSOR_LABELS[a.case.sensor] for a in better) or "none")
                    + " (adaptive vs nonadaptive: "
                    + "; ".join(  # four figures: the pairs may differ in the third
                        f"{SENSOR_LABELS[a.case.sensor]}: {sig(1e3 * a.rms, 4)} vs "
                        f"{sig(1e3 * b.rms, 4)} mm"
                        for a, b in pairs
                    )
                    + ", inf = diverged)",
                )
            ],
            tail,
        )
    )
    if ks_study:
        settings = sorted({(c.case.law, c.case.ks) for c in ks_study})
        good = [
            s
            for s in settings
            if all(
                any(
                    tracks_well(c, tol)
                    for c in ks_study
                    if (c.case.law, c.case.ks) == s and c.case.sensor == sensor
                )
                for sensor in SENSOR_CASES
            )
        ]
        best = []
        for sensor in SENSOR_CASES:
            runs = [c for c in ks_study if c.case.sensor == sensor]
            b = min(runs, key=lambda c: c.rms)
            best.append(
                f"{SENSOR_LABELS[sensor]}: "
                + (
                    f"RMS {mm(b.rms)} at ks = {b.case.ks:g} ({b.case.law})"
                    if b.status == "ok"
                    else "every setting diverged"
                )
            )
        settings_text = ", ".join(f"ks = {k:g} ({law})" for law, k in good) or "none"
        out.append(
            _claim(
                "Some setting of the fuzzy law (any ks, either law) tracks well with every sensor",
                model,
                [
                    Part(
                        name="one setting for every sensor",
                        holds=bool(good),
                        evidence=f"settings that track well with every sensor: {settings_text}; "
                        "best per sensor: " + "; ".join(best),
                    )
                ],
                tail,
            )
        )
    return out
