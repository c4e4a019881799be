"""Driving the mobile robot through a room with its learned traversability (thesis 5.6.5).

One world persists: the robot starts at a random free place of the room (the scene's
``stand``), and at every step scans, asks its model each move's chance of success, lets the
controller (``plan.navigation``) choose, and moves on from wherever the move left it. A
move that the robot's own odometry judges failed counts as failed; three failed moves in a
row, or a whole turn of looking around (six 60-degree turns in place) with nothing to move
on, and the robot is stuck. The path is the true one (ground truth, for the report only).

The robot also remembers, from its gyro, the headings of the moves that failed since its
last successful one, and does not try a move that would head within 10 degrees of one of
them again: a blocked robot has not moved far, sees nearly what it saw, and would otherwise
be told the same thing by its model and fail the same way until it is stuck. The thesis
leaves a failed move's aftermath open; this rule is ours (all controllers follow it).
"""

from __future__ import annotations

import math

import numpy as np

from afford.errors import AffordError

__all__ = ["navigate", "draw_navigation", "STUCK_AFTER", "LOOK_TURN"]

#: Failed moves in a row that leave the robot stuck.
STUCK_AFTER = 3
#: The turn in place (degrees) when nothing is afforded, and how many of them make a whole turn.
LOOK_TURN = 60.0
LOOKS = 6
#: A move heading within this many degrees of a failed one since the last success is not tried.
REFUSE_WITHIN = 10.0


def _success_chances(loaded, x: np.ndarray) -> list[float]:
    good = loaded.result_names.index("success")
    out = []
    for name in loaded.names:
        pred = loaded.predictors[name]
        p = pred.predict_proba(x[:, loaded.selected[name]])[0]
        classes = list(np.asarray(pred.classes_, dtype=int))
        out.append(float(p[classes.index(good)]) if good in classes else 0.0)
    return out


def check_navigable(loaded, scene) -> None:
    """One sentence if this model cannot drive this scene's robot."""
    if not hasattr(scene, "stand"):
        raise AffordError(f"scene {scene.name!r} is not a room to navigate; use room or traverse-room")
    if loaded.label_source != "given" or "success" not in loaded.result_names:
        raise AffordError("navigation needs a model of the mobile robot's moves (learned from its success readings)")
    moves = [b.name for b in scene.behaviors]
    missing = [m for m in moves if m not in loaded.names]
    if missing:
        raise AffordError(f"the model has no predictor for {missing[0]}: it was not learned from the mobile robot's moves")
    loaded.check_schema(scene.schema, "this scene's perception")


