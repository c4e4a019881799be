"""Grid features of a whole range image (thesis chapter 5.3.1).

In chapter 5 the mobile robot does not detect objects: it splits its whole (down-scaled,
360 x 360) range image into a grid of squares and describes every square by

* 3 distance features: the ``min``, ``max`` and ``mean`` range of its pixels (metres), and
* 36 shape features: an 18-bin histogram of the polar angle ``theta`` and an 18-bin
  histogram of the azimuth ``phi`` of the surface normals of its pixels, each normalised
  to sum to 1 (all zeros if the square has no normal).

"The grid squares are shifted in order to have a representation that provides overlaps":
:class:`GridSpec` has ``layers`` copies of the grid, layer ``l`` shifted by ``l / layers``
of a cell down and to the right. The thesis's 5 x 5 grid in 4 layers gives
5 * 5 * 4 * 39 = 3900 features; chapter 6 uses 30 x 30 in one layer (35100 features).

Normals are computed once for the whole image with the thesis's formula
``N(r, c) = (p(r-n, c) - p(r, c)) x (p(r, c-n) - p(r, c))``, ``n = 5``, turned to face the
scanner, and belong to pixel ``(r, c)``; pixels in the first ``n`` rows or columns, and
pixels whose point or either neighbour is a miss, have no normal. Across a depth jump
the "normal" joins two surfaces, as in the thesis.

Departures and choices (the thesis leaves these open):

* **Angles.** Frame: the robot frame, z up. ``theta`` is the polar angle between the
  normal and the vertical (0 = facing up, like a floor; 90 = a wall; 180 = facing down),
  ``phi`` the heading of the normal's horizontal part, counter-clockwise from the
  frontal axis +x (180 = facing back at a scanner that looks along +x; 90 = facing left).
  The thesis measures both from its scanner's axes and speaks of 18 intervals of 20
  degrees; 20-degree bins fill ``phi``'s 360 degrees, and ``theta``'s 180 degrees are
  split into 18 bins of 10 degrees.
* **Bin centres, not edges, on the canonical surfaces.** Noise-free floors and walls put
  their normals exactly on 0, 90 or 180 degrees; with edges there, rounding would scatter
  one flat surface over two bins. So bins are centred on multiples of their width:
  ``theta`` bin ``k`` holds [10k - 5, 10k + 5) degrees (bin 0 is [0, 5), bin 17 is
  [165, 180]); ``phi`` bin ``k`` holds [20k - 10, 20k + 10) degrees modulo 360 (bin 0 is
  centred on +x, bin 9 on -x, the wall facing the scanner). A normal facing (nearly)
  straight up has an undefined heading; as in the thesis (Figure 5.2b) it still counts
  in the ``phi`` histogram, wherever noise puts it.
* **Ranges.** Misses (``inf``) and ranges beyond ``max_range`` count as ``max_range`` for
  the three distance features; they give no normals. ``own_body`` is ignored (the
  chapter-5 robot does not see itself).
* **Cell borders.** Cell edges along an axis of ``n`` pixels are at
  ``round((i + l / layers) * n / cells)`` for ``i = 0..cells``, clipped to the image. So
  each layer has ``cells x cells`` cells; in a shifted layer the last row and column of
  cells are cut short by the image border and the strip before the first edge (the top
  and left ``l / layers`` of a cell) belongs to no cell of that layer (layer 0 covers it).
  Layer 0 is exactly the unshifted grid, whatever ``layers`` is. A cell with no pixels
  (only in images smaller than ``cells * layers``) reads as all misses: ranges
  ``max_range``, histograms zero.

Speed: the edges of all layers cut the image into at most ``(cells * layers + 1)^2``
"atoms"; one ``np.bincount`` gives every atom's histograms, ``reduceat`` its min and max,
and summed-area tables of the atoms give every layer's cells. About 5 ms for a
360 x 360 image with the default spec.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from afford.features.detect import RangeImage
from afford.features.errors import DataError
from afford.features.schema import Channel, N_ANGLE_BINS, FeatureSchema

__all__ = [
    "GridSpec",
    "N_CELL_FEATURES",
    "RANGE_FEATURES",
    "THETA_BIN_DEG",
    "PHI_BIN_DEG",
    "grid_schema",
    "grid_histogram_groups",
    "grid_features",
    "grid_normal_bins",
    "cell_edges",
    "feature_cells",
    "cell_of_feature",
]

#: The three distance features of a cell, in vector order.
RANGE_FEATURES = ("min", "max", "mean")
#: Features per cell: 3 distance + 18 theta + 18 phi.
N_CELL_FEATURES = len(RANGE_FEATURES) + 2 * N_ANGLE_BINS
#: Width of a polar-angle bin (18 bins over 0..180 degrees).
THETA_BIN_DEG = 180.0 / N_ANGLE_BINS
#: Width of an azimuth bin (18 bins over 360 degrees, as in the thesis).
PHI_BIN_DEG = 360.0 / N_ANGLE_BINS


@dataclass(frozen=True)
class GridSpec:
    """How a range image is split into cells.

    Parameters
    ----------
    cells : int
        The grid has ``cells x cells`` cells per layer.
    layers : int
        Overlapping copies of the grid; layer ``l`` is shifted by ``l / layers`` of a cell
        in both directions (1 layer: no shift).
    normal_step : int
        Neighbour distance ``n`` in pixels of the normal formula.
    max_range : float
        Misses and longer ranges count as this many metres for the range features.
    """

    cells: int = 5
    layers: int = 4
    normal_step: int = 5
    max_range: float = 4.0

    def __post_init__(self) -> None:
        if self.cells < 1 or self.layers < 1 or self.normal_step < 1:
            raise DataError("a grid needs cells, layers and normal_step of at least 1")
        if not self.max_range > 0:
            raise DataError("max_range must be positive")

    @property
    def n_cells(self) -> int:
        """Cells over all layers."""
        return self.layers * self.cells * self.cells

    @property
    def n_features(self) -> int:
        return self.n_cells * N_CELL_FEATURES


def _cell_suffixes() -> list[tuple[str, str]]:
    out = [(name, "range") for name in RANGE_FEATURES]
    for angle in ("theta", "phi"):
        out += [(f"{angle}_{i:02d}", "shape") for i in range(N_ANGLE_BINS)]
    return out


@lru_cache(maxsize=32)
def _schema(spec: GridSpec) -> FeatureSchema:
    names: list[str] = []
    channels: list[str] = []
    suffixes = _cell_suffixes()
    for layer in range(spec.layers):
        for row in range(spec.cells):
            for col in range(spec.cells):
                prefix = f"l{layer}_r{row}_c{col}_"
                names += [prefix + s for s, _ in suffixes]
                channels += [c for _, c in suffixes]
    # The whole environment is the entity: it is always seen (no visibility feature).
    return FeatureSchema(tuple(names), tuple(channels), visibility=None,
                         histograms=tuple(grid_histogram_groups(spec)),
                         channel_info=(Channel("range", "m", 0.05, 0.1), Channel("shape", "fraction", 0.1, 0.5)))


def grid_schema(spec: GridSpec = GridSpec()) -> FeatureSchema:
    """Names and channels of :func:`grid_features`.

    Cells in order layer, row, column; per cell ``l{layer}_r{row}_c{col}_`` followed by
    ``min``, ``max``, ``mean`` (channel ``range``), ``theta_00``..``theta_17`` and
    ``phi_00``..``phi_17`` (channel ``shape``).
    """
    return _schema(spec)


def grid_histogram_groups(spec: GridSpec = GridSpec()) -> list[tuple[int, int]]:
    """``(start, stop)`` columns of every 18-bin histogram (theta, then phi, per cell)."""
    groups = []
    for cell in range(spec.n_cells):
        start = cell * N_CELL_FEATURES + len(RANGE_FEATURES)
        groups.append((start, start + N_ANGLE_BINS))
        groups.append((start + N_ANGLE_BINS, start + 2 * N_ANGLE_BINS))
    return groups


def feature_cells(spec: GridSpec = GridSpec()) -> np.ndarray:
    """``(n_features, 3)`` int array: the (layer, row, column) of each feature's cell."""
    cell = np.arange(spec.n_features) // N_CELL_FEATURES
    c = spec.cells
    return np.stack([cell // (c * c), (cell // c) % c, cell % c], axis=1)


def cell_of_feature(spec: GridSpec, index: int) -> tuple[int, int, int, str]:
    """``(layer, row, column, feature)`` of feature ``index``, e.g. ``(0, 2, 3, "theta_04")``."""
    if not 0 <= index < spec.n_features:
        raise IndexError(f"feature {index} outside a grid of {spec.n_features} features")
    cell, k = divmod(int(index), N_CELL_FEATURES)
    layer, rest = divmod(cell, spec.cells * spec.cells)
    row, col = divmod(rest, spec.cells)
    return layer, row, col, _cell_suffixes()[k][0]


def _axis_edges(n: int, cells: int, layers: int) -> np.ndarray:
    """(layers, cells + 1) pixel edges along an axis of n pixels: round((i + l/L) n / C)."""
    i = np.arange(cells + 1)[None, :] * layers + np.arange(layers)[:, None]
    # floor((i*L + l) * n / (C*L) + 1/2) in integers
    return np.minimum((2 * i * n + cells * layers) // (2 * cells * layers), n)


def cell_edges(spec: GridSpec, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Pixel edges of the cells of an image of ``shape``: rows and columns, each
    ``(layers, cells + 1)``; cell (l, r, c) holds rows ``[R[l, r], R[l, r + 1])`` and
    columns ``[C[l, c], C[l, c + 1])``. For plots."""
    h, w = shape
    return _axis_edges(h, spec.cells, spec.layers), _axis_edges(w, spec.cells, spec.layers)


@dataclass(frozen=True)
class _Layout:
    row_starts: np.ndarray   # (Ar,) first pixel row of each row atom
    col_starts: np.ndarray   # (Ac,)
    atom: np.ndarray         # (H, W) int atom id of each pixel
    row_ai: np.ndarray       # (layers, cells + 1) atom index of each row edge (Ar at the end)
    col_ai: np.ndarray       # (layers, cells + 1)
    area: np.ndarray         # (layers, cells, cells) pixels per cell


def _axis_atoms(n: int, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    starts = np.unique(np.concatenate([[0], edges.ravel()]))
    starts = starts[starts < n]
    of_pixel = np.searchsorted(starts, np.arange(n), side="right") - 1
    index = np.searchsorted(starts, edges)  # == len(starts) for edges at n
    return starts, of_pixel, index


@lru_cache(maxsize=16)
def _layout(h: int, w: int, cells: int, layers: int) -> _Layout:
    re, ce = _axis_edges(h, cells, layers), _axis_edges(w, cells, layers)
    rs, r_of, r_ai = _axis_atoms(h, re)
    cs, c_of, c_ai = _axis_atoms(w, ce)
    atom = r_of[:, None] * cs.size + c_of[None, :]
    area = np.diff(re, axis=1)[:, :, None] * np.diff(ce, axis=1)[:, None, :]
    for a in (rs, cs, atom, r_ai, c_ai, area):
        a.setflags(write=False)
    return _Layout(rs, cs, atom, r_ai, c_ai, area)


#: Pixels per block of the normal computation: small temporaries stay in the cache and
#: in malloc's heap (full-image temporaries cost a page fault per 4 kB, 3x the arithmetic).
_BLOCK_PIXELS = 8192


def _normal_blocks(image: RangeImage, n: int):
    """Yield ``(rows, ok, theta_bin, phi_bin)`` for row blocks of the pixels ``[n:, n:]``
    (the ones that can have a normal): ``rows`` is a slice of image rows, the rest are
    ``(len(rows), W - n)`` arrays; the int64 bins are garbage where not ``ok``."""
    r = np.asarray(image.ranges)
    d = np.asarray(image.directions)
    h, w = r.shape
    step = max(1, _BLOCK_PIXELS // max(w, 1))
    for i0 in range(n, h, step):
        i1 = min(i0 + step, h)
        rb = r[i0 - n : i1]
        finite = np.isfinite(rb)
        rf = np.where(finite, rb, 0.0)
        db = d[i0 - n : i1]
        # the origin cancels in p(a) - p(b) = r_a d_a - r_b d_b
        vx, vy, vz = rf * db[..., 0], rf * db[..., 1], rf * db[..., 2]
        ax, ay, az = (q[:-n, n:] - q[n:, n:] for q in (vx, vy, vz))   # p(r - n, c) - p(r, c)
        bx, by, bz = (q[n:, :-n] - q[n:, n:] for q in (vx, vy, vz))   # p(r, c - n) - p(r, c)
        nx = ay * bz - az * by
        ny = az * bx - ax * bz
        nz = ax * by - ay * bx
        length = np.sqrt(nx * nx + ny * ny + nz * nz)
        ok = finite[n:, n:] & finite[:-n, n:] & finite[n:, :-n] & (length > 1e-12)
        # face the scanner: N . (origin - p) = -r N . d must be >= 0
        dc = db[n:, n:]
        facing = nx * dc[..., 0] + ny * dc[..., 1] + nz * dc[..., 2]
        sign = np.where(facing > 0, -1.0, 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            cos_theta = np.clip(sign * nz / length, -1.0, 1.0)
            # theta bin k holds [10k - 5, 10k + 5) degrees; 175..180 joins bin 17
            tb = (np.arccos(cos_theta) * (N_ANGLE_BINS / np.pi) + 0.5).astype(np.int64)
            np.minimum(tb, N_ANGLE_BINS - 1, out=tb)
            # phi bin k holds [20k - 10, 20k + 10) degrees modulo 360
            phi = np.arctan2(sign * ny, sign * nx)  # -pi..pi
            pb = (phi * (N_ANGLE_BINS / (2 * np.pi)) + (N_ANGLE_BINS + 0.5)).astype(np.int64)
        pb[pb >= N_ANGLE_BINS] -= N_ANGLE_BINS
        yield slice(i0, i1), ok, tb, pb


def grid_normal_bins(image: RangeImage, n: int = 5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-pixel normal-angle bins of a whole image.

    Returns ``(has_normal, theta_bin, phi_bin)``, all ``(H, W)``; the bins (0..17, see the
    module docstring) are set where ``has_normal`` and -1 elsewhere.
    """
    h, w = np.shape(image.ranges)
    has = np.zeros((h, w), dtype=bool)
    tb = np.full((h, w), -1, dtype=np.int64)
    pb = np.full((h, w), -1, dtype=np.int64)
    for rows, ok, t, p in _normal_blocks(image, n):
        has[rows, n:] = ok
        tb[rows, n:] = np.where(ok, t, -1)
        pb[rows, n:] = np.where(ok, p, -1)
    return has, tb, pb


def _box_sums(table: np.ndarray, ri: np.ndarray, ci: np.ndarray) -> np.ndarray:
    """Sums over atom boxes from a summed-area table (Ar+1, Ac+1, ...), per layer and cell."""
    r0, r1 = ri[:, :-1, None], ri[:, 1:, None]
    c0, c1 = ci[:, None, :-1], ci[:, None, 1:]
    return table[r1, c1] - table[r0, c1] - table[r1, c0] + table[r0, c0]


def _summed(x: np.ndarray) -> np.ndarray:
    s = np.zeros((x.shape[0] + 1, x.shape[1] + 1) + x.shape[2:], dtype=np.float64)
    s[1:, 1:] = x.cumsum(axis=0).cumsum(axis=1)
    return s


def grid_features(image: RangeImage, spec: GridSpec = GridSpec()) -> np.ndarray:
    """The grid feature vector (float32, ``len(grid_schema(spec))``) of a range image."""
    ranges = np.asarray(image.ranges)
    h, w = ranges.shape
    lay = _layout(h, w, spec.cells, spec.layers)
    ar, ac = lay.row_starts.size, lay.col_starts.size
    nb = N_ANGLE_BINS

    # distance features: per atom min / max / sum, then per cell
    with np.errstate(invalid="ignore"):
        clipped = np.where(ranges < spec.max_range, ranges, spec.max_range)  # inf, NaN -> max
    clipped = np.maximum(clipped, 0.0)
    amin = np.minimum.reduceat(np.minimum.reduceat(clipped, lay.row_starts, axis=0), lay.col_starts, axis=1)
    amax = np.maximum.reduceat(np.maximum.reduceat(clipped, lay.row_starts, axis=0), lay.col_starts, axis=1)
    asum = np.add.reduceat(np.add.reduceat(clipped, lay.row_starts, axis=0), lay.col_starts, axis=1)
    # sentinels at index (ar, ac) so that reduceat indices may point one past the last atom
    pmin = np.full((ar + 1, ac + 1), np.inf)
    pmin[:ar, :ac] = amin
    pmax = np.full((ar + 1, ac + 1), -np.inf)
    pmax[:ar, :ac] = amax

    c = spec.cells
    out = np.empty((spec.layers, c, c, N_CELL_FEATURES), dtype=np.float32)
    empty = lay.area == 0
    for layer in range(spec.layers):
        ri, ci = lay.row_ai[layer, :-1], lay.col_ai[layer, :-1]
        mn = np.minimum.reduceat(np.minimum.reduceat(pmin, ri, axis=0), ci, axis=1)
        mx = np.maximum.reduceat(np.maximum.reduceat(pmax, ri, axis=0), ci, axis=1)
        out[layer, :, :, 0] = np.where(empty[layer], spec.max_range, mn)
        out[layer, :, :, 1] = np.where(empty[layer], spec.max_range, mx)
    sums = _box_sums(_summed(asum), lay.row_ai, lay.col_ai)
    with np.errstate(invalid="ignore", divide="ignore"):
        out[..., 2] = np.where(empty, spec.max_range, sums / lay.area)

    # shape features: one bincount of every atom's theta and phi histograms; pixels
    # without a normal go to a trash slot past the end
    n = spec.normal_step
    size = ar * ac * 2 * nb
    idx = np.empty((2, max(h - n, 0), max(w - n, 0)), dtype=np.intp)
    for rows, ok, tb, pb in _normal_blocks(image, n):
        base = np.where(ok, lay.atom[rows, n:] * (2 * nb), size)
        k = slice(rows.start - n, rows.stop - n)
        np.add(base, np.where(ok, tb, 0), out=idx[0, k])
        np.add(base, np.where(ok, pb + nb, 0), out=idx[1, k])
    counts = np.bincount(idx.ravel(), minlength=size + 1)[:size].reshape(ar, ac, 2 * nb)
    hist = _box_sums(_summed(counts), lay.row_ai, lay.col_ai)  # (layers, c, c, 36)
    total = hist[..., :nb].sum(axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        out[..., 3:] = np.where(total > 0, hist / np.maximum(total, 1), 0.0)
    return out.ravel()
