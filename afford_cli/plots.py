"""PNG figures for ``--plots DIR``: what an artefact holds, and how well a model predicts.

``afford inspect --plots`` draws, per behaviour, the prototype effect of each category
(thesis figures 8.4-8.7: one row per category, one panel per channel, signed bars) and
the relevance of the features, and, for artefacts that carry rows, the ground-truth
outcomes per behaviour and shape. ``afford evaluate --plots`` draws, per behaviour, the
confusion matrix and the reliability diagram of the predicted probabilities.

Every function takes the plain data the command already reports (``describe()`` of
``afford inspect``, ``evaluate_model()`` of ``afford evaluate``), so a figure shows the
numbers ``--json`` prints. matplotlib is imported inside the drawing functions: commands
that do not plot never import it. Figures are ``matplotlib.figure.Figure`` objects on an
Agg canvas rather than pyplot figures: nothing switches the process-wide backend and no
figure is kept in pyplot's registry, so there is nothing to close; each figure is dropped
once saved.
"""

from __future__ import annotations

import re
import os
from pathlib import Path
from typing import Annotated, Optional

import typer

from afford.errors import AffordError

__all__ = [
    "PlotDir", "plot_directory", "written", "artefact_plots", "evaluation_plots",
    "prototypes_figure", "relevance_figure", "outcomes_figure", "confusion_figure", "reliability_figure",
    "scene_figure", "check_plot_file", "PlotFile",
]

#: ``--plots DIR``, shared by inspect and evaluate.
PlotDir = Annotated[Optional[Path], typer.Option(
    "--plots", metavar="DIR", help="Also write PNG figures into DIR (created if missing).")]

#: ``--plot FILE.png``, shared by predict, plan and emulate.
PlotFile = Annotated[Optional[str], typer.Option(
    "--plot", metavar="FILE.png", help="Also draw what the robot saw (the range image, objects outlined and numbered) "
                                       "and the scene from above: where each object started, was predicted to end and "
                                       "(with --check/--execute) really ended.")]

DPI = 100
TOP_FEATURES = 20
_UP, _DOWN = "#2e8b3d", "#c8372d"              # the colours of the text reports' bar rows
_SELECTED, _OTHER = "#d9822b", "#9aa5b1"
_OUTCOME_COLOURS = {"fell": "#c8372d", "left-view": "#8e5ab5", "lifted": "#2f78c4",
                    "dragged": "#e3a33b", "no-change": "#b8bec6"}


# --------------------------------------------------------------------------- files

def plot_directory(path: str | Path) -> Path:
    """``path`` as a directory, created with its parents if missing; refused if it is a file."""
    d = Path(path)
    if d.exists() and not d.is_dir():
        raise AffordError(f"the plot directory {d} is a file; give --plots a directory (it is created if missing)")
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise AffordError(f"cannot create the plot directory {d} ({exc.strerror or exc})") from None
    return d


def written(paths: list[str]) -> str:
    """What a command tells stderr about its figures: one path a line (escaped: rich reads markup)."""
    from rich.markup import escape

    if not paths:
        return "no plots written: nothing to draw"
    return f"wrote {len(paths)} plot{'s' if len(paths) != 1 else ''}:" + "".join(f"\n  {escape(p)}" for p in paths)


def _file_name(stem: str, behavior: str | None = None) -> str:
    if behavior is None:
        return f"{stem}.png"
    return f"{stem}-{re.sub(r'[^A-Za-z0-9._-]+', '_', behavior)}.png"


def _new_figure(width: float, height: float, **kwargs):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained", **kwargs)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: Path) -> str:
    """Write the figure as PNG, atomically (a temporary file beside it, renamed into place)."""
    import io

    from afford.artifacts import write_artifact

    buf = io.BytesIO()
    fig.savefig(buf, dpi=DPI, format="png")
    write_artifact(str(path), buf.getvalue())
    return str(path)


