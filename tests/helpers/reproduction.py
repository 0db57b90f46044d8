"""What the reproduction's tests share: rows of the study beyond the paper, made by hand."""

from __future__ import annotations

from flexarm.studies.reproduction.beyond import RowResult

__all__ = ["row_result"]


def row_result(
    law: str,
    sensor: str,
    name: str,
    rms: float | None,
    mx: float | None = None,
    torque: float = 40.0,
    diverged_at: float = 1.0,
) -> RowResult:
    """One run of the study: ``rms`` None for a run that diverged (at ``diverged_at`` s),
    else its RMS error (m), maximum error ``mx`` (m; 3 rms if not given) and torque (N m)."""
    diverged = rms is None
    return RowResult(
        law=law,
        sensor=sensor,
        row=name,
        status="diverged" if diverged else "ok",
        diverged_at_s=diverged_at if diverged else None,
        rms_error_m=rms,
        max_error_m=None if diverged else (mx if mx is not None else 3 * rms),
        max_torque_Nm=None if diverged else torque,
    )