def navigate(loaded, scene, controller: str, *, seed: int = 0, steps: int = 100, threshold: float = 0.5,
             progress=None) -> dict:
    """Drive ``scene``'s robot for at most ``steps`` scans with ``controller``; the report."""
    from afford.plan.navigation import choose
    from afford.sim.moves import DRIVE

    check_navigable(loaded, scene)
    rotations = {b.name: _rotation(b.name) for b in scene.behaviors}
    rng = np.random.default_rng(np.random.SeedSequence(entropy=int(seed), spawn_key=(11,)))
    pick = np.random.default_rng(np.random.SeedSequence(entropy=int(seed), spawn_key=(12,)))
    layout, (sx, sy, syaw) = scene.stand(rng)
    world = scene.build(layout, rng)
    robot = world.world.robot
    c, s = math.cos(math.radians(syaw)), math.sin(math.radians(syaw))

    def where() -> tuple[float, float]:
        p = robot.pose()
        return round(sx + c * p.x - s * p.y, 4), round(sy + s * p.x + c * p.y, 4)

    path, failed_at, log, failed_headings = [where()], [], [], []
    distance, moves, failed, in_row, looks, stuck, reason = 0.0, 0, 0, 0, 0, False, None
    for step in range(steps):
        x = world.perceive()
        chances = _success_chances(loaded, x)
        heading = math.degrees(robot.gyro())
        refused = [_near(heading + rotations[n], failed_headings) for n in loaded.names]
        if all(refused):
            rotate = None
        else:
            names = [n for n, r in zip(loaded.names, refused) if not r]
            rotate = choose(controller, [rotations[n] for n in names],
                            [p for p, r in zip(chances, refused) if not r], threshold=threshold, rng=pick)
        if rotate is None:
            world.move(LOOK_TURN, 0.0)
            looks += 1
            log.append({"step": step, "look": True})
            if looks >= LOOKS:
                stuck, reason = True, "nothing afforded all around"
                break
            continue
        looks = 0
        odometry = world.move(rotate, DRIVE)
        moves += 1
        before, now = path[-1], where()
        distance += math.hypot(now[0] - before[0], now[1] - before[1])
        path.append(now)
        ok = bool(odometry.success)
        log.append({"step": step, "heading": round(heading, 2), "rotate": round(float(rotate), 2), "success": ok,
                    "p_success": round(float(max(chances)), 4)})
        if ok:
            in_row, failed_headings = 0, []
        else:
            failed, in_row = failed + 1, in_row + 1
            failed_headings.append(heading + float(rotate))
            failed_at.append(now)
            if in_row >= STUCK_AFTER:
                stuck, reason = True, f"{STUCK_AFTER} failed moves in a row"
                break
        if progress is not None:
            progress(step + 1, steps)
    return {"scene": scene.name, "room": getattr(scene, "room", None), "controller": controller, "seed": int(seed),
            "steps": len(log), "distance_m": round(distance, 3), "moves": moves, "failed_moves": failed,
            "failed_per_metre": round(failed / distance, 4) if distance > 0 else None,
            "looks": sum(1 for e in log if e.get("look")), "stuck": stuck, "stuck_because": reason,
            "start": [round(sx, 4), round(sy, 4), round(syaw, 2)], "path": [list(p) for p in path],
            "failed_at": [list(p) for p in failed_at], "log": log}


def _near(heading: float, headings: list[float]) -> bool:
    """Whether ``heading`` lies within :data:`REFUSE_WITHIN` degrees of one of ``headings``."""
    return any(abs((heading - h + 180.0) % 360.0 - 180.0) < REFUSE_WITHIN for h in headings)


def _rotation(name: str) -> float:
    if name == "go-forward":
        return 0.0
    _, side, angle = name.split("-")
    return float(angle) * (1.0 if side == "left" else -1.0)


def draw_navigation(path: str, scene, result: dict) -> str:
    """The room from above: walls, furniture and objects where they started, and the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon

    fig, ax = plt.subplots(figsize=(6.5, 6.5))
    for it in scene.items():
        (cx, cy), (hx, hy), yaw = it.footprint()
        a = math.radians(yaw)
        u, v = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
        corners = [np.array([cx, cy]) + sx * hx * u + sy * hy * v for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        colour = "0.25" if it.fixed and it.bottom == 0 else ("0.6" if it.fixed else "tab:orange")
        ax.add_patch(Polygon(corners, closed=True, color=colour, alpha=0.35 if it.bottom > 0 else 0.8, lw=0))
    p = np.asarray(result["path"])
    ax.plot(p[:, 0], p[:, 1], "-", color="tab:blue", lw=1.5, label="path")
    ax.plot(*p[0], "o", color="tab:green", label="start")
    if result["failed_at"]:
        f = np.asarray(result["failed_at"])
        ax.plot(f[:, 0], f[:, 1], "x", color="tab:red", label="failed move")
    ax.set_aspect("equal")
    ax.set_xlim(-3.3, 3.3)
    ax.set_ylim(-3.3, 3.3)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{result['controller']}: {result['distance_m']:.1f} m, {result['moves']} moves, "
                 f"{result['failed_moves']} failed{', stuck' if result['stuck'] else ''} (room {result['room']})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