def check_plot_file(path: str | None) -> None:
    """Fail before any work if ``--plot FILE`` cannot take a PNG."""
    from afford.artifacts import check_output

    if path is None:
        return
    if path == "-" or not path.lower().endswith(".png"):
        raise AffordError(f"--plot takes a file name ending in .png, not {path!r}")
    check_output(path)


# --------------------------------------------------------------------------- what a command draws

def artefact_plots(info: dict, directory: Path) -> list[str]:
    """Every figure ``afford inspect`` can draw from ``describe()``'s ``info``; the paths written."""
    paths = []
    features = info.get("features") or []
    for name, report in (info.get("behaviors") or {}).items():
        if report.get("categories") and "prototype" in report["categories"][0]:
            paths.append(prototypes_figure(directory / _file_name("prototypes", name), name,
                                           report["categories"], features, info.get("histogram_columns")))
        if report.get("relevance") or report.get("selected"):
            paths.append(relevance_figure(directory / _file_name("relevance", name), name,
                                          report.get("relevance"), report.get("selected", []), len(features)))
    outcomes = info.get("outcomes") or {}
    if any(n for shapes in outcomes.values() for labels in shapes.values() for n in labels.values()):
        paths.append(outcomes_figure(directory / _file_name("outcomes"), outcomes))
    return paths


def evaluation_plots(behaviors: dict, directory: Path) -> list[str]:
    """Confusion matrix and reliability diagram per behaviour from ``evaluate_model()``; the paths written."""
    paths = []
    for name, m in behaviors.items():
        paths.append(confusion_figure(directory / _file_name("confusion", name), name, m))
        paths.append(reliability_figure(directory / _file_name("reliability", name), name, m))
    return paths


# --------------------------------------------------------------------------- inspect

def _channels(features: list[dict], categories: list[dict]) -> list[tuple[str, list[str]]]:
    out: dict[str, list[str]] = {}
    for f in features:
        out.setdefault(f["channel"], []).append(f["name"])
    if not out and categories:  # no schema in the manifest: one panel of whatever the prototypes name
        out["features"] = list(categories[0]["prototype"])
    return list(out.items())


def _groups(names: list[str], columns: dict[str, int], histograms: list) -> list[tuple[str, int, int]]:
    """The schema's histograms among a channel's ``names``, as (label, start, stop) in that list.

    The label is what the histogram's first and last feature names share (``elevation``).
    """
    local = {columns[n]: i for i, n in enumerate(names) if n in columns}
    runs = []
    for a, b in histograms:
        if a in local and b - 1 in local:
            first, last = names[local[a]], names[local[b - 1]]
            label = os.path.commonprefix([first, last]).rstrip("_0123456789") or first
            runs.append((label, local[a], local[b - 1] + 1))
    return runs


def _dominant(outcomes: dict) -> str:
    if not outcomes:
        return "no ground truth"
    label, share = max(outcomes.items(), key=lambda kv: kv[1])
    return f"{label} {100 * share:.0f}%"


