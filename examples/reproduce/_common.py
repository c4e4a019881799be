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
