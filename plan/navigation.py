"""Navigation with learned traversability (thesis 5.6.5, Figure 5.9): which way to move next.

The mobile robot's moves rotate in place by a multiple of 20 degrees and drive 70 cm. At
every step the robot scans, asks its model each move's chance of success, and a
controller decides, given which moves are *afforded* (chance of success at least
``threshold``, one half by default):

* **aggressive** (Figure 5.9a): the first afforded move in priority order, go-forward
  first, then the smallest turns, left before right (0, +20, -20, +40, -40, +60, -60).
* **cautious** (Figure 5.9b): the robot moves only if more than one neighbouring move is
  afforded (neighbours: rotations 20 degrees apart). Among the runs of neighbouring afforded
  moves it takes the longest (ties: the one heading straightest, then the left one) and
  moves in its mean direction, so it may turn by 10, 30 or 50 degrees, "new behaviours"
  as the thesis says.
* **random**: any of the moves, uniformly; the baseline, blind to the model.

When no move is afforded (aggressive) or no two neighbouring ones (cautious), the
controller returns ``None``: the caller turns the robot in place to look elsewhere (the
thesis leaves this case open).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

__all__ = ["CONTROLLERS", "priority", "choose"]

CONTROLLERS = ("aggressive", "cautious", "random")


def priority(rotations: Sequence[float]) -> list[float]:
    """The aggressive controller's order: straight ahead first, then the smallest turns, left first."""
    return sorted((float(r) for r in rotations), key=lambda r: (abs(r), -r))


def _runs(afforded: list[float], step: float) -> list[list[float]]:
    runs: list[list[float]] = []
    for r in sorted(afforded):
        if runs and abs(r - runs[-1][-1] - step) < 1e-6:
            runs[-1].append(r)
        else:
            runs.append([r])
    return runs


def choose(controller: str, rotations: Sequence[float], p_success: Sequence[float], *,
           threshold: float = 0.5, rng: np.random.Generator | None = None, step: float = 20.0) -> float | None:
    """The rotation (degrees, left positive) of the next move, or None: nothing to move on.

    ``rotations[i]`` is move i's rotation and ``p_success[i]`` its predicted chance of success.
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"unknown controller {controller!r}; the controllers are {', '.join(CONTROLLERS)}")
    rotations = [float(r) for r in rotations]
    if len(rotations) != len(p_success) or not rotations:
        raise ValueError("give one chance of success per move")
    if controller == "random":
        g = rng if rng is not None else np.random.default_rng()
        return rotations[int(g.integers(len(rotations)))]
    afforded = {r for r, p in zip(rotations, p_success) if p >= threshold}
    if controller == "aggressive":
        return next((r for r in priority(rotations) if r in afforded), None)
    runs = [run for run in _runs(sorted(afforded), step) if len(run) > 1]
    if not runs:
        return None
    best = min(runs, key=lambda run: (-len(run), abs(float(np.mean(run))), -float(np.mean(run))))
    return float(np.mean(best))
