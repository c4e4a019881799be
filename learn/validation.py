"""Shared by every learner: input checks (one sentence for bad data), and the stratified
sample a cross-validated search runs on when the rows are many."""

from __future__ import annotations

import numpy as np
from afford.features.errors import DataError

__all__ = ["check_finite", "stratified_sample"]


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


def stratified_sample(y_idx: np.ndarray, n: int | None, random_state) -> np.ndarray | None:
    """Sorted rows of a stratified sample of about ``n`` of the labels ``y_idx`` (0-based
    ids), or None when ``n`` is None or there are no more rows than that. Each category
    gives in proportion to its size, and at least two members (or all it has), so none
    that cross-validation could hold out is lost. ``random_state`` (a seed, a
    ``RandomState`` or None) is drawn from only when there is a sample to take, so a shared
    generator moves as it would without the sample."""
    if n is None or y_idx.size <= n:
        return None
    from sklearn.utils import check_random_state

    rng = np.random.default_rng(check_random_state(random_state).randint(np.iinfo(np.int32).max))
    share = n / y_idx.size
    picked = []
    for c in range(int(y_idx.max()) + 1):
        rows = np.flatnonzero(y_idx == c)
        if rows.size:
            picked.append(rng.choice(rows, min(rows.size, max(2, int(round(rows.size * share)))), replace=False))
    return np.sort(np.concatenate(picked))