def prototypes_figure(path: Path, behavior: str, categories: list[dict], features: list[dict],
                      histograms: list | None = None) -> str:
    """One row of signed bar panels per effect category, one panel per channel (thesis fig. 8.4-8.7).

    Each row is labelled with the category id, its member count and the ground-truth outcome
    most of its members had; bars are the prototype effect (after - before), green up, red
    down, on one scale per channel.
    """
    channels = _channels(features, categories)
    columns = {f["name"]: i for i, f in enumerate(features)}
    n_rows, n_cols = len(categories), len(channels)
    widths = [max(0.9, len(names) ** 0.6) for _, names in channels]
    fig = _new_figure(1.6 + 1.0 * sum(widths), 1.3 + 0.72 * n_rows)
    axes = fig.subplots(n_rows, n_cols, squeeze=False, gridspec_kw={"width_ratios": widths})
    for j, (channel, names) in enumerate(channels):
        scale = max((abs(c["prototype"].get(n, 0.0)) for c in categories for n in names), default=0.0) or 1.0
        x = range(len(names))
        groups = _groups(names, columns, histograms or [])
        for i, cat in enumerate(categories):
            ax = axes[i, j]
            values = [cat["prototype"].get(n, 0.0) for n in names]
            ax.bar(x, values, width=0.8, color=[_UP if v >= 0 else _DOWN for v in values])
            ax.axhline(0.0, color="#444444", linewidth=0.6)
            ax.set_xlim(-0.6, len(names) - 0.4)
            ax.set_ylim(-1.1 * scale, 1.1 * scale)
            for side in ("top", "right"):
                ax.spines[side].set_visible(False)
            if len(names) > 8:
                for _, start, _stop in groups:
                    if start > 0:
                        ax.axvline(start - 0.5, color="#999999", linewidth=0.6, linestyle=":")
            # Only the bottom row carries ticks (one scale per column): ticks are most of the drawing time.
            if i < n_rows - 1:
                ax.set_xticks([])
                ax.set_yticks([])
                ax.spines["bottom"].set_visible(False)
            else:
                ax.tick_params(labelsize=7, length=2)
                ax.set_yticks([-scale, 0.0, scale], [f"{-scale:.2g}", "0", f"{scale:.2g}"])
                if 1 < len(names) <= 8:
                    ax.set_xticks(list(x), names, rotation=90)
                elif len(names) > 8 and groups and len(groups) < len(names):
                    ax.set_xticks([(a + b - 1) / 2 for _, a, b in groups], [g for g, _, _ in groups])
                else:
                    ax.set_xticks([])
            if i == 0:
                ax.set_title(f"{channel} ({len(names)})", fontsize=9)
            if j == 0:
                ax.set_ylabel(f"category {cat['id']}\nn = {cat['count']}\n{_dominant(cat.get('outcomes', {}))}",
                              rotation=0, ha="right", va="center", fontsize=8, labelpad=8)
    fig.align_ylabels(axes[:, 0])
    fig.suptitle(f"{behavior}: prototype effect (after - before) of its {n_rows} effect categories", fontsize=11)
    return _save(fig, path)


def relevance_figure(path: Path, behavior: str, scores: dict | None, selected: list[str], n_features: int = 0) -> str:
    """Horizontal bars of the top relevance scores, the selected features highlighted.

    A model artefact keeps which features were chosen but not their scores; then the chosen
    features are listed, in the order chosen, as bars of equal length.
    """
    from matplotlib.patches import Patch

    chosen = set(selected)
    if scores:
        ranked = sorted(scores.items(), key=lambda kv: -kv[1])[:TOP_FEATURES]
        names = [n for n, _ in ranked]
        values = [v for _, v in ranked]
        below = len(chosen - set(names))
        title = (f"{behavior}: feature relevance, top {len(names)} of {len(scores)}"
                 f" ({len(chosen)} selected" + (f", {below} of them not shown" if below else "") + ")")
        xlabel = "relevance score"
    else:
        names = list(selected)
        values = [1.0] * len(names)
        title = f"{behavior}: the {len(names)} features the model uses" + (f" (of {n_features})" if n_features else "")
        xlabel = "(the model stores which features were selected, not their scores)"
    fig = _new_figure(6.4 if scores else 4.8, 1.2 + 0.24 * max(len(names), 3))
    ax = fig.subplots()
    y = range(len(names))
    ax.barh(list(y), values, height=0.7, color=[_SELECTED if n in chosen else _OTHER for n in names])
    ax.set_yticks(list(y), names, fontsize=8)
    ax.invert_yaxis()
    ax.axvline(0.0, color="#444444", linewidth=0.6)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.tick_params(axis="x", labelsize=8)
    if not scores:
        ax.set_xticks([])
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    if scores:
        ax.legend(handles=[Patch(color=_SELECTED, label="selected"), Patch(color=_OTHER, label="not selected")],
                  fontsize=8, loc="best", frameon=False)
    ax.set_title(title, fontsize=10)
    return _save(fig, path)


