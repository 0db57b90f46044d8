"""How the reproduction writes numbers for people: rounded to what they mean.

The JSON summary and the CSV table keep every digit in SI units (the unit in each
key: ``rms_error_m``); the console, the figures and the HTML report write
tracking errors and deflections in millimetres, times in seconds and rates in
rad/s, each to three significant figures (a tracking error is known to a few
per cent, not to the float's sixteen digits), and whole numbers as they are.

>>> sig(0.11812), sig(1234.6), sig(-0.000544), sig(0.0480), sig(0.0)
('0.118', '1230', '-0.000544', '0.048', '0')
>>> mm(0.11812), mm(None), mm(float("inf"))
('118 mm', '–', 'inf')
"""

from __future__ import annotations

import math

__all__ = ["MISSING", "mm", "sig"]

MISSING = "–"
"""What stands for a number that does not exist (a diverged run's error)."""


def sig(value: float | None, digits: int = 3) -> str:
    """``value`` to ``digits`` significant figures (trailing decimal zeros dropped),
    in plain notation between 1e-5 and 1e6; :data:`MISSING` for None or NaN;
    ``"inf"`` for infinity."""
    if value is None or math.isnan(value):
        return MISSING
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if value == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(value)))
    if not -5 <= magnitude < 6:
        return f"{value:.{digits - 1}e}"
    decimals = digits - 1 - magnitude
    if decimals <= 0:  # whole numbers rounded too: 418273 -> 418000
        return f"{round(value, decimals):.0f}"
    text = f"{value:.{decimals}f}".rstrip("0").rstrip(".")  # 0.048 s, not 0.0480 s
    return "0" if float(text) == 0 else text


def mm(value_m: float | None, digits: int = 3) -> str:
    """A length given in m, written in mm to ``digits`` significant figures with its
    unit (``"118 mm"``); :data:`MISSING` for None or NaN, ``"inf"`` for infinity."""
    if value_m is None or math.isnan(value_m):
        return MISSING
    if math.isinf(value_m):
        return sig(value_m)
    return f"{sig(1e3 * value_m, digits)} mm"
