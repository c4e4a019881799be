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
    return ap


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


def train_model(scene: str, args, directory: Path) -> str:
    """Explore ``scene`` and learn as ``afford select-features | afford train`` does; the
    model's path in ``directory``. ``args.episodes`` sizes the exploration if given; else 100
    environments in quick mode and 5000 interactions in full mode (the README's models).
    ``args.kernel``, where a script has it, is the learner (None: the scene's); a forest
    trains on every feature, with no selection."""
    import afford

    size = {"episodes": args.episodes} if args.episodes else (
        {"episodes": 100} if args.quick else {"interactions": 5000})
    data = afford.explore(scene, seed=args.seed, workers=args.workers, **size)
    afford.save(data, str(directory / "train.afford"), seed=args.seed)
    kernel = getattr(args, "kernel", None)
    if kernel == "forest":  # a forest reads every feature: no selection
        afford.train(str(directory / "train.afford"), str(directory / "model.afford"), seed=args.seed, kernel=kernel)
        return str(directory / "model.afford")
    afford.select_features(str(directory / "train.afford"), str(directory / "features.afford"), seed=args.seed,
                           kernel=kernel)
    afford.train(str(directory / "features.afford"), str(directory / "model.afford"), seed=args.seed, kernel=kernel)
    return str(directory / "model.afford")
