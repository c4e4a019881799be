"""Feature schemas: the names and channels of the numbers a robot perceives.

Every feature vector afford stores travels with its :class:`FeatureSchema`, so that
reports can name features, goals can refer to them (``0:z_min=0.95``) and a model can
refuse data of another schema.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["FeatureSchema", "object_schema", "AXES", "N_ANGLE_BINS"]

#: Names of the three axes of the robot frame, in the thesis's words: frontal (x),
#: lateral (y, left positive) and vertical (z).
AXES = ("x", "y", "z")

#: Bins of each normal-angle histogram (thesis 8.3.1: 36 shape features = 2 x 18).
N_ANGLE_BINS = 18


@dataclass(frozen=True)
class FeatureSchema:
    """Named features, each in one channel.

    Parameters
    ----------
    names : tuple of str
        One unique name per feature, in vector order.
    channels : tuple of str
        The channel of each feature (``visibility``, ``position``, ``shape``, ...).
    """

    names: tuple[str, ...]
    channels: tuple[str, ...]

    def __post_init__(self) -> None:
        if len(self.names) != len(self.channels):
            raise ValueError("a schema needs one channel per feature name")
        if len(set(self.names)) != len(self.names):
            raise ValueError("feature names in a schema must be unique")

    def __len__(self) -> int:
        return len(self.names)

    @property
    def channel_names(self) -> tuple[str, ...]:
        """Channels in order of first appearance."""
        return tuple(dict.fromkeys(self.channels))

    def channel_indices(self, channel: str) -> np.ndarray:
        """Column indices of one channel's features."""
        idx = np.flatnonzero(np.asarray(self.channels) == channel)
        if idx.size == 0:
            raise KeyError(f"no channel named {channel!r}; the schema has {', '.join(self.channel_names)}")
        return idx

    def index(self, name: str) -> int:
        """Column index of a feature, with a clear error for an unknown name."""
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no feature named {name!r} in this schema") from None

    def to_json(self) -> list[dict[str, str]]:
        return [{"name": n, "channel": c} for n, c in zip(self.names, self.channels)]

    @classmethod
    def from_json(cls, items: list[dict[str, str]]) -> "FeatureSchema":
        return cls(tuple(str(i["name"]) for i in items), tuple(str(i["channel"]) for i in items))


def object_schema() -> FeatureSchema:
    """The 43-feature object vector of thesis chapter 8.3.1.

    ``visibility`` (1), ``position`` (6: min and max of the object's points along x, y, z,
    in metres in the robot frame) and ``shape`` (36: normalised histograms of the
    surface-normal elevation angle and azimuth angle, 18 bins each).
    """
    names = ["visibility"]
    channels = ["visibility"]
    for axis in AXES:
        names += [f"{axis}_min", f"{axis}_max"]
        channels += ["position", "position"]
    for angle in ("elevation", "azimuth"):
        names += [f"{angle}_{i:02d}" for i in range(N_ANGLE_BINS)]
        channels += ["shape"] * N_ANGLE_BINS
    return FeatureSchema(tuple(names), tuple(channels))
