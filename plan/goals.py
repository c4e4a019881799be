"""Goals: constraints on perceived features (thesis chapter 8.6's {(o, i_f, v, r)}).

An expression ``OBJ:FEATURE=VALUE~RANGE`` says: feature FEATURE of object OBJ must lie
within RANGE of VALUE; ``OBJ:FEATURE<VALUE`` and ``OBJ:FEATURE>VALUE`` that it must lie
below or above VALUE. OBJ is an object index, ``*`` (some object) or ``A-B`` (object A's
feature minus object B's: a relative goal). Without ``~RANGE`` the default tolerance of
the feature's channel applies, as the schema gives it; so does the scale the search's
heuristic measures the channel in. Several constraints must all hold.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from afford.features import FeatureSchema
from afford.features.errors import DataError

__all__ = ["Constraint", "Goal", "parse_goal", "GoalError"]

_EXPR = re.compile(r"^\s*(?P<obj>\*|\d+|\d+\s*-\s*\d+)\s*:\s*(?P<feat>[A-Za-z_][\w]*)\s*(?P<op>[=<>])\s*(?P<val>[-+]?(?:[\d.eE+-]+|nan|inf))"
                   r"\s*(~\s*(?P<rng>[-+]?(?:[\d.eE+-]+|nan|inf)))?\s*$", re.IGNORECASE)


class GoalError(DataError):
    """A goal expression that cannot be used."""


@dataclass(frozen=True)
class Constraint:
    """One constraint: ``obj`` is an index, ``"*"``, or a pair (a, b) for a relative goal."""

    obj: int | str | tuple[int, int]
    feature: int
    name: str
    value: float
    tolerance: float
    channel: str
    scale: float = 1.0   # how far one unit of the channel counts in the search heuristic
    op: str = "="        # "=" within tolerance, "<" below value, ">" above value

    def text(self) -> str:
        obj = f"{self.obj[0]}-{self.obj[1]}" if isinstance(self.obj, tuple) else str(self.obj)
        if self.op != "=":
            return f"{obj}:{self.name}{self.op}{self.value:g}"
        return f"{obj}:{self.name}={self.value:g}~{self.tolerance:g}"


@dataclass(frozen=True)
class Goal:
    constraints: tuple[Constraint, ...]

    @cached_property
    def _arrays(self) -> dict:
        """The constraints as index arrays, for :meth:`gaps` (a search calls it per node)."""
        kinds = {"one": [], "pair": [], "any": []}
        for i, c in enumerate(self.constraints):
            kinds["any" if c.obj == "*" else "pair" if isinstance(c.obj, tuple) else "one"].append(i)

        def take(idx, f):
            return np.array([f(self.constraints[i]) for i in idx])

        one, pair, any_ = kinds["one"], kinds["pair"], kinds["any"]
        return {
            "one": (np.array(one, int), take(one, lambda c: c.obj).astype(int), take(one, lambda c: c.feature).astype(int)),
            "pair": (np.array(pair, int), take(pair, lambda c: c.obj[0]).astype(int),
                     take(pair, lambda c: c.obj[1]).astype(int), take(pair, lambda c: c.feature).astype(int)),
            "any": (np.array(any_, int), take(any_, lambda c: c.feature).astype(int)),
            "value": np.array([c.value for c in self.constraints], float),
            "tolerance": np.array([c.tolerance for c in self.constraints], float),
            "scale": np.array([c.scale for c in self.constraints], float),
            "sign": np.array([{"=": 0.0, "<": 1.0, ">": -1.0}[c.op] for c in self.constraints], float),
            "named": [c.obj if isinstance(c.obj, int) else None for c in self.constraints],
            "pairs": [c.obj if isinstance(c.obj, tuple) else None for c in self.constraints],
        }

    def gaps(self, state: np.ndarray) -> np.ndarray:
        """How far each constraint is from holding (0 where it holds; for ``*``, the nearest object)."""
        a = self._arrays
        v = np.empty(len(self.constraints))
        pos, obj, feat = a["one"]
        v[pos] = state[obj, feat]
        pos, i, j, feat = a["pair"]
        v[pos] = state[i, feat] - state[j, feat]
        gaps = self._gap(v, a["value"], a["tolerance"], a["sign"])
        pos, feat = a["any"]
        if pos.size:
            if state.shape[0] == 0:
                gaps[pos] = np.inf
            else:
                cand = self._gap(state[:, feat], a["value"][pos], a["tolerance"][pos], a["sign"][pos])
                gaps[pos] = cand.min(axis=0)
        return gaps

    @staticmethod
    def _gap(v, value, tolerance, sign):
        """0 where a constraint holds, else how far it is from holding."""
        within = np.maximum(np.abs(v - value) - tolerance, 0.0)
        if not sign.any():
            return within
        beyond = np.maximum(sign * (v - value), 0.0)  # "<": above the value by; ">": below it by
        return np.where(sign == 0.0, within, beyond)

    def holds(self, state: np.ndarray, gaps: np.ndarray | None = None) -> bool:
        g = self.gaps(state) if gaps is None else gaps
        return bool((g <= 1e-9).all())

    def distance(self, state: np.ndarray, gaps: np.ndarray | None = None) -> float:
        """Scaled distance to the goal: 0 exactly when it holds (the search heuristic)."""
        g = self.gaps(state) if gaps is None else gaps
        return float((g / self._arrays["scale"]).sum())

    def min_steps(self, state: np.ndarray, gaps: np.ndarray | None = None) -> int:
        """A lower bound on the steps still needed: a behaviour changes one object only.

        Every named object with an unmet constraint needs a step of its own, and so does an
        unmet relative constraint neither of whose objects is among them (``*`` constraints
        add nothing: a step on any object might meet them).
        """
        g = self.gaps(state) if gaps is None else gaps
        unmet = g > 1e-9
        a = self._arrays
        named = {o for o, u in zip(a["named"], unmet) if u and o is not None}
        pairs = [p for p, u in zip(a["pairs"], unmet) if u and p is not None]
        return len(named) + int(any(i not in named and j not in named for i, j in pairs))

    @property
    def channels(self) -> set[str]:
        return {c.channel for c in self.constraints}

    def objects(self) -> set[int]:
        out: set[int] = set()
        for c in self.constraints:
            if isinstance(c.obj, tuple):
                out.update(c.obj)
            elif isinstance(c.obj, int):
                out.add(c.obj)
        return out

    def check_objects(self, n: int) -> None:
        for i in sorted(self.objects()):
            if i >= n:
                raise GoalError(f"the goal names object {i}, but the robot sees {n} object{'s' if n != 1 else ''} (0..{n - 1})")

    def to_json(self) -> list[str]:
        return [c.text() for c in self.constraints]


def parse_goal(expressions: list[str], schema: FeatureSchema) -> Goal:
    """Parse ``OBJ:FEATURE=VALUE~RANGE`` expressions; every mistake is one sentence."""
    if not expressions:
        raise GoalError("give at least one goal, e.g. '*:visibility=0'")
    out = []
    for expr in expressions:
        m = _EXPR.match(expr)
        if not m:
            raise GoalError(f"cannot read goal {expr!r}; write OBJ:FEATURE=VALUE~RANGE, OBJ:FEATURE<VALUE or "
                            f"OBJ:FEATURE>VALUE, e.g. '0:z_min=0.95~0.03'")
        try:
            feature = schema.index(m["feat"])
        except KeyError:
            raise GoalError(f"goal {expr!r} names an unknown feature {m['feat']!r}; features are "
                            f"{', '.join(schema.names[:7])}, ... (see 'afford inspect MODEL')") from None
        obj_text = m["obj"].replace(" ", "")
        if obj_text == "*":
            obj: int | str | tuple[int, int] = "*"
        elif "-" in obj_text:
            a, b = (int(v) for v in obj_text.split("-"))
            if a == b:
                raise GoalError(f"goal {expr!r} relates object {a} to itself")
            obj = (a, b)
        else:
            obj = int(obj_text)
        try:
            value = float(m["val"])
            tol = float(m["rng"]) if m["rng"] is not None else None
        except ValueError:
            raise GoalError(f"goal {expr!r} has a value that is not a number") from None
        channel = schema.channels[feature]
        info = schema.channel(channel)
        if m["op"] != "=" and tol is not None:
            raise GoalError(f"goal {expr!r}: a range (~) goes with '=', not with '{m['op']}'")
        tol = info.tolerance if tol is None else tol
        if not (np.isfinite(tol) and np.isfinite(value)) or tol < 0:
            raise GoalError(f"goal {expr!r}: the value must be finite and the range not negative")
        out.append(Constraint(obj, feature, schema.names[feature], value, tol, channel, info.scale, m["op"]))
    return Goal(tuple(out))
