"""Human renderings shared by several commands (the JSON carries the same numbers)."""

from __future__ import annotations

from rich import box
from rich.table import Table
from rich.text import Text

__all__ = ["bar_row", "render_categories", "render_outcome_table", "render_metrics", "render_result_rates"]

_GLYPHS = " ▁▂▃▄▅▆▇█"


def bar_row(values: list[float], scale: float) -> Text:
    """One glyph per value, height by |value| / scale, green up, red down (thesis fig. 8.4)."""
    text = Text()
    for v in values:
        level = 0 if scale <= 0 else min(8, int(round(8 * abs(v) / scale)))
        text.append(_GLYPHS[level] if level else "·", style="green" if v > 0 else "red" if v < 0 else "dim")
    return text


def render_categories(console, behavior: str, categories: list[dict], channels: list[tuple[str, list[str]]]) -> None:
    """A behaviour's categories: size, prototype per channel as bar rows, what physically happened."""
    table = Table(title=f"{behavior}: {len(categories)} effect categories (prototype effects; the position "
                        "channel also gives the centre's shift in metres)", box=box.SIMPLE_HEAD)
    table.add_column("id", justify="right", no_wrap=True, min_width=2)
    table.add_column("n", justify="right", no_wrap=True, min_width=4)
    scales = {}
    for channel, names in channels:
        table.add_column(channel if len(names) > 1 else channel[:3], no_wrap=True)
        scales[channel] = max((abs(c["prototype"][n]) for c in categories for n in names), default=0.0)
    table.add_column("what happened (truth)", no_wrap=True)
    for c in categories:
        cells = [str(c["id"]), str(c["count"])]
        for channel, names in channels:
            values = [c["prototype"][n] for n in names]
            row = bar_row(values, scales[channel])
            if len(names) == 1:
                row.append(f" {values[0]:+.2f}", style="dim")
            elif all(n.endswith(("_min", "_max")) for n in names):
                # a position channel: also the shift of the centre along each axis
                axes = dict.fromkeys(n.rsplit("_", 1)[0] for n in names)
                shift = [(c["prototype"][f"{a}_min"] + c["prototype"][f"{a}_max"]) / 2 for a in axes]
                row.append(" " + " ".join(f"{a}{v:+.2f}" for a, v in zip(axes, shift)), style="dim")
            cells.append(row)
        outcomes = c.get("outcomes", {})
        top = sorted(outcomes.items(), key=lambda kv: -kv[1])[:2]
        cells.append(", ".join(f"{k} {100 * v:.0f}%" for k, v in top))
        table.add_row(*cells)
    console.print(table)


def render_outcome_table(console, outcomes: dict) -> None:
    """``{behaviour: {shape: {label: count}}}`` as one table (its labels as the counts name them)."""
    labels = next((list(counts) for shapes in outcomes.values() for counts in shapes.values()), [])
    ot = Table(title="what physically happened (ground truth, never used to learn)", box=box.SIMPLE_HEAD)
    ot.add_column("behaviour", no_wrap=True)
    ot.add_column("shape", no_wrap=True, min_width=14)
    for label in labels:
        ot.add_column(label, justify="right", no_wrap=True)
    for behavior, shapes in outcomes.items():
        for shape, counts in shapes.items():
            ot.add_row(behavior, shape, *[str(counts.get(label, 0)) for label in labels])
    console.print(ot)


def render_metrics(console, behaviors: dict, title: str) -> None:
    """Per behaviour: accuracy, log loss, Brier, ECE, and baselines when present."""
    table = Table(title=title, box=box.SIMPLE_HEAD)
    for col in ("behaviour", "n test", "categories", "accuracy", "log loss", "Brier", "ECE"):
        table.add_column(col, justify="left" if col == "behaviour" else "right", no_wrap=True)
    with_base = any("baselines" in m for m in behaviors.values())
    if with_base:
        for col in ("majority", "k-NN", "forest"):
            table.add_column(col, justify="right")
    for name, m in behaviors.items():
        row = [name, str(m["n_test"]), str(m["n_categories"]), f"{100 * m['accuracy']:.1f}%", f"{m['log_loss']:.3f}",
               f"{m['brier']:.3f}", f"{m['ece']:.3f}"]
        if with_base:
            b = m.get("baselines", {})
            row += [f"{100 * b[k]:.1f}%" for k in ("majority", "knn", "random_forest")]
        table.add_row(*row)
    console.print(table)


def render_result_rates(console, rates: dict[str, dict[str, float]]) -> None:
    """Per behaviour, the share of each result the robot read off its own sensors."""
    if not rates:
        return
    names = list(next(iter(rates.values())))
    table = Table(title="the robot's own results per behaviour", box=box.SIMPLE_HEAD)
    table.add_column("behaviour", no_wrap=True)
    for n in names:
        table.add_column(n, justify="right")
    for b, r in rates.items():
        table.add_row(b, *[f"{100 * r[n]:.1f} %" for n in names])
    console.print(table)


def category_name(prototype: dict[str, float]) -> str:
    """A short description of an effect category from its prototype's numbers (never from
    ground truth): "vanished", "lifted 25 cm", "+12 cm x", "no change", or, for features
    that are not a table object's, the largest change ("min_range_0_2 -0.31")."""
    p = prototype
    if p.get("visibility", 0.0) <= -0.5:
        return "vanished"
    if all(k in p for k in ("x_min", "x_max", "y_min", "y_max", "z_min")):
        moves = {"x": (p["x_min"] + p["x_max"]) / 2, "y": (p["y_min"] + p["y_max"]) / 2}
        if p["z_min"] >= 0.05:
            return f"lifted {100 * p['z_min']:.0f} cm"
        axis, d = max(moves.items(), key=lambda kv: abs(kv[1]))
        return "no change" if abs(d) < 0.015 else f"{100 * d:+.0f} cm {axis}"
    if not p:
        return "?"
    name, value = max(p.items(), key=lambda kv: abs(kv[1]))
    return f"{name} {value:+.2f}"
