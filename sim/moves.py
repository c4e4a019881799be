"""The mobile robot's behaviours and what every traverse scene shares (thesis chapter 5).

Seven behaviours without parameters and without a target (``target = None``): rotate in
place by -60, -40, -20, 0, 20, 40 or 60 degrees (left positive), then drive 70 cm
(thesis 5.3.2). The label is the robot's own reading of how it went
(:class:`sim.robots.mobile.Odometry`: heading within 5 degrees of the rotation, displacement
65-75 cm), never ground truth and never a look at what lies in its way.

The entity is the whole environment as the robot's 3D scanner sees it from the start, as
grid features (``features.grid``: 5 x 5 cells in 4 overlapping layers, 39 features each,
3900 in all; chapter 6 uses 30 x 30 in one layer). The scene loop is Algorithm 1: scan
once, then every behaviour from the same start in a freshly built world.

:class:`TraverseScene` is the base of the four traverse scenes; each scene file supplies
its name, task sheet and sampler (``sim.traverse.sample_*``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace

import numpy as np

from afford.features.errors import DataError
from afford.features.grid import GridSpec, grid_features, grid_schema
from afford.sim.behaviors import Behavior, Execution
from afford.sim.traverse import ROTATIONS, TraverseConfig, TraverseLayout, TraverseLayoutFiles, TraverseWorld, check_layout

__all__ = ["MOVES", "RESULTS", "TraverseScene", "TraverseSceneConfig", "ScanningWorld", "move_name"]

#: The robot's own readings, in the order results store them.
RESULTS = ("fail", "success")

#: Drive length of every move behaviour, metres.
DRIVE = 0.70


def move_name(rotate: float) -> str:
    """``go-forward``, ``turn-left-20``, ``turn-right-60``, ..."""
    if rotate == 0:
        return "go-forward"
    return f"turn-{'left' if rotate > 0 else 'right'}-{abs(rotate):g}"


def _move(rotate: float):
    def controller(world: "ScanningWorld", target, alpha) -> Execution:
        odometry = world.move(rotate, DRIVE)
        return Execution(True, result=int(odometry.success), reading=odometry.to_dict())

    return controller


MOVES: tuple[Behavior, ...] = tuple(
    Behavior(move_name(r), (), _move(r), f"rotate {r:+g} deg in place, then drive {100 * DRIVE:.0f} cm", target=None)
    for r in sorted(ROTATIONS, key=lambda r: (abs(r), -r))
)


class ScanningWorld:
    """One traverse world as the scene loop drives it: scan (grid features), move, truth."""

    def __init__(self, layout: TraverseLayout, rng: np.random.Generator, config: TraverseConfig, grid: GridSpec):
        self.world = TraverseWorld(layout, rng, config)
        self.layout = layout
        self.grid = grid
        self.odometry = None

    def perceive(self) -> np.ndarray:
        """The environment as one entity: (1, d) grid features of a fresh scan."""
        self.last_image = self.world.scan()
        return grid_features(self.last_image, self.grid).astype(np.float64)[None, :]

    def last_view(self, image=None) -> tuple[np.ndarray, list] | None:
        """The last scan's (or ``image``'s) ranges (rows, cols; inf where nothing was hit), and
        no object boxes: this robot perceives the whole environment, not objects."""
        image = getattr(self, "last_image", None) if image is None else image
        return None if image is None else (np.asarray(image.ranges), [])

    def move(self, rotate: float, drive: float):
        self.odometry = self.world.move(rotate, drive)
        return self.odometry

    def truth_row(self) -> dict:
        """What physically happened in the last behaviour (for reports), and the readings behind the result."""
        t = self.world.truth()
        s, e = t["start"], t["end"]
        row = {
            "pose_before": np.array([s["x"], s["y"], s["yaw"]], dtype=np.float32),
            "pose_after": np.array([e["x"], e["y"], e["yaw"]], dtype=np.float32),
            "fell": bool(t["fell"]),
            "contact": bool(t["contact"]),
            "tilt_deg": np.float32(t["tilt_deg"]),
            "n_objects": np.int16(len(self.layout.items)),
        }
        if self.odometry is not None:
            row["odometry_heading_change_deg"] = np.float32(self.odometry.heading_change_deg)
            row["odometry_displacement_m"] = np.float32(self.odometry.displacement_m)
        return row


@dataclass(frozen=True)
class TraverseSceneConfig:
    """The traverse worlds' settings and the robot's perception."""

    world: TraverseConfig = field(default_factory=TraverseConfig)
    """Physics, robot and scanner."""
    grid: GridSpec = field(default_factory=GridSpec)
    """Grid features of the range image (cells, overlapping layers)."""


class TraverseScene(TraverseLayoutFiles):
    """What the traverse scenes share: the robot, its scanner and grid perception, its seven moves.

    A subclass sets ``name``, ``summary`` and :meth:`sample`.
    """

    behaviors = MOVES
    labels = "given"
    results = RESULTS
    outcomes: tuple[str, ...] = ()
    loop = "scan"
    options = {
        "grid": "Grid cells per side of the range image (5 in chapter 5, 30 in chapter 6).",
        "layers": "Overlapping grid layers (4 in chapter 5, 1 in chapter 6).",
    }
    sample_options: tuple[str, ...] = ()
    name = "traverse"
    summary = ""

    def __init__(self, config: TraverseSceneConfig | None = None):
        self.config = config or TraverseSceneConfig()

    @property
    def schema(self):
        return grid_schema(self.config.grid)

    #: How ``afford train`` learns from these scenes unless told otherwise: the thesis's
    #: linear SVM (5.4), reported with 5-fold cross-validation (5.6.1).
    learner = {"kernel": "linear", "folds": 5}

    def describe(self) -> dict:
        d = asdict(self.config)
        d["name"] = self.name
        d["learner"] = dict(self.learner)
        return d

    def options_from(self, description: dict) -> dict:
        g = description.get("grid", {})
        return {"grid": g.get("cells", self.config.grid.cells), "layers": g.get("layers", self.config.grid.layers)}

    def configure(self, grid: int | None = None, layers: int | None = None) -> "TraverseScene":
        g = self.config.grid
        spec = replace(g, cells=g.cells if grid is None else int(grid), layers=g.layers if layers is None else int(layers))
        return type(self)(replace(self.config, grid=spec))

    def sample(self, rng: np.random.Generator) -> TraverseLayout:  # pragma: no cover - each scene has its own
        raise NotImplementedError

    def check_layout(self, layout: TraverseLayout) -> None:
        self._check_kind(layout)
        check_layout(layout, self.config.world.robot)

    def build(self, layout: TraverseLayout, rng: np.random.Generator) -> ScanningWorld:
        """A fresh world (one per behaviour: rebuilding is Algorithm 1's reset)."""
        return ScanningWorld(layout, rng, self.config.world, self.config.grid)
