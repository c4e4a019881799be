"""Feature schemas: the names, channels and meaning of the numbers a robot perceives.

Every feature vector afford stores travels with its :class:`FeatureSchema`, so that
reports can name features, goals can refer to them (``0:z_min=0.95``) and a model can
refuse data of another schema. The schema is also the one place that says what a feature
*means* to the rest of afford:

- which feature, if any, is the entity's visibility (none: the entity is always visible,
  as the whole environment of chapter 5 is);
- which runs of features form a normalised histogram (a normal-angle histogram of chapter
  8, or of every grid cell of chapter 5);
- per channel, its unit, the default tolerance of a goal on it and the scale the search
  heuristic measures it in;
- named roles a consumer may ask for (``height``: the feature that rises when the hand
  holds the object).

Goals, the forward model, search, monitoring, ReliefF's grouping, reports and plots ask
these questions of the schema; none of them finds a meaning by column position or by a
name pattern.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from afford.features.errors import DataError, NameNotFound

__all__ = ["Channel", "FeatureSchema", "object_schema", "AXES", "N_ANGLE_BINS"]

#: Names of the three axes of the robot frame, in the thesis's words: frontal (x),
#: lateral (y, left positive) and vertical (z).
AXES = ("x", "y", "z")

#: Bins of each normal-angle histogram (thesis 8.3.1: 36 shape features = 2 x 18).
N_ANGLE_BINS = 18


@dataclass(frozen=True)
class Channel:
    """What one channel's numbers are.

    Parameters
    ----------
    name : str
    unit : str
        ``m``, ``deg``, ``px``, ``fraction``, ... (``""``: a plain number).
    tolerance : float
        Default tolerance of a goal on a feature of this channel (``=value~tolerance``).
    scale : float
        How far one unit of this channel counts in the search heuristic.
    """

    name: str
    unit: str = ""
    tolerance: float = 0.05
    scale: float = 1.0

    def to_json(self) -> dict:
        return {"unit": self.unit, "tolerance": self.tolerance, "scale": self.scale}


@dataclass(frozen=True)
class FeatureSchema:
    """Named features, each in one channel, with what they mean.

    Parameters
    ----------
    names : tuple of str
        One unique name per feature, in vector order.
    channels : tuple of str
        The channel of each feature (``visibility``, ``position``, ``shape``, ...).
    visibility : str or None
        The feature that says whether the entity is seen (1) or gone (0); None: always seen.
    histograms : tuple of (start, stop)
        Column ranges that each hold one normalised histogram.
    channel_info : tuple of Channel
        Unit, tolerance and scale per channel (a channel not listed gets ``Channel(name)``).
    roles : tuple of (role, feature name)
        Named roles, e.g. ``("height", "z_min")``.
    """

    names: tuple[str, ...]
    channels: tuple[str, ...]
    visibility: str | None = None
    histograms: tuple[tuple[int, int], ...] = ()
    channel_info: tuple[Channel, ...] = ()
    roles: tuple[tuple[str, str], ...] = field(default=())

    def __post_init__(self) -> None:
        if len(self.names) != len(self.channels):
            raise DataError("a schema needs one channel per feature name")
        if len(set(self.names)) != len(self.names):
            raise DataError("feature names in a schema must be unique")
        if self.visibility is not None and self.visibility not in self.names:
            raise DataError(f"the visibility feature {self.visibility!r} is not among the schema's features")
        for a, b in self.histograms:
            if not (isinstance(a, int) and isinstance(b, int) and 0 <= a < b <= len(self.names)):
                raise DataError(f"histogram columns {a}..{b} lie outside the schema's {len(self.names)} features")
        for role, name in self.roles:
            if name not in self.names:
                raise DataError(f"the {role} feature {name!r} is not among the schema's features")
        # one order for equal meanings (files store these as JSON objects, keys sorted)
        order = {ch: i for i, ch in enumerate(dict.fromkeys(self.channels))}
        object.__setattr__(self, "channel_info", tuple(sorted(self.channel_info, key=lambda c: order.get(c.name, len(order)))))
        object.__setattr__(self, "roles", tuple(sorted(self.roles)))
        object.__setattr__(self, "histograms", tuple(sorted((int(a), int(b)) for a, b in self.histograms)))

    def __len__(self) -> int:
        return len(self.names)

    # -- channels --------------------------------------------------------------------------
    @cached_property
    def channel_names(self) -> tuple[str, ...]:
        """Channels in order of first appearance."""
        return tuple(dict.fromkeys(self.channels))

    @cached_property
    def _channel_index(self) -> dict[str, np.ndarray]:
        arr = np.asarray(self.channels)
        return {ch: np.flatnonzero(arr == ch) for ch in self.channel_names}

    def channel_indices(self, channel: str) -> np.ndarray:
        """Column indices of one channel's features."""
        try:
            return self._channel_index[channel]
        except KeyError:
            raise NameNotFound(f"no channel named {channel!r}; the schema has {', '.join(self.channel_names)}") from None

    def channel(self, name: str) -> Channel:
        """Unit, tolerance and scale of channel ``name``."""
        for c in self.channel_info:
            if c.name == name:
                return c
        return Channel(name)

    def channel_groups(self) -> list[tuple[str, np.ndarray]]:
        """(channel, column indices) in order of first appearance."""
        return [(ch, self._channel_index[ch]) for ch in self.channel_names]

    @cached_property
    def tolerances(self) -> np.ndarray:
        """Each feature's channel's default goal tolerance."""
        return np.array([self.channel(c).tolerance for c in self.channels], dtype=float)

    # -- meaning ---------------------------------------------------------------------------
    @cached_property
    def visibility_index(self) -> int | None:
        """Column of the visibility feature, or None (always visible)."""
        return None if self.visibility is None else self.names.index(self.visibility)

    def visible(self, states: np.ndarray) -> np.ndarray:
        """Which rows of ``states`` (..., d) are seen; all of them without a visibility feature."""
        states = np.asarray(states)
        if self.visibility_index is None:
            return np.ones(states.shape[:-1], dtype=bool)
        return states[..., self.visibility_index] >= 0.5

    @cached_property
    def histogram_slices(self) -> list[slice]:
        return [slice(a, b) for a, b in self.histograms]

    @cached_property
    def in_histogram(self) -> np.ndarray:
        mask = np.zeros(len(self.names), dtype=bool)
        for a, b in self.histograms:
            mask[a:b] = True
        return mask

    @cached_property
    def geometry(self) -> np.ndarray:
        """Columns that are neither visibility nor histogram bins: the entity's measurements
        (where it is, how far, how big), compared by distance in their own units."""
        mask = ~self.in_histogram
        if self.visibility_index is not None:
            mask[self.visibility_index] = False
        return np.flatnonzero(mask)

    def role(self, name: str) -> int | None:
        """Column of the feature that plays ``name`` (e.g. ``height``), or None."""
        for role, feature in self.roles:
            if role == name:
                return self.names.index(feature)
        return None

    def groups(self) -> np.ndarray:
        """A group label per feature: each histogram is one group, every other feature its own.

        The wrappers of feature selection move a group as one unit (the thesis's Schemata
        search treated each normal-angle histogram so).
        """
        labels = np.full(len(self.names), -1, dtype=int)
        for g, (a, b) in enumerate(self.histograms):
            labels[a:b] = g
        rest = labels < 0
        labels[rest] = len(self.histograms) + np.arange(int(rest.sum()))
        _, first = np.unique(labels, return_index=True)
        renumber = {int(labels[i]): n for n, i in enumerate(sorted(first))}
        return np.array([renumber[int(v)] for v in labels], dtype=int)

    def index(self, name: str) -> int:
        """Column index of a feature, with a clear error for an unknown name."""
        try:
            return self._name_index[name]
        except KeyError:
            raise NameNotFound(f"no feature named {name!r} in this schema") from None

    @cached_property
    def _name_index(self) -> dict[str, int]:
        return {n: i for i, n in enumerate(self.names)}

    # -- files -----------------------------------------------------------------------------
    def to_json(self) -> dict:
        return {
            "features": [{"name": n, "channel": c} for n, c in zip(self.names, self.channels)],
            "visibility": self.visibility,
            "histograms": [[a, b] for a, b in self.histograms],
            "channels": {c.name: c.to_json() for c in self.channel_info},
            "roles": {role: name for role, name in self.roles},
        }

    @classmethod
    def from_json(cls, doc) -> "FeatureSchema":
        """A schema from :meth:`to_json`'s output, or from the plain feature list of
        artefacts written before schemas carried meaning (the chapter 8 object vector is
        recognised by its names and gets its meaning back)."""
        if isinstance(doc, list):
            names = tuple(str(i["name"]) for i in doc)
            channels = tuple(str(i["channel"]) for i in doc)
            legacy = object_schema()
            if names == legacy.names and channels == legacy.channels:
                return legacy
            return cls(names, channels)
        if not isinstance(doc, dict) or not isinstance(doc.get("features"), list):
            raise DataError("the feature schema is malformed")
        items = doc["features"]
        info = doc.get("channels") or {}
        return cls(
            tuple(str(i["name"]) for i in items),
            tuple(str(i["channel"]) for i in items),
            visibility=doc.get("visibility"),
            histograms=tuple((int(a), int(b)) for a, b in doc.get("histograms") or []),
            channel_info=tuple(Channel(str(name), str(v.get("unit", "")), float(v.get("tolerance", 0.05)),
                                       float(v.get("scale", 1.0))) for name, v in info.items()),
            roles=tuple((str(r), str(n)) for r, n in (doc.get("roles") or {}).items()),
        )


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
    first = len(names) - 2 * N_ANGLE_BINS
    return FeatureSchema(
        tuple(names), tuple(channels), visibility="visibility",
        histograms=((first, first + N_ANGLE_BINS), (first + N_ANGLE_BINS, first + 2 * N_ANGLE_BINS)),
        channel_info=(Channel("visibility", "", 0.5, 1.0), Channel("position", "m", 0.05, 0.1),
                      Channel("shape", "fraction", 0.1, 0.5)),
        roles=(("height", "z_min"),),
    )
