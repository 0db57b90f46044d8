"""Array types of the type hints, one name each (``F64``: an array of float64)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["F64", "I64"]

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]
