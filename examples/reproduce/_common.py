"""What every reproduction script shares (DESIGN.md section 14); not a script itself."""

from __future__ import annotations

import subprocess
from pathlib import Path


def commit() -> str:
    """The commit the figures come from (``unknown`` outside a git checkout)."""
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=Path(__file__).parent, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def parser(doc: str):
    """The options every script takes: ``--quick``, ``--seed``, ``--out``, ``--workers``."""
    import argparse

    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="minutes, smaller samples (make reproduce)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default="reproduce", help="where the .md, .png and .json go")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--cache", default=None, metavar="DIR",
                    help="keep explorations and models here and reuse those of the same recipe (scene, seed, size, "
                         "learner, afford version); make reproduce shares one among its scripts")
    return ap


def _cached(args, recipe: dict, suffix: str) -> Path | None:
    """Where ``recipe``'s artefact lives in ``args.cache`` (None: no cache). The name is the
    hash of the recipe and afford's version, so a file is only ever reused for the same
    exploration or learning; ``make reproduce`` empties the cache first, so edits to the code
    between runs cannot leak in."""
    import hashlib
    import json

    import afford

    cache = getattr(args, "cache", None)
    if not cache:
        return None
    key = json.dumps({**recipe, "afford": afford.__version__}, sort_keys=True)
    Path(cache).mkdir(parents=True, exist_ok=True)
    return Path(cache) / f"{hashlib.sha256(key.encode()).hexdigest()[:20]}.{suffix}.afford"


def explored(scene: str, args, *, seed: int, **size):
    """``afford.explore(scene, seed=seed, workers=args.workers, **size)`` (``size``:
    ``episodes`` or ``interactions``), or the same exploration from ``args.cache``."""
    import afford

    path = _cached(args, {"scene": scene, "seed": seed, **size}, "interactions")
    if path is not None and path.exists():
        return afford.load(str(path))
    data = afford.explore(scene, seed=seed, workers=args.workers, **size)
    if path is not None:
        afford.save(data, str(path), seed=seed)  # atomic: a killed run leaves no half file
    return data


def parallel(fn, items, workers: int, *shared) -> list:
    """``[fn(*shared, item) for item in items]``, in order, on ``workers`` processes (joblib),
    the items dealt out in contiguous chunks so that ``shared`` (a model, say) is sent once
    per chunk. For independent simulator runs: each item carries its own seed, so the
    results do not depend on ``workers``."""
    from joblib import Parallel, delayed

    items = list(items)
    if workers <= 1 or len(items) < 2:
        return [fn(*shared, item) for item in items]
    size = -(-len(items) // (4 * workers))
    chunks = [items[a:a + size] for a in range(0, len(items), size)]
    run = lambda chunk, *shared: [fn(*shared, item) for item in chunk]  # noqa: E731
    return [r for part in Parallel(n_jobs=workers)(delayed(run)(c, *shared) for c in chunks) for r in part]


def stream_parser(doc: str, situations: str):
    """:func:`parser` with the overrides of the curiosity scripts' candidate streams:
    ``--candidates``, ``--test-size`` (test ``situations``) and ``--orderings``."""
    ap = parser(doc)
    ap.add_argument("--candidates", type=int, help="override the mode's number of candidates")
    ap.add_argument("--test-size", type=int, help=f"override the mode's number of test {situations}")
    ap.add_argument("--orderings", type=int, help="override the mode's number of orderings")
    return ap


def quartiles(values) -> dict:
    """Median and quartiles (rounded to 4 places) of the finite ``values``, and how many there were."""
    import numpy as np

    v = np.asarray([x for x in values if np.isfinite(x)], dtype=float)
    if v.size == 0:
        return {"median": None, "q1": None, "q3": None, "n": 0}
    q1, med, q3 = np.percentile(v, [25, 50, 75])
    return {"median": round(float(med), 4), "q1": round(float(q1), 4), "q3": round(float(q3), 4), "n": int(v.size)}


def learner_option(ap, default: str | None = None) -> None:
    """``--kernel``: the learner ``train_model`` fits (``default``; None: the scene's)."""
    what = default or "the scene's SVM"
    ap.add_argument("--kernel", choices=("linear", "rbf", "forest"), default=default,
                    help=f"the learner (default: {what}); forest: a random forest on every feature, with no "
                         "feature selection")


def learner_note(args) -> str:
    """What a script's own model learned with, for its report: "" for the scene's learner."""
    kernel = getattr(args, "kernel", None)
    if getattr(args, "model", None) or kernel is None:
        return ""
    return ", a random forest" if kernel == "forest" else f", an {kernel} SVM" if kernel == "rbf" else f", a {kernel} SVM"


def learner_fields(args) -> dict:
    """What a script's JSON records of its learner: ``kernel`` (None with ``--model``; the
    scripts with ``--kernel`` learn the traverse scenes, whose own learner is the linear SVM)
    and ``learner``, :func:`learner_note`'s phrase for its report."""
    kernel = None if getattr(args, "model", None) else (getattr(args, "kernel", None) or "linear")
    return {"kernel": kernel, "learner": learner_note(args)}


def train_model(scene: str, args, directory: Path, interactions: int = 5000) -> str:
    """Explore ``scene`` and learn as ``afford select-features | afford train`` does; the
    model's path in ``directory``. ``args.episodes`` sizes the exploration if given; else 100
    environments in quick mode and ``interactions`` in full mode (5000: the README's models).
    With ``args.cache``, the exploration and the model are taken from there when a script
    before made them from the same recipe, and left there for the next.
    ``args.kernel``, where a script has it, is the learner (None: the scene's); a forest
    trains on every feature, with no selection."""
    import afford

    episodes = getattr(args, "episodes", None)
    size = {"episodes": episodes} if episodes else (
        {"episodes": 100} if args.quick else {"interactions": interactions})
    kernel = getattr(args, "kernel", None)
    cached = _cached(args, {"scene": scene, "seed": args.seed, **size, "kernel": kernel}, "model")
    if cached is not None and cached.exists():
        return str(cached)
    data = explored(scene, args, seed=args.seed, **size)
    afford.save(data, str(directory / "train.afford"), seed=args.seed)
    model = str(cached or directory / "model.afford")
    if kernel == "forest":  # a forest reads every feature: no selection
        afford.train(str(directory / "train.afford"), model, seed=args.seed, kernel=kernel)
        return model
    afford.select_features(str(directory / "train.afford"), str(directory / "features.afford"), seed=args.seed,
                           kernel=kernel)
    afford.train(str(directory / "features.afford"), model, seed=args.seed, kernel=kernel)
    return model
