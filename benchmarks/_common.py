"""What every benchmark does with its result: print it as JSON and keep a copy."""

from __future__ import annotations

import json
from pathlib import Path


def emit(result: dict, out: str) -> None:
    text = json.dumps(result, indent=1)
    Path(out).parent.mkdir(parents=True, exist_ok=True)
    Path(out).write_text(text + "\n")
    print(text)
