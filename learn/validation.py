"""Input checks shared by every learner: one sentence for bad data."""

from __future__ import annotations

import numpy as np
from afford.features.errors import DataError

__all__ = ["check_finite"]


def check_finite(X: np.ndarray, what: str = "X") -> None:
    """Raise one ValueError sentence when an array holds NaN or infinite values."""
    finite = np.isfinite(X)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        where = f"row {bad[0]}" + (f", column {bad[1]}" if bad.size > 1 else "")
        raise DataError(
            f"{what} contains NaN or infinite values (first at {where}); "
            "drop or repair those rows before learning."
        )
