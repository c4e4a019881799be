"""Summaries of many planning runs: plans found and goals reached by plan length (thesis Table 7.1)."""

from __future__ import annotations

import numpy as np

__all__ = ["summarise"]


def summarise(entries: list[dict], executed: bool) -> dict:
    """Found, reached and mean probabilities over the ``plan_once`` results of many scenes."""
    by_length: dict[str, dict] = {}
    probs, blind, imagined, first_ok = [], [], [], []
    for e in entries:
        p = e["plan"]
        if not p["found"]:
            continue
        key = str(p["length"])
        slot = by_length.setdefault(key, {"found": 0, "reached": 0 if executed else None})  # null: nothing ran
        slot["found"] += 1
        probs.append(p["success_probability"])
        blind.append(p["open_loop_probability"])
        if "blind_probability" in p:
            imagined.append(p["blind_probability"])
        if executed:
            slot["reached"] += int(e.get("reached", False))
            first_ok.append(bool(e.get("first_plan_worked", False)))
    found = sum(1 for e in entries if e["plan"]["found"])
    planned = [e for e in entries if "skipped" not in e]
    out = {"episodes": len(entries), "skipped": len(entries) - len(planned), "found": found, "by_length": dict(sorted(by_length.items(), key=lambda kv: int(kv[0]))),
           "mean_success_probability": round(float(np.mean(probs)), 4) if probs else None,
           "mean_open_loop_probability": round(float(np.mean(blind)), 4) if blind else None,
           "mean_blind_probability": round(float(np.mean(imagined)), 4) if imagined else None,
           "mean_seconds": round(float(np.mean([e["plan"]["seconds"] for e in planned] or [0.0])), 4),
           "mean_expanded": round(float(np.mean([e["plan"]["expanded"] for e in planned] or [0.0])), 1),
           # the search and the candidates' assessment (a caller that times the search alone: its time)
           "mean_planning_seconds": round(sum(e.get("planning_seconds", e["plan"]["seconds"]) for e in planned)
                                          / max(1, len(planned)), 4)}
    if executed:
        out["reached"] = sum(int(e.get("reached", False)) for e in entries)
        out["first_plan_worked"] = int(sum(first_ok))
    out["runs"] = entries if len(entries) > 1 else []
    return out
