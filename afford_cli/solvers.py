"""Off-the-shelf planners on afford's PDDL: Fast Downward through unified-planning.

unified-planning and up-fast-downward (whose wheel carries the planner) are the optional
extra ``afford[pddl]``; without them solving refuses in one sentence. The plan comes back as afford steps (behaviour, object),
which :func:`run_blind` executes in the simulator.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from afford.errors import AffordError

__all__ = ["solve_pddl", "run_blind"]


def _driver() -> Path:
    """The Fast Downward driver script up-fast-downward's wheel ships (with its binary)."""
    try:
        import importlib.resources

        import up_fast_downward  # noqa: F401
        import unified_planning  # noqa: F401  (the extra is installed whole, or not at all)
    except ImportError:
        raise AffordError("solving PDDL needs unified-planning and up-fast-downward, an optional extra: "
                          "pip install 'afford[pddl]'") from None
    driver = Path(str(importlib.resources.files("up_fast_downward").joinpath("downward/fast-downward.py")))
    if not driver.exists():
        raise AffordError(f"up-fast-downward is installed without its planner ({driver} is missing); reinstall it")
    return driver


def check_solver() -> None:
    """Refuse, before any work, when the planner is not installed."""
    _driver()


#: Fast Downward's exit codes that mean "no plan" (translate or search proved it unsolvable,
#: or the search space ran out without one)
_NO_PLAN = {10: "unsolvable", 11: "unsolvable", 12: "unsolved"}


def solve_pddl(task, time_limit: float = 120.0) -> dict:
    """Fast Downward's cheapest plan (A* with LM-cut: the most probable plan of the
    determinised model) for a :class:`afford.plan.pddl.PddlTask`, the closing ``finish``
    step left out: ``{"solved", "status", "steps": [[behaviour, object], ...], "cost", "seconds"}``.

    The planner runs on the written files, through the driver up-fast-downward's wheel
    ships. (unified-planning's ``OneshotPlanner`` re-writes the task first, which took 40 s
    on a task Fast Downward itself solves in 0.3 s; tests parse the files with
    unified-planning's reader as an independent check.)
    """
    from afford.plan.pddl import decode_step

    driver = _driver()
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="afford-pddl-") as tmp:
        Path(tmp, "domain.pddl").write_text(task.domain)
        Path(tmp, "problem.pddl").write_text(task.problem)
        try:
            proc = subprocess.run([sys.executable, str(driver), "--plan-file", "plan", "domain.pddl", "problem.pddl",
                                   "--search", "astar(lmcut())"], cwd=tmp, capture_output=True, text=True,
                                  timeout=time_limit)
        except subprocess.TimeoutExpired:
            raise AffordError(f"Fast Downward found no plan within {time_limit:g} s") from None
        seconds = round(time.perf_counter() - start, 4)
        if proc.returncode in _NO_PLAN:
            return {"solved": False, "status": _NO_PLAN[proc.returncode], "steps": [], "cost": None, "seconds": seconds}
        plan_file = Path(tmp, "plan")
        if proc.returncode != 0 or not plan_file.exists():
            last = (proc.stdout + proc.stderr).strip().splitlines()[-1:] or ["no output"]
            raise AffordError(f"Fast Downward failed (exit {proc.returncode}): {last[0]}")
        lines = plan_file.read_text().splitlines()
    steps, cost = [], None
    for line in lines:
        line = line.strip()
        if line.startswith(";"):
            found = re.search(r"cost = (\d+)", line)
            cost = int(found.group(1)) if found else cost
        elif line:
            name, *args = line.strip("()").split()
            if name.lower() != "finish":
                steps.append(list(decode_step(name, args, task)))
    return {"solved": True, "status": "optimal", "steps": steps, "cost": cost, "seconds": seconds}


def run_blind(world, goal, steps) -> dict:
    """Run ``steps`` in ``world`` one after another, without monitoring; did the goal hold?"""
    ran = []
    for behavior, obj in steps:
        if obj >= world.perceive().shape[0]:
            break
        world.act(behavior, int(obj))
        ran.append([behavior, int(obj)])
    return {"reached": bool(goal.holds(world.perceive())), "ran": ran}
