"""``afford scenes``: the registered scenes and their behaviours."""

from __future__ import annotations

from rich.table import Table

from afford.options import Json
from afford.output import Output


def scenes(json: Json = False) -> None:
    """List the registered scenes, what they are, and the behaviours the robot has in them."""
    from afford.sim.registry import get_scene, scene_names

    items = []
    for name in scene_names():
        cls = get_scene(name)
        items.append({"name": name, "summary": cls.summary,
                      "behaviors": [b.to_json() for b in cls.behaviors]})

    def render(console):
        table = Table(title="scenes")
        table.add_column("scene")
        table.add_column("what happens")
        table.add_column("behaviours")
        for it in items:
            table.add_row(it["name"], it["summary"], ", ".join(b["name"] for b in it["behaviors"]))
        console.print(table)

    Output(json).result({"scenes": items}, render)