def outcomes_figure(path: Path, outcomes: dict) -> str:
    """Stacked bars of ground-truth outcome counts, one panel per behaviour, one bar per shape."""
    from matplotlib.patches import Patch

    behaviours = list(outcomes)
    labels = list(dict.fromkeys(l for shapes in outcomes.values() for counts in shapes.values() for l in counts))
    colours = {l: _OUTCOME_COLOURS.get(l, f"C{k}") for k, l in enumerate(labels)}
    fig = _new_figure(1.8 + 2.6 * len(behaviours), 4.0)
    axes = fig.subplots(1, len(behaviours), squeeze=False, sharey=True)[0]
    for ax, name in zip(axes, behaviours):
        shapes = list(outcomes[name])
        bottom = [0] * len(shapes)
        for label in labels:
            counts = [outcomes[name][s].get(label, 0) for s in shapes]
            ax.bar(range(len(shapes)), counts, bottom=bottom, width=0.7, color=colours[label])
            bottom = [b + c for b, c in zip(bottom, counts)]
        ax.set_xticks(range(len(shapes)), shapes, rotation=35, ha="right", fontsize=8)
        ax.tick_params(axis="y", labelsize=8)
        ax.set_title(name, fontsize=10)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    axes[0].set_ylabel("interactions", fontsize=9)
    # legend top to bottom as the stacks read: the last label is on top
    fig.legend(handles=[Patch(color=colours[l], label=l) for l in reversed(labels)], loc="outside right center",
               fontsize=8, frameon=False, title="outcome", title_fontsize=8)
    fig.suptitle("what physically happened, per behaviour and shape (ground truth, never used to learn)", fontsize=11)
    return _save(fig, path)


# --------------------------------------------------------------------------- evaluate

