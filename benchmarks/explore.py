"""Exploration speed: interactions (and environments) per second with 1 and 2 workers, and where the time goes.

    python benchmarks/explore.py [--scenes table,traverse,...] [--interactions N] [--out benchmarks/results/explore.json]

Prints one JSON object (and writes it to --out). ``backends`` compares loky with Dask (a
LocalCluster of 2 workers on 127.0.0.1: start-up, interactions/s, shut-down) and checks that
both, and a run interrupted half-way and resumed, give the same bytes (2000 interactions). The breakdown times one worker's
episodes in this process by wrapping each stage. The table: world build, ray casting
(Open3D), physics (PhysX steps, including contact queries) and features (detection,
normals, histograms, tracking). The traverse scenes: world build, the scan (720 x 720
rays cast with Open3D, noise, min-downscale), physics (the robot's moves) and the grid
features. ``crane-lift``: the same stages, physics being the moves, the crane's lifts and
settling, features the background subtraction, segmentation and the 44 features.
``grasp``: the table's stages, features being chapter 9's contact-point features.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402

import afford.features.objects as fobj  # noqa: E402
import afford.sim.camera as cam  # noqa: E402
import afford.sim.crane as crane  # noqa: E402
import afford.sim.grasp as grasp  # noqa: E402
import afford.sim.moves as moves  # noqa: E402
import afford.sim.robots.mobile as mobile  # noqa: E402
import afford.sim.scanner as scanner  # noqa: E402
import afford.sim.traverse as traverse  # noqa: E402
import afford.sim.world as world  # noqa: E402
from afford.sim.explore import explore, run_episode  # noqa: E402
from afford.sim.registry import make_scene  # noqa: E402


def throughput(scene, n: int, workers: int, seed: int) -> dict:
    explore(scene, interactions=min(n, 20), seed=seed + 999, workers=workers)  # start the workers' imports
    start = time.perf_counter()
    data = explore(scene, interactions=n, seed=seed, workers=workers)
    seconds = time.perf_counter() - start
    environments = int(np.unique(data.episode).size)
    return {"workers": workers, "interactions": len(data), "environments": environments, "seconds": round(seconds, 3),
            "interactions_per_second": round(len(data) / seconds, 1),
            "environments_per_second": round(environments / seconds, 2)}


def backends(scene, n: int, seed: int) -> dict:
    """loky against Dask (a LocalCluster of 2 workers on 127.0.0.1), and a run interrupted
    half-way and resumed from its journal: interactions/s, Dask's start-up and shut-down,
    and whether all three gave the same bytes."""
    import tempfile

    import afford
    from afford.backends import open_pool
    from afford.datasets import interactions_members
    from afford.errors import Interrupted

    def digest(data) -> str:
        import hashlib

        h = hashlib.sha256()
        for k, v in sorted(interactions_members(data)[0].items()):
            h.update(k.encode() + v.tobytes())
        return h.hexdigest()

    out: dict = {"interactions": n}
    start = time.perf_counter()
    loky = afford.explore(scene, interactions=n, seed=seed, workers=2)
    out["loky_2_workers"] = {"seconds": round(time.perf_counter() - start, 2),
                             "interactions_per_second": round(n / (time.perf_counter() - start), 1)}
    t0 = time.perf_counter()
    with open_pool("dask", 2) as pool:
        started = time.perf_counter() - t0
        from afford.sim.explore import explore as run

        run(scene, interactions=min(n, 200), seed=seed + 999, pool=pool)  # both workers import afford
        t1 = time.perf_counter()
        dask = run(scene, interactions=n, seed=seed, pool=pool)
        seconds = time.perf_counter() - t1
        t2 = time.perf_counter()
    out["dask_2_workers"] = {"seconds": round(seconds, 2), "interactions_per_second": round(n / seconds, 1),
                             "cluster_start_seconds": round(started, 2),
                             "shutdown_seconds": round(time.perf_counter() - t2, 2)}
    with tempfile.TemporaryDirectory() as d:
        journal = Path(d) / "run.partial"

        def stop_half_way(done, total):
            if done >= total // 2:
                raise KeyboardInterrupt

        try:
            afford.explore(scene, interactions=n, seed=seed, workers=2, journal=journal, progress=stop_half_way)
        except Interrupted:
            pass
        resumed = afford.explore(scene, interactions=n, seed=seed, workers=2, journal=journal, resume=True)
    out["same_bytes"] = {"loky": digest(loky), "dask": digest(dask) == digest(loky),
                         "interrupted_and_resumed": digest(resumed) == digest(loky)}
    return out


def _patched(targets: list[tuple[object, str, str]], totals: dict):
    """Wrap ``owner.attr`` so its time adds to ``totals[key]``; returns what to restore."""
    saved = []
    for owner, attr, key in targets:
        fn = getattr(owner, attr)
        saved.append((owner, attr, fn))

        def wrapper(*a, _fn=fn, _key=key, **k):
            t = time.perf_counter()
            try:
                return _fn(*a, **k)
            finally:
                totals[_key] += time.perf_counter() - t
        setattr(owner, attr, wrapper)
    return saved


#: What to time in each mobile-robot scene: (owner, attribute, stage).
_STAGES = {
    "traverse": [(traverse.TraverseWorld, "__init__", "world_build"), (scanner.RangeScanner, "scan", "scan"),
                 (mobile.MobileRobot, "move", "physics"), (moves, "grid_features", "features")],
    "crane": [(crane.CraneWorld, "__init__", "world_build"), (scanner.RangeScanner, "scan", "scan"),
              (mobile.MobileRobot, "move", "physics"), (crane.CraneWorld, "lift", "physics"),
              (crane.CraneWorld, "settle", "physics"), (crane, "perceive_against", "features")],
}


def scan_breakdown(scene, episodes: int, seed: int) -> dict:
    """Where one worker's time goes in a mobile-robot scene (Algorithm 1), per interaction."""
    totals = {"world_build": 0.0, "scan": 0.0, "physics": 0.0, "features": 0.0}
    saved = _patched(_STAGES["crane" if scene.name.startswith("crane") else "traverse"], totals)
    try:
        start = time.perf_counter()
        rows = sum(len(run_episode(scene, seed, e)) for e in range(episodes))
        total = time.perf_counter() - start
    finally:
        for owner, attr, fn in saved:
            setattr(owner, attr, fn)
    out = {k: round(1000 * v / rows, 2) for k, v in totals.items()}
    out["other"] = round(1000 * total / rows - sum(out.values()), 2)
    env = {k: round(1000 * v / episodes, 1) for k, v in totals.items()}
    return {"ms_per_interaction": out, "ms_per_environment": env, "interactions": rows, "environments": episodes,
            "seconds": round(total, 3)}


