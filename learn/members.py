"""Each object's own effect within its category: the effects of its most similar members.

The thesis predicts the next state as ``f + prototype(E)``: every member of "dragged 12 cm"
is expected to move exactly the category's mean, so a planner cannot tell a 9 cm drag from a
15 cm one, nor aim an object at a place tighter than a category's spread. Yet what spread
there is within a category is mostly the objects' own doing: a lateral push moves the palm
to the object's centre, so a wide box travels further than a narrow one; a ball rolls on.

:class:`MemberEffects` predicts, within a category, the mean effect of the ``k`` category
members whose entity (and parameters) looked most like the one at hand, and keeps those
``k`` effects as the distribution a rollout draws from. ``k`` is chosen per behaviour and
effect channel by leave-one-out error among a few values, one of which is "every member":
the thesis's prototype, so the choice can always fall back on it. Similarity is Euclidean in a space
where each feature is standardised and each channel (position, shape, ...) weighs the same
in all, however many features it has: otherwise the 36 shape bins of the table would drown
its six position features. Measured on 5000 table interactions (held out: 1000 of another
seed, categories given), five neighbours cut the 90th percentile of the position error from
11-13 cm to 4-6 cm on the pushes, and the median from about 3 cm to 1-1.5 cm.

Members of a kind the categories discarded (a rare effect, pruned: label below 0) are kept
apart, as a pool: they teach no category, yet they are what the robot saw happen. When the
model gives an object a chance of an unknown outcome (P(known) < 1), an imagined world asks
:meth:`MemberEffects.unknown_effects` what the most similar of them did, rather than assuming
that nothing happens: on 5000 table interactions many pushes whose effect fell outside the
kept kinds (the shape bins set them apart) still moved the object much as the kept ones did.

Everything fitted is plain arrays (:meth:`to_arrays` / :meth:`from_arrays`), so a model
file holds it without any code.
"""

from __future__ import annotations

import numpy as np

__all__ = ["MemberEffects", "JointMembers", "K_GRID", "UNKNOWN_K"]

#: Neighbour counts tried; 0 means every member of the category (the thesis's prototype).
K_GRID = (3, 5, 10, 20, 0)

#: Discarded members an unknown outcome is drawn from: the most similar this many.
UNKNOWN_K = 5

#: Members per category the leave-one-out choice of k looks at, at most (a random sample).
LOO_ROWS = 1500