def confusion_figure(path: Path, behavior: str, metrics: dict) -> str:
    """The confusion matrix, rows true and columns predicted, coloured by row share, annotated with counts."""
    import numpy as np

    matrix = np.asarray(metrics["confusion_matrix"], dtype=int)
    names = metrics.get("label_names") or {}
    labels = [f"{v}: {names[str(v)]}" if str(v) in names else str(v) for v in metrics["labels"]]
    n = len(labels)
    rows = matrix.sum(axis=1, keepdims=True)
    share = np.divide(matrix, rows, out=np.zeros(matrix.shape), where=rows > 0)
    side = 2.4 + 0.42 * n
    fig = _new_figure(side + 1.0, side)
    ax = fig.subplots()
    image = ax.imshow(share, cmap="Blues", vmin=0.0, vmax=1.0)
    fontsize = 9 if n <= 10 else 7 if n <= 18 else 5
    for i in range(n):
        for j in range(n):
            if matrix[i, j]:
                ax.text(j, i, str(matrix[i, j]), ha="center", va="center", fontsize=fontsize,
                        color="white" if share[i, j] > 0.55 else "#1a1a1a")
    ax.set_xticks(range(n), labels, fontsize=fontsize, rotation=35 if names else 0, ha="right" if names else "center")
    ax.set_yticks(range(n), labels, fontsize=fontsize)
    ax.set_xlabel("predicted category", fontsize=9)
    ax.set_ylabel("true category", fontsize=9)
    bar = fig.colorbar(image, ax=ax, shrink=0.8)
    bar.set_label("share of the true category's rows", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    n_test = metrics.get("n_test", int(matrix.sum()))
    accuracy = metrics.get("accuracy", float(np.trace(matrix) / max(matrix.sum(), 1)))
    ax.set_title(f"{behavior}: confusion on {n_test} held-out interactions\naccuracy {100 * accuracy:.1f}%",
                 fontsize=10)
    return _save(fig, path)


def reliability_figure(path: Path, behavior: str, metrics: dict, n_bins: int = 10) -> str:
    """Mean top-class confidence against observed accuracy per bin, over the bins' counts.

    ``metrics["reliability"]`` holds the non-empty bins of :func:`learn.evaluate.reliability_bins`
    (equal width, ``n_bins`` of them); a bin's place follows from its mean confidence, which
    lies inside it.
    """
    bins = metrics.get("reliability", [])
    width = 1.0 / n_bins
    fig = _new_figure(5.2, 5.6)
    top, bottom = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    top.plot([0, 1], [0, 1], linestyle="--", color="#888888", linewidth=1, label="perfectly calibrated")
    conf = [b["confidence"] for b in bins]
    acc = [b["accuracy"] for b in bins]
    for c, a in zip(conf, acc):
        top.plot([c, c], [c, a], color=_DOWN, linewidth=1.5, alpha=0.7)
    top.plot(conf, acc, marker="o", color="#2f78c4", linewidth=1.2, label="model")
    top.plot([], [], color=_DOWN, linewidth=1.5, alpha=0.7, label="gap (weighted mean = ECE)")
    top.set_xlim(0, 1)
    top.set_ylim(0, 1.02)
    top.set_ylabel("observed accuracy", fontsize=9)
    top.legend(fontsize=8, loc="best", frameon=False)
    top.grid(alpha=0.3)
    starts = [min(int(c * n_bins), n_bins - 1) * width for c in conf]
    counts = [b["count"] for b in bins]
    bottom.bar(starts, counts, width=width * 0.92, align="edge", color=_OTHER)
    for s, k in zip(starts, counts):
        bottom.text(s + width / 2, k, str(k), ha="center", va="bottom", fontsize=7)
    bottom.set_ylim(0, 1.25 * max(counts, default=1))
    bottom.set_ylabel("count", fontsize=9)
    bottom.set_xlabel("mean predicted probability of the top category", fontsize=9)
    for ax in (top, bottom):
        ax.tick_params(labelsize=8)
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    n = metrics.get("n_test", sum(counts))
    ece = metrics.get("ece")
    head = f"ECE {ece:.3f}, " if ece is not None else ""
    top.set_title(f"{behavior}: reliability of the predicted probabilities\n{head}{n} held-out interactions",
                  fontsize=10)
    return _save(fig, path)


# --------------------------------------------------------------------------- what the robot saw and did

_OBJECT_COLOURS = ("#2f78c4", "#d9822b", "#2e8b3d", "#8e5ab5", "#c8372d", "#6b7b8c")


def _footprint_columns(schema) -> tuple[int, int, int, int] | None:
    names = ("x_min", "x_max", "y_min", "y_max")
    if not all(n in schema.names for n in names):
        return None
    return tuple(schema.index(n) for n in names)  # type: ignore[return-value]


def scene_figure(path: Path, schema, *, view=None, panels=(), results=None, title: str = "") -> str:
    """What the robot saw, and what it expected and got, in one PNG.

    ``view``: ``(ranges, boxes)`` of the start (a scene world's ``last_view``): the range
    image, each detected object outlined and numbered. ``panels``: top views of the scene in
    the robot's frame (metres), each ``{"title", "start", "predicted", "actual", "shown"}``
    with (k, d) entity arrays (any but ``start`` may be None): every object's footprint
    where it started (solid), where the model predicted it would end (dashed), where it
    really ended (filled), and where a shown scene has its objects (dotted). An object that
    vanished is a cross at its last seen place. ``results``: for a model of given results
    (chapter 5), ``[(behaviour, P(success), observed result or None)]`` as bars.
    """
    import numpy as np
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch, Rectangle

    cols = _footprint_columns(schema)
    tops = list(panels) if cols is not None else []
    n = (view is not None) + len(tops) + (results is not None)
    if n == 0:
        raise AffordError("there is nothing to draw for this scene")
    per_row = min(n, 3)
    rows = -(-n // per_row)
    fig = _new_figure(5.6 * per_row, 4.2 * rows + (0.6 if title else 0))
    axes = list(np.atleast_1d(fig.subplots(rows, per_row)).ravel())
    for ax in axes[n:]:
        ax.set_visible(False)
    k = 0
    if view is not None:
        ranges, boxes = view
        ax = axes[k]
        k += 1
        shown = np.where(np.isfinite(ranges), ranges, np.nan)
        image = ax.imshow(shown, cmap="viridis_r", interpolation="nearest")
        bar = fig.colorbar(image, ax=ax, shrink=0.8)
        bar.set_label("range (m); blank: nothing hit", fontsize=8)
        for i, (r0, c0, r1, c1) in enumerate(boxes):
            colour = _OBJECT_COLOURS[i % len(_OBJECT_COLOURS)]
            ax.add_patch(Rectangle((c0 - 0.5, r0 - 0.5), c1 - c0, r1 - r0, fill=False, lw=1.8, ec=colour))
            ax.text(c0, r0 - 1.5, str(i), color=colour, fontsize=10, fontweight="bold", va="bottom")
        ax.set_xlabel("image column (ray)", fontsize=9)
        ax.set_ylabel("image row (ray)", fontsize=9)
        ax.set_title(f"range image at the start: {len(boxes)} object{'s' * (len(boxes) != 1)} detected"
                     if boxes or cols is not None else "range image at the start", fontsize=10)
    vis = schema.visibility_index
    for panel in tops:
        ax = axes[k]
        k += 1
        x0, x1, y0, y1 = cols
        extent = []

        def draw(f, colour, style, label_number=None):
            seen = vis is None or f[vis] >= 0.5
            cx, cy = (f[x0] + f[x1]) / 2, (f[y0] + f[y1]) / 2
            extent.append((f[x0], f[x1], f[y0], f[y1]))
            if not seen:  # predicted to vanish: a thin cross; vanished: a bold one
                if style == "actual":
                    ax.plot([cx], [cy], marker="X", ms=12, color=colour, alpha=0.6, ls="")
                else:
                    ax.plot([cx], [cy], marker="x", ms=10, mew=1.6, color=colour, ls="")
            elif style == "actual":
                ax.add_patch(Rectangle((f[x0], f[y0]), f[x1] - f[x0], f[y1] - f[y0], fc=colour, ec=colour, alpha=0.3))
            else:
                ax.add_patch(Rectangle((f[x0], f[y0]), f[x1] - f[x0], f[y1] - f[y0], fill=False, ec=colour,
                                       lw={"start": 1.8, "predicted": 1.6, "shown": 1.4}[style],
                                       ls={"start": "-", "predicted": "--", "shown": ":"}[style]))
            if label_number is not None:
                ax.text(cx, cy, str(label_number), color=colour, fontsize=10, fontweight="bold", ha="center", va="center")

        start = np.asarray(panel["start"])
        for i, f in enumerate(start):
            colour = _OBJECT_COLOURS[i % len(_OBJECT_COLOURS)]
            draw(f, colour, "start", i)
            for key in ("predicted", "actual"):
                if panel.get(key) is not None and i < len(panel[key]):
                    draw(np.asarray(panel[key])[i], colour, key)
        for f in (panel.get("shown") if panel.get("shown") is not None else []):
            draw(np.asarray(f), "#1a1a1a", "shown")
        if extent:
            e = np.asarray(extent)
            pad = 0.08
            ax.set_xlim(e[:, 0].min() - pad, e[:, 1].max() + pad)
            ax.set_ylim(e[:, 2].min() - pad, e[:, 3].max() + pad)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(alpha=0.3)
        ax.set_xlabel("x, ahead of the robot (m)", fontsize=9)
        ax.set_ylabel("y, to its left (m)", fontsize=9)
        ax.set_title(panel.get("title", ""), fontsize=10)
        handles = [Line2D([], [], color="#444", lw=1.8, label="start (numbered)")]
        if panel.get("predicted") is not None:
            handles.append(Line2D([], [], color="#444", lw=1.6, ls="--", label="predicted end"))
        if panel.get("actual") is not None:
            handles.append(Patch(fc="#444", alpha=0.3, label="actual end"))
        if panel.get("shown") is not None:
            handles.append(Line2D([], [], color="#1a1a1a", lw=1.4, ls=":", label="shown (the goal)"))
        if panel.get("predicted") is not None:
            handles.append(Line2D([], [], color="#444", marker="x", ls="", ms=8, label="predicted to vanish"))
        if panel.get("actual") is not None:
            handles.append(Line2D([], [], color="#444", marker="X", ls="", ms=8, alpha=0.6, label="vanished"))
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    if results is not None:
        ax = axes[k]
        names = [r[0] for r in results]
        p = [r[1] for r in results]
        ax.barh(range(len(names)), p, color=_SELECTED)
        for i, (_, q, seen) in enumerate(results):
            ax.text(min(q, 0.98), i, f" {q:.2f}" + (f"  (ran: {seen})" if seen is not None else ""), va="center",
                    fontsize=8, ha="right" if q > 0.6 else "left")
        ax.set_yticks(range(len(names)), names, fontsize=8)
        ax.set_xlim(0, 1)
        ax.invert_yaxis()
        ax.set_xlabel("predicted probability of success", fontsize=9)
        ax.set_title("what each behaviour would do", fontsize=10)
    if title:
        import textwrap

        fig.suptitle(textwrap.fill(title, 60 * per_row), fontsize=10)
    return _save(fig, path)


def range_images_figure(path: Path, starts: list[dict]) -> str:
    """Range images of episode starts (``scenes_io.episode_starts``), each detected object
    outlined and numbered: what the robot saw before its first behaviour."""
    import numpy as np
    from matplotlib.patches import Rectangle

    n = len(starts)
    per_row = min(n, 3)
    rows = -(-n // per_row)
    fig = _new_figure(4.4 * per_row, 3.6 * rows)
    axes = list(np.atleast_1d(fig.subplots(rows, per_row)).ravel())
    for ax in axes[n:]:
        ax.set_visible(False)
    image = None
    for ax, s in zip(axes, starts):
        ranges = np.where(np.isfinite(s["ranges"]), s["ranges"], np.nan)
        image = ax.imshow(ranges, cmap="viridis_r", interpolation="nearest")
        for i, (r0, c0, r1, c1) in enumerate(s["boxes"]):
            colour = _OBJECT_COLOURS[i % len(_OBJECT_COLOURS)]
            ax.add_patch(Rectangle((c0 - 0.5, r0 - 0.5), c1 - c0, r1 - r0, fill=False, lw=1.6, ec=colour))
            ax.text(c0, r0 - 1.5, str(i), color=colour, fontsize=9, fontweight="bold", va="bottom")
        found = f": {len(s['boxes'])} object{'s' * (len(s['boxes']) != 1)} detected" if s["boxes"] else ""
        note = "" if s["matches_recording"] else "\n(re-simulated look differs from the recording)"
        ax.set_title(f"episode {s['episode']}{found}{note}", fontsize=9)
        ax.set_xlabel("image column (ray)", fontsize=8)
        ax.set_ylabel("image row (ray)", fontsize=8)
        ax.tick_params(labelsize=7)
    if image is not None:
        bar = fig.colorbar(image, ax=axes[:n], shrink=0.7)
        bar.set_label("range (m); blank: nothing hit", fontsize=8)
    fig.suptitle("what the robot saw at the start of its first episodes (re-simulated from the seed)", fontsize=10)
    return _save(fig, path)


def curve_figure(path: Path, curve: list[dict], strategy: str = "") -> str:
    """Test accuracy against interactions tried, one line per behaviour (``explore --strategy --test``)."""
    fig = _new_figure(7.0, 4.4)
    ax = fig.subplots()
    by: dict[str, list[dict]] = {}
    for c in curve:
        by.setdefault(c["behavior"], []).append(c)
    for name, points in by.items():
        ax.plot([p["interactions"] for p in points], [100 * p["accuracy"] for p in points], marker=".", lw=1.2, label=name)
    ax.set_xlabel("interactions tried", fontsize=9)
    ax.set_ylabel("held-out accuracy (%)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(f"learning as it explores{f' ({strategy})' if strategy else ''}", fontsize=10)
    return _save(fig, path)