def breakdown(scene, episodes: int, seed: int) -> dict:
    totals = {"world_build": 0.0, "ray_casting": 0.0, "physics": 0.0, "features": 0.0}

    def timed(key, fn):
        def wrapper(*a, **k):
            t = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                totals[key] += time.perf_counter() - t
        return wrapper

    saved = (world.TableWorld.__init__, cam.RangeCamera.capture, world.TableWorld.step, world.perceive, world.track,
             grasp.perceive_contact_points)
    world.TableWorld.__init__ = timed("world_build", saved[0])
    cam.RangeCamera.capture = timed("ray_casting", saved[1])
    world.TableWorld.step = timed("physics", saved[2])
    world.perceive = timed("features", saved[3])
    world.track = timed("features", saved[4])
    grasp.perceive_contact_points = timed("features", saved[5])
    try:
        start = time.perf_counter()
        rows = sum(len(run_episode(scene, seed, e)) for e in range(episodes))
        total = time.perf_counter() - start
    finally:
        (world.TableWorld.__init__, cam.RangeCamera.capture, world.TableWorld.step, world.perceive, world.track,
         grasp.perceive_contact_points) = saved
    # world build includes the initial settle of a held object (physics), counted once each
    out = {k: round(1000 * v / rows, 2) for k, v in totals.items()}
    out["other"] = round(1000 * total / rows - sum(out.values()), 2)
    return {"ms_per_interaction": out, "interactions": rows, "seconds": round(total, 3)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--interactions", type=int, default=1000, help="per throughput run on the table")
    ap.add_argument("--traverse-interactions", type=int, default=700, help="per throughput run on a mobile-robot scene")
    ap.add_argument("--backend-interactions", type=int, default=2000, help="per run comparing loky, Dask and a resume")
    ap.add_argument("--scenes", default="table,traverse,traverse-body,traverse-ramps,traverse-gaps,crane-lift,grasp")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "explore.json"))
    args = ap.parse_args()
    names = [n for n in args.scenes.split(",") if n]
    result = {
        "benchmark": "explore",
        "machine": {"python": platform.python_version(), "cpus": __import__("os").cpu_count(),
                    "platform": platform.platform()},
    }
    for name in names:
        if name == "table":
            continue
        sc = make_scene(name)
        if name == "grasp":  # a play scene on the chapter-8 world: the table's breakdown
            result[name] = {
                "throughput": [throughput(sc, args.interactions, w, args.seed) for w in (1, 2)],
                "breakdown_one_worker": breakdown(sc, episodes=max(20, args.interactions // 5), seed=args.seed),
            }
            continue
        result[name] = {
            "throughput": [throughput(sc, args.traverse_interactions, w, args.seed) for w in (1, 2)],
            "breakdown_one_worker": scan_breakdown(sc, episodes=20, seed=args.seed),
        }
    if "table" not in names:
        emit(result, args.out)
        return
    scene = make_scene("table")
    result.update({
        "throughput": [throughput(scene, args.interactions, w, args.seed) for w in (1, 2)],
        "breakdown_one_worker": breakdown(scene, episodes=max(20, args.interactions // 10), seed=args.seed),
        "features_alone_ms": None,
        "backends": backends(scene, args.backend_interactions, args.seed),
    })
    # perception alone, on a typical range image
    rng = np.random.default_rng(0)
    w = scene.build([scene.sample_object(rng)], rng)
    image = w.camera.capture(w.meshes(), rng)
    t = time.perf_counter()
    for _ in range(50):
        fobj.perceive(image, w.config.roi())
    result["features_alone_ms"] = round(1000 * (time.perf_counter() - t) / 50, 2)
    emit(result, args.out)


if __name__ == "__main__":
    main()
