"""Run every reproduction script (``make reproduce``), in lanes side by side, then write the index.

    python examples/reproduce/_run.py [--quick] [--out DIR] [--cache DIR] [--lanes N] [--workers W] [SCRIPT ...]

The scripts of one chapter share explorations and models through ``--cache`` (chapter 5's
all train on the same ``traverse`` recipes), so a chapter's scripts run one after another,
in file-name order, in one lane. Chapters are dealt to ``--lanes`` lanes as lanes come
free, the chapter with the most scripts first. Every script spends part of its time on one
core (fitting, planning, drawing), so two lanes on two cores finish sooner than one; each
script's numbers do not depend on the lanes or the workers (every run has its own seed).

Each script's output is printed whole once it ends, with its time; the first script that
fails stops the run (the scripts running then are let finish) and the exit code is 1.
``DIR/index.md`` links every script's page.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import threading
import time
from collections import defaultdict
from pathlib import Path

HERE = Path(__file__).resolve().parent


def scripts(names: list[str] | None = None, folder: Path = HERE) -> list[Path]:
    """The reproduction scripts (``[!_]*.py`` in ``folder``), or the ones named, in file-name order."""
    every = sorted(p for p in Path(folder).glob("*.py") if not p.name.startswith("_"))
    if not names:
        return every
    chosen = []
    for name in names:
        match = [p for p in every if p.name == Path(name).name or p.stem == name]
        if not match:
            raise SystemExit(f"error: no reproduction script {name!r} in {folder}")
        chosen += match
    return sorted(set(chosen))


def chapter(script: Path) -> str:
    """The thesis chapter a script reproduces: the first number of its name (``table_7_1_crane``: 7)."""
    m = re.search(r"_(\d+)", script.stem)
    return m.group(1) if m else script.stem


def groups(chosen: list[Path]) -> list[list[Path]]:
    """The scripts by chapter, each chapter's in file-name order, the largest chapter first."""
    by = defaultdict(list)
    for s in chosen:
        by[chapter(s)].append(s)
    return sorted(by.values(), key=lambda g: (-len(g), g[0].name))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scripts", nargs="*", help="only these scripts (default: every one)")
    ap.add_argument("--quick", action="store_true", help="each script's quick mode (make reproduce)")
    ap.add_argument("--out", default="reproduce")
    ap.add_argument("--cache", default=None, help="the cache the scripts share (see _common.py)")
    ap.add_argument("--lanes", type=int, default=2, help="chapters run side by side (default 2)")
    ap.add_argument("--workers", type=int, default=2, help="each script's --workers")
    ap.add_argument("--dir", type=Path, default=HERE, help="where the scripts are (default: beside this file)")
    args = ap.parse_args(argv)
    if args.lanes < 1 or args.workers < 1:
        print("error: --lanes and --workers must be at least 1", file=sys.stderr)
        return 1
    todo = groups(scripts(args.scripts, args.dir))
    Path(args.out).mkdir(parents=True, exist_ok=True)
    lock = threading.Lock()
    failed: list[str] = []
    begin = time.monotonic()

    def lane() -> None:
        while True:
            with lock:
                if failed or not todo:
                    return
                group = todo.pop(0)
            for script in group:
                with lock:
                    if failed:
                        return
                cmd = [sys.executable, str(script), "--out", args.out, "--workers", str(args.workers)]
                cmd += ["--quick"] * args.quick + (["--cache", args.cache] if args.cache else [])
                start = time.monotonic()
                run = subprocess.run(cmd, capture_output=True, text=True)
                took = time.monotonic() - start
                with lock:
                    print(f"== {script.name}", flush=True)
                    sys.stdout.write(run.stdout)
                    sys.stdout.write(run.stderr[-4000:] if run.returncode else "")
                    print(f"== {script.name} took {took:.0f} s"
                          + ("" if run.returncode == 0 else f": FAILED (exit {run.returncode})"), flush=True)
                    if run.returncode:
                        failed.append(script.name)
                        return

    threads = [threading.Thread(target=lane, daemon=True) for _ in range(min(args.lanes, len(todo)))]
    for t in threads:
        t.start()
    try:
        for t in threads:
            while t.is_alive():
                t.join(0.5)  # a bare join() would not hear Ctrl-C until the lane ends
    except KeyboardInterrupt:  # the scripts, in the terminal's process group, heard it too
        print("error: interrupted; the pages written so far are in " + args.out, file=sys.stderr)
        return 130
    print(f"== every {'quick mode' if args.quick else 'script'} took {time.monotonic() - begin:.0f} s "
          f"({args.lanes} lane{'s' * (args.lanes != 1)})")
    if failed:
        print(f"error: {', '.join(failed)} failed", file=sys.stderr)
        return 1
    out = Path(args.out)
    pages = sorted(p for p in out.glob("*.md") if p.name != "index.md")
    lines = ["# Thesis figures reproduced" + (" (quick mode)" if args.quick else ""), ""]
    lines += [f"- [{(p.read_text().splitlines() or [p.stem])[0].lstrip('# ').strip()}]({p.name})" for p in pages]
    (out / "index.md").write_text("\n".join(lines) + "\n")
    print(f"-> {out / 'index.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