class MemberEffects:
    """Per category, the effect predicted from the entity: the mean of its ``k`` nearest members.

    Parameters
    ----------
    groups : sequence of str
        The group (channel) of every input column; every group weighs the same in the
        similarity, whatever its number of columns (parameters may form a group of their own).
    effect_groups : sequence of str
        The channel of every effect column, for the leave-one-out error.
    tolerances : array of shape (n_effect_features,)
        The unit each effect column's error is measured in (the schema's goal tolerances).
    k_grid : tuple of int
        Neighbour counts to choose from (0: every member).
    random_state : int
        Seeds the sample the leave-one-out choice uses in large categories.

    Attributes (after :meth:`fit`)
    ------------------------------
    k_ : dict of str to int
        Per effect channel, the chosen neighbour count (0: every member, the prototype):
        how far a push moves an object may depend on its width while how its shape bins
        jitter does not, so each channel takes the count that predicts it best.
    loo_error_ : dict of str to dict of int to float
        Per channel, the mean leave-one-out error of each k tried (tolerance units).
    Zu_, Eu_ : arrays
        The discarded members (label below 0): their scaled inputs and their effects, the
        pool :meth:`unknown_effects` draws from (empty where none were given).
    """

    def __init__(self, groups, effect_groups, tolerances, k_grid: tuple[int, ...] = K_GRID, random_state: int = 0):
        self.groups = tuple(str(g) for g in groups)
        self.effect_groups = tuple(str(g) for g in effect_groups)
        self.tolerances = np.asarray(tolerances, dtype=float)
        self.k_grid = tuple(int(k) for k in k_grid)
        self.random_state = random_state

    # -- fitting ---------------------------------------------------------------------------
    def fit(self, X: np.ndarray, E: np.ndarray, labels: np.ndarray) -> "MemberEffects":
        """``X``: the inputs (entity features, then encoded parameters), ``E``: the effects,
        ``labels``: each row's category (rows below 0, pruned, teach no category: they form
        the pool of discarded members, scaled as the kept ones are)."""
        X, E, labels = np.asarray(X, dtype=float), np.asarray(E, dtype=float), np.asarray(labels, dtype=int)
        if X.shape[1] != len(self.groups) or E.shape[1] != len(self.effect_groups):
            raise ValueError(f"MemberEffects was given {X.shape[1]} inputs and {E.shape[1]} effect columns for "
                             f"{len(self.groups)} groups and {len(self.effect_groups)} effect channels")
        keep = labels >= 0
        pool = ~keep & np.isfinite(X).all(axis=1) & np.isfinite(E).all(axis=1)
        Xu, Eu = X[pool], E[pool]
        X, E, labels = X[keep], E[keep], labels[keep]
        self.shift_ = X.mean(axis=0) if len(X) else np.zeros(X.shape[1])
        sd = X.std(axis=0) if len(X) else np.ones(X.shape[1])
        g = np.asarray(self.groups)
        size = {name: int((g == name).sum()) for name in set(self.groups)}
        balance = np.array([1.0 / np.sqrt(size[name]) for name in self.groups])
        # a constant column tells members apart in nothing: weight 0
        self.weight_ = np.where(sd > 1e-12, 1.0 / np.maximum(sd, 1e-12), 0.0) * balance
        self.Z_ = ((X - self.shift_) * self.weight_).astype(np.float32)
        self.E_ = E.astype(np.float32)
        self.labels_ = labels.astype(np.int16)
        self.Zu_ = ((Xu - self.shift_) * self.weight_).astype(np.float32)
        self.Eu_ = Eu.astype(np.float32)
        self.loo_error_ = self._leave_one_out()
        self.k_ = {ch: (min(errors, key=lambda k: (errors[k], k != 0, k)) if errors else 0)
                   for ch, errors in self.loo_error_.items()}
        self._index()
        return self

    @property
    def channels(self) -> list[str]:
        return list(dict.fromkeys(self.effect_groups))

    def _errors(self, pred: np.ndarray, E: np.ndarray) -> dict[str, np.ndarray]:
        """Per channel and row: the root mean square error over the channel's columns, in tolerance units."""
        r = (pred - E) / np.where(self.tolerances > 0, self.tolerances, 1.0)
        ch = np.asarray(self.effect_groups)
        return {name: np.sqrt((r[:, ch == name] ** 2).mean(axis=1)) for name in self.channels}

    def _leave_one_out(self) -> dict[str, dict[int, float]]:
        """Per channel, the mean leave-one-out error of each k (tolerance units)."""
        rng = np.random.default_rng(self.random_state)
        total = {ch: {k: 0.0 for k in self.k_grid} for ch in self.channels}
        n = 0
        for c in np.unique(self.labels_):
            rows = np.flatnonzero(self.labels_ == c)
            if rows.size < 3:
                continue
            test = rows if rows.size <= LOO_ROWS else np.sort(rng.choice(rows, LOO_ROWS, replace=False))
            Zc, Ec = self.Z_[rows].astype(float), self.E_[rows].astype(float)
            Zt, Et = self.Z_[test].astype(float), self.E_[test].astype(float)
            d = (Zt * Zt).sum(1)[:, None] - 2.0 * Zt @ Zc.T + (Zc * Zc).sum(1)[None, :]
            d[np.searchsorted(rows, test)[:, None] == np.arange(rows.size)[None, :]] = np.inf  # not oneself
            kmax = min(max(self.k_grid), rows.size - 1)
            near = np.argsort(d, axis=1, kind="stable")[:, :kmax]
            csum = np.cumsum(Ec[near], axis=1)  # (tested, kmax, features): running sums of the nearest
            everyone = (Ec.sum(axis=0)[None, :] - Et) / (rows.size - 1)  # every other member: the prototype
            for k in self.k_grid:
                pred = everyone if k == 0 or k > kmax else csum[:, k - 1] / k
                for ch, err in self._errors(pred, Et).items():
                    total[ch][k] += float(err.sum())
            n += test.size
        return {ch: {k: v / n for k, v in errors.items()} for ch, errors in total.items()} if n else \
            {ch: {} for ch in self.channels}

    def _index(self) -> None:
        self._rows = {int(c): np.flatnonzero(self.labels_ == c) for c in np.unique(self.labels_)}
        # members sorted by category (rows in order within each): one block per category
        perm = np.argsort(self.labels_, kind="stable")
        self._perm = perm
        self._lab = self.labels_[perm].astype(np.int64)
        self._Z = np.ascontiguousarray(self.Z_[perm], dtype=float)
        self._ZT = np.ascontiguousarray(self._Z.T)
        self._sq = (self._Z * self._Z).sum(1)
        self._E = self.E_.astype(float)
        self._Es = self._E[perm]
        n_cat = int(self.labels_.max()) + 1 if self.labels_.size else 0
        counts = np.bincount(self.labels_.astype(int), minlength=n_cat)
        self._known = counts > 0
        self._start = np.concatenate([[0], np.cumsum(counts)])[:-1]
        self._blocks = [(int(self._start[c]), int(counts[c])) for c in np.flatnonzero(counts)]
        self._kmax = max(self.k_.values(), default=0)
        self._all_means = np.zeros((n_cat, self._E.shape[1]))
        for c, rows in self._rows.items():
            self._all_means[c] = self._E[rows].mean(axis=0)
        # per distinct k: which of the grouped positions are each category's k nearest (its
        # block's first k), and the effect columns of the channels that use that k
        ch = np.asarray(self.effect_groups)
        self._by_k = []
        for k in sorted(set(self.k_.values())):
            cols = np.flatnonzero(np.isin(ch, [c for c, kc in self.k_.items() if kc == k]))
            if k == 0:
                self._by_k.append((0, cols, None, None, None, None))
                continue
            taken = np.minimum(counts, k)
            cats = np.flatnonzero(taken > 0)
            pick = np.concatenate([self._start[c] + np.arange(taken[c]) for c in cats]) if cats.size \
                else np.zeros(0, dtype=np.int64)
            segments = np.concatenate([[0], np.cumsum(taken[cats])])[:-1]
            self._by_k.append((k, cols, cats, pick, segments, taken[cats].astype(float)))
        # The same members laid out one padded row per category (padding: never nearer than
        # a member), so that one partition finds every category's nearest at once
        # (:meth:`_nearest`) instead of a loop over the categories.
        cats = np.flatnonzero(counts)
        self._cats = cats
        self._width = int(counts.max()) if cats.size else 0
        self._near_k = min(self._kmax, self._width)
        slot_of_cat = np.full(n_cat, -1, dtype=np.int64)
        slot_of_cat[cats] = np.arange(cats.size)
        rank = np.arange(self._lab.size) - self._start[self._lab]
        self._slot = slot_of_cat[self._lab] * self._width + rank  # grouped position -> padded position
        self._pad_counts = counts[cats]
        self._row_base = np.arange(cats.size) * self._width
        self._pad_start = self._start[cats]
        self._Ep = np.zeros((cats.size * self._width, self._E.shape[1]))
        self._Ep[self._slot] = self._Es
        # per distinct k > 0: the channels' columns and, per category, how many of its
        # nearest the mean takes (its count, where smaller than k)
        # (and those columns of the padded effects, contiguous)
        self._pad_by_k = []
        for k, cols, *_ in self._by_k:
            if k > 0:
                taken = np.minimum(self._pad_counts, k)
                self._pad_by_k.append((min(k, self._near_k), cols, taken, np.flatnonzero(taken < min(k, self._near_k)),
                                       np.ascontiguousarray(self._Ep[:, cols])))

    # -- predicting ------------------------------------------------------------------------
    def _grouped(self, x: np.ndarray) -> np.ndarray:
        """Positions (in category order) of each category's nearest members to input ``x``:
        block by block, the first ``min(count, largest k)`` positions of every category's block
        hold its nearest members, nearest first (ties: the lower row); the rest of a block is
        left in no particular order, for nothing reads it. A 2-D ``x``: one row per query.

        For many queries each block is partitioned to its ``kmax`` nearest and only those are
        sorted (3.5 times faster for 200 queries of 1124 members than sorting them all, which
        cost planning more than the classifiers did); one query is sorted whole, which is
        faster than the partition's per-block calls."""
        z = (np.asarray(x, dtype=float) - self.shift_) * self.weight_
        d = self._sq - 2.0 * (z @ self._ZT)
        if d.ndim == 1:  # one query: a full sort costs less than partitioning block by block
            order = np.argsort(d, kind="stable")
            return order[np.argsort(self._lab[order], kind="stable")]
        grouped = np.array(np.broadcast_to(np.arange(d.shape[-1]), d.shape))
        for start, count in self._blocks:
            k = min(count, self._kmax)
            block = d[..., start: start + count]
            if k <= 0:
                continue
            near = np.broadcast_to(np.arange(count), block.shape)
            if k < count:
                part = np.argpartition(block, k - 1, axis=-1)[..., :k]
                kth = np.take_along_axis(block, part, axis=-1).max(axis=-1, keepdims=True)
                if not np.any((block <= kth).sum(axis=-1) > k):  # a tie at the k-th: sort it all
                    near = part
            near = np.sort(near, axis=-1)  # lower rows first, so the stable sort breaks ties by row
            order = np.argsort(np.take_along_axis(block, near, axis=-1), axis=-1, kind="stable")
            grouped[..., start: start + k] = start + np.take_along_axis(near, order[..., :k], axis=-1)
        return grouped

    def _nearest(self, x: np.ndarray) -> np.ndarray:
        """Per category with members (in id order), the padded positions of its
        ``min(count, largest k)`` members nearest to input ``x``, nearest first, ties to the
        lower row: what :meth:`_grouped` finds, in one partition for every category and
        query. Shape ``(..., categories, largest k)``; a position is the member's place in
        the padded layout (``_Ep``'s row); past a category's count they are padding. The
        distances are computed exactly as :meth:`_grouped` computes them."""
        z = (np.asarray(x, dtype=float) - self.shift_) * self.weight_
        d = self._sq - 2.0 * (z @ self._ZT)
        lead = d.shape[:-1]
        n_cat, width, k = self._cats.size, self._width, self._near_k
        if k <= 0:
            return np.zeros(lead + (n_cat, 0), dtype=np.int64)
        flat = d.reshape(-1, d.shape[-1])
        queries = flat.shape[0]
        padded = np.full((queries, n_cat * width), np.inf)
        padded[:, self._slot] = flat
        padded = padded.reshape(-1, width)  # one row per (query, category)
        rows = np.arange(padded.shape[0])[:, None]
        if k < width:
            # the k nearest (a set) and, in place k, the next one: a tie across the boundary
            # shows as the next one as near as the k-th
            part = np.argpartition(padded, (k - 1, k), axis=-1)
            edge = padded[rows[:, 0], part[:, k - 1]] == padded[rows[:, 0], part[:, k]]
            near = part[:, :k]
            near.sort(axis=-1)  # lower positions first, so the stable sort breaks ties by row
        else:
            near = np.tile(np.arange(width), (padded.shape[0], 1))
        near = near[rows, np.argsort(padded[rows, near], axis=-1, kind="stable")]
        if k < width:
            # which of the tied the partition kept is arbitrary: such a category is sorted
            # whole (padding sorts last, farther than every member)
            tied = edge & (self._pad_counts > k if queries == 1 else np.tile(self._pad_counts > k, queries))
            for r in np.flatnonzero(tied):
                near[r] = np.argsort(padded[r], kind="stable")[:k]
        return (near + (self._row_base if queries == 1 else np.tile(self._row_base, queries))[:, None]).reshape(
            lead + (n_cat, k))

    def has(self, category: int) -> bool:
        return int(category) in self._rows

    def neighbours(self, x: np.ndarray, category: int, channel: str, grouped: np.ndarray | None = None) -> np.ndarray:
        """Rows (into ``E_``) of the members of ``category`` nearest to input ``x``, nearest first:
        as many as ``channel`` uses (every member for k 0 or a category that small).
        ``grouped``: :meth:`_grouped` of ``x``, where the caller has it already."""
        rows = self._rows.get(int(category))
        if rows is None:
            raise KeyError(f"no members of category {category}")
        k = self.k_[channel]
        if k == 0 or k >= rows.size:
            return rows
        start = int(self._start[int(category)])
        if grouped is not None:
            return self._perm[grouped[start: start + k]]
        c = int(np.searchsorted(self._cats, int(category)))
        return self._perm[start + self._nearest(x)[c, :k] - self._row_base[c]]

    def means(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(mean effect per category id, shape (n_categories, n_features); which ids have
        members): every category's prediction for input ``x`` at once, one distance pass, each
        channel the mean of its own number of nearest members. A 2-D ``x`` gives one such
        table per row (leading axis), in one pass for all."""
        x = np.asarray(x, dtype=float)
        out = np.array(np.broadcast_to(self._all_means, x.shape[:-1] + self._all_means.shape))
        if not self._pad_by_k:
            return out, self._known  # every channel takes every member: the categories' means
        near = self._nearest(x)
        lead, cats = near.shape[:-2], self._cats
        near = near.reshape(-1, near.shape[-1])
        for k, cols, taken, short, Ep in self._pad_by_k:
            picked = Ep[near[:, :k]]  # (queries x categories, nearest, columns)
            # the sums run nearest first (the order they were always taken in: a sum over the
            # middle axis adds row after row)
            sums = picked.sum(axis=1).reshape(lead + (cats.size, cols.size))
            for c in short:  # a category smaller than k: its sum stops at its count
                sums[..., c, :] = np.cumsum(picked.reshape(lead + (cats.size, k, cols.size))[..., c, :, :],
                                            axis=-2)[..., taken[c] - 1, :]
            out[..., cats[:, None], cols[None, :]] = sums / taken[:, None]
        return out, self._known

    def category_spread(self, category: int) -> np.ndarray:
        """The standard deviation of the effects of every member of ``category``."""
        return self._E[self._rows[int(category)]].std(axis=0)

    def effects(self, x: np.ndarray, category: int, channel: str) -> np.ndarray:
        """The effects the members of ``category`` nearest to ``x`` had, as many as ``channel``
        uses: the distribution a rollout draws that channel from."""
        return self._E[self.neighbours(x, category, channel)]

    def unknown_effects(self, x: np.ndarray, k: int = UNKNOWN_K) -> np.ndarray:
        """The effects the ``k`` discarded members nearest to input ``x`` had, nearest first
        (ties: the lower row); shape ``(≤ k, n_features)``, empty where the pool is."""
        if self.Eu_.shape[0] == 0:
            return self.Eu_.astype(float)
        z = (np.asarray(x, dtype=float) - self.shift_) * self.weight_
        Zu = self.Zu_.astype(float)
        d = ((Zu - z) ** 2).sum(axis=1)
        return self.Eu_[np.argsort(d, kind="stable")[:k]].astype(float)

    def predict(self, x: np.ndarray, category: int) -> tuple[np.ndarray, np.ndarray]:
        """(mean effect, its spread: per channel the standard deviation of the effects of the
        members that channel's mean rests on)."""
        mean = np.zeros(len(self.effect_groups))
        spread = np.zeros(len(self.effect_groups))
        ch = np.asarray(self.effect_groups)
        grouped = self._grouped(x)  # one distance pass for every channel
        for channel in self.channels:
            cols = ch == channel
            e = self._E[self.neighbours(x, category, channel, grouped)][:, cols]
            mean[cols], spread[cols] = e.mean(axis=0), e.std(axis=0)
        return mean, spread

    # -- storing ---------------------------------------------------------------------------
    def to_arrays(self) -> tuple[dict[str, np.ndarray], dict]:
        """Plain arrays and a JSON-able description, all a model file needs to hold."""
        arrays = {"Z": self.Z_, "E": self.E_, "labels": self.labels_, "Zu": self.Zu_, "Eu": self.Eu_,
                  "shift": self.shift_.astype(np.float64), "weight": self.weight_.astype(np.float64)}
        meta = {"k": {ch: int(k) for ch, k in self.k_.items()}, "groups": list(self.groups),
                "effect_groups": list(self.effect_groups), "tolerances": [float(t) for t in self.tolerances],
                "loo_error": {ch: {str(k): round(float(v), 5) for k, v in errors.items()}
                              for ch, errors in self.loo_error_.items()}}
        return arrays, meta

    @classmethod
    def from_arrays(cls, arrays: dict[str, np.ndarray], meta: dict) -> "MemberEffects":
        """The fitted model back from :meth:`to_arrays`; ``ValueError`` when the parts do not fit
        together. The pool of discarded members (``Zu``, ``Eu``) is optional: models from
        before it existed have none."""
        try:
            self = cls(meta["groups"], meta["effect_groups"], meta["tolerances"])
            self.k_ = {str(ch): int(k) for ch, k in dict(meta["k"]).items()}
            self.loo_error_ = {str(ch): {int(k): float(v) for k, v in dict(errors).items()}
                               for ch, errors in dict(meta.get("loo_error", {})).items()}
            Z, E, labels = arrays["Z"], arrays["E"], arrays["labels"]
            shift, weight = arrays["shift"], arrays["weight"]
            Zu = arrays.get("Zu")
            Eu = arrays.get("Eu")
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"the member effects are incomplete ({exc})") from None
        n, d = Z.shape if Z.ndim == 2 else (-1, -1)
        if (Z.ndim != 2 or E.ndim != 2 or labels.shape != (n,) or E.shape[0] != n or d != len(self.groups)
                or shift.shape != (d,) or weight.shape != (d,) or E.shape[1] != len(self.effect_groups)
                or set(self.k_) != set(self.channels) or min(self.k_.values(), default=0) < 0 or labels.dtype.kind not in "iu" or (labels.size and labels.min() < 0) or Z.dtype.kind != "f" or E.dtype.kind != "f"
                or not (np.all(np.isfinite(Z)) and np.all(np.isfinite(E)))):
            raise ValueError("the member effects' arrays do not fit together")
        if (Zu is None) != (Eu is None):
            raise ValueError("the discarded members lack their inputs or their effects")
        if Zu is None:
            Zu, Eu = np.zeros((0, d), dtype=np.float32), np.zeros((0, E.shape[1]), dtype=np.float32)
        if (Zu.ndim != 2 or Eu.ndim != 2 or Zu.shape[0] != Eu.shape[0] or Zu.shape[1] != d
                or Eu.shape[1] != E.shape[1] or Zu.dtype.kind != "f" or Eu.dtype.kind != "f"
                or not (np.all(np.isfinite(Zu)) and np.all(np.isfinite(Eu)))):
            raise ValueError("the discarded members' arrays do not fit together")
        self.Zu_, self.Eu_ = Zu.astype(np.float32), Eu.astype(np.float32)
        self.Z_, self.E_, self.labels_ = Z.astype(np.float32), E.astype(np.float32), labels.astype(np.int16)
        self.shift_, self.weight_ = shift.astype(float), weight.astype(float)
        self._index()
        return self


class JointMembers:
    """Several behaviours' member effects asked about one entity at once.

    A planning search that expands a state asks every behaviour what it would do to the
    object that just changed; each :meth:`MemberEffects.means` is a dozen small numpy
    calls, and their overhead, not the arithmetic, is what a search pays. This lays every
    behaviour's categories out as the rows of one padded table, so one partition and one
    gather per neighbour count serve them all. The numbers are :meth:`MemberEffects.means`'s
    to the bit: the same distances, the same nearest members in the same order, summed in
    the same order (``tests/test_members.py`` holds it to that).
    """

    def __init__(self, members):
        self.members = list(members)
        ms = self.members
        if len({m._Ep.shape[1] for m in ms}) > 1:
            raise ValueError("the behaviours' member effects have different effect columns")
        self._width = max((m._width for m in ms), default=0)
        self._k = min(max((m._near_k for m in ms), default=0), self._width)
        n_rows = [m._cats.size for m in ms]
        self._row_off = np.concatenate([[0], np.cumsum(n_rows)]).astype(np.int64)
        W, R = self._width, int(self._row_off[-1])
        self._slot = np.concatenate([(off + m._slot // max(m._width, 1)) * W + m._slot % max(m._width, 1)
                                     for off, m in zip(self._row_off, ms)]) if ms else np.zeros(0, dtype=np.int64)
        self._counts = np.concatenate([m._pad_counts for m in ms]) if ms else np.zeros(0, dtype=np.int64)
        self._row_base = np.arange(R) * W
        F = ms[0]._Ep.shape[1] if ms else 0
        Ep = np.zeros((R, W, F))
        for off, m in zip(self._row_off, ms):
            Ep[off: off + m._cats.size, : m._width] = m._Ep.reshape(m._cats.size, m._width, F)
        Ep = Ep.reshape(R * W, F)
        self._out_off = np.concatenate([[0], np.cumsum([m._all_means.shape[0] for m in ms])]).astype(np.int64)
        self._out0 = np.concatenate([m._all_means for m in ms]) if ms else np.zeros((0, F))
        groups: dict = {}
        for j, m in enumerate(ms):
            for k, cols, taken, _short, _ in m._pad_by_k:
                g = groups.setdefault((k, cols.tobytes()), {"k": k, "cols": cols, "rows": [], "out": [], "taken": []})
                g["rows"].append(self._row_off[j] + np.arange(m._cats.size))
                g["out"].append(self._out_off[j] + m._cats)
                g["taken"].append(taken)
        self._groups = []
        for g in groups.values():
            taken = np.concatenate(g["taken"])
            self._groups.append((g["k"], g["cols"], np.concatenate(g["rows"]), np.concatenate(g["out"]), taken,
                                 np.flatnonzero(taken < g["k"]), np.ascontiguousarray(Ep[:, g["cols"]])))

    def means(self, xs) -> list[tuple[np.ndarray, np.ndarray]]:
        """``[m.means(x) for m, x in zip(members, xs)]`` for one input per behaviour."""
        ms = self.members
        out = self._out0.copy()
        k, W = self._k, self._width
        if k > 0:
            d = [m._sq - 2.0 * (((np.asarray(x, dtype=float) - m.shift_) * m.weight_) @ m._ZT) for m, x in zip(ms, xs)]
            padded = np.full(self._row_base.size * W, np.inf)
            padded[self._slot] = np.concatenate(d)
            padded = padded.reshape(-1, W)
            rows = np.arange(padded.shape[0])[:, None]
            if k < W:
                part = np.argpartition(padded, (k - 1, k), axis=-1)
                edge = padded[rows[:, 0], part[:, k - 1]] == padded[rows[:, 0], part[:, k]]
                near = part[:, :k]
                near.sort(axis=-1)
            else:
                near = np.tile(np.arange(W), (padded.shape[0], 1))
            near = near[rows, np.argsort(padded[rows, near], axis=-1, kind="stable")]
            if k < W:
                for r in np.flatnonzero(edge & (self._counts > k)):
                    near[r] = np.argsort(padded[r], kind="stable")[:k]
            near += self._row_base[:, None]
            for kk, cols, grows, orows, taken, short, Ep in self._groups:
                picked = Ep[near[grows, :kk]]  # (rows, nearest, columns)
                sums = picked.sum(axis=1)
                for i in short:
                    sums[i] = np.cumsum(picked[i], axis=0)[taken[i] - 1]
                out[orows[:, None], cols[None, :]] = sums / taken[:, None]
        return [(out[self._out_off[j]: self._out_off[j + 1]], m._known) for j, m in enumerate(ms)]
