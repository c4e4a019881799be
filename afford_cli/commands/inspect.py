"""``afford inspect``: report and verify any artefact."""

from __future__ import annotations

from rich import box
from rich.table import Table

from afford_cli.artifacts import Artifact, read_artifact
from afford_cli.datasets import interactions_from_artifact, outcome_table
from afford_cli.options import InputPath, Json
from afford_cli.output import Output


def describe(art: Artifact) -> dict:
    """Everything a report shows, as plain data."""
    m = art.manifest
    info = {
        "kind": art.kind,
        "schema_version": m["schema_version"],
        "afford_version": m.get("afford_version"),
        "sha256": art.sha256,
        "created": m.get("created"),
        "command": m.get("command"),
        "seed": m.get("seed"),
        "parents": m.get("parents", []),
        "verified": True,
        "members": sorted(m.get("members", {})),
        "features": m.get("schema", []),
        "behaviors": [b["name"] for b in m.get("behaviors", [])],
    }
    if "n_interactions" in m:
        data = interactions_from_artifact(art)
        info.update({
            "n_interactions": m["n_interactions"],
            "n_episodes": m.get("n_episodes"),
            "counts": m.get("counts", {}),
            "outcomes": outcome_table(data),
            "scene": m.get("scene", {}),
        })
    return info


def render(console, info: dict) -> None:
    head = Table(title=f"afford artefact: {info['kind']}", show_header=False)
    head.add_column("field", style="bold")
    head.add_column("value")
    for key in ("kind", "schema_version", "afford_version", "sha256", "created", "seed"):
        head.add_row(key, str(info.get(key)))
    head.add_row("command", " ".join(info.get("command") or []))
    head.add_row("parents", ", ".join(f"{p['kind']} {p['sha256'][:12]}" for p in info["parents"]) or "none")
    head.add_row("checksums", "verified")
    if "n_interactions" in info:
        head.add_row("interactions", f"{info['n_interactions']} in {info['n_episodes']} episodes")
        head.add_row("scene", str(info["scene"].get("name", "?")))
    console.print(head)
    if info["features"]:
        channels: dict[str, list[str]] = {}
        for f in info["features"]:
            channels.setdefault(f["channel"], []).append(f["name"])
        ft = Table(title=f"features ({len(info['features'])})")
        ft.add_column("channel")
        ft.add_column("n", justify="right")
        ft.add_column("names")
        for ch, names in channels.items():
            shown = ", ".join(names) if len(names) <= 8 else ", ".join(names[:3]) + f", ... , {names[-1]}"
            ft.add_row(ch, str(len(names)), shown)
        console.print(ft)
    if info.get("counts"):
        ct = Table(title="interactions per behaviour")
        ct.add_column("behaviour")
        ct.add_column("count", justify="right")
        for k, v in info["counts"].items():
            ct.add_row(k, str(v))
        console.print(ct)
    if info.get("outcomes"):
        render_outcome_table(console, info["outcomes"])


def render_outcome_table(console, outcomes: dict) -> None:
    """``{behaviour: {shape: {label: count}}}`` as one table."""
    from features import OUTCOMES

    ot = Table(title="what physically happened (ground truth, never used to learn)", box=box.SIMPLE_HEAD)
    ot.add_column("behaviour", no_wrap=True)
    ot.add_column("shape", no_wrap=True, min_width=14)
    for label in OUTCOMES:
        ot.add_column(label, justify="right", no_wrap=True)
    for behavior, shapes in outcomes.items():
        for shape, counts in shapes.items():
            ot.add_row(behavior, shape, *[str(counts.get(label, 0)) for label in OUTCOMES])
    console.print(ot)


def inspect(path: InputPath, json: Json = False) -> None:
    """Report any afford artefact (kind, lineage, features, counts, outcomes) and verify its checksums."""
    art = read_artifact(path)
    info = describe(art)
    Output(json).result(info, lambda console: render(console, info))
