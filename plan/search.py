"""Searching for behaviour sequences in the robot's perceptual space (thesis 7.5, 8.6).

``best_first``: states are the lists of object vectors; an edge is (behaviour, object,
alpha) together with one predicted outcome category, costing -log P(category). Nodes are
popped in order of cost plus ``heuristic_weight`` times the goal distance (ties go to the
node nearer the goal), so with the default weight of 0 the first plan that reaches the
goal is the most probable one within the limits; ``best_plans`` goes on to the next most
probable behaviour sequences. ``breadth_first`` is the thesis's forward chaining: only each
behaviour's most probable outcome, shortest plan first.

A plan's *open-loop probability* is the chance that executing its behaviours blind
reaches the goal at some step, summed over every outcome sequence the model predicts (not
only the one the plan was found along). A search reports it as the plan's success
probability; :func:`plan.monitor.assess` replaces that with the chance of reaching the goal
when the plan runs with monitoring and replanning, as ``afford plan`` and ``afford
emulate`` run it.
"""

from __future__ import annotations

import heapq
import math
import time
from contextlib import contextmanager, nullcontext
from contextvars import ContextVar
from dataclasses import dataclass, field

import numpy as np

from afford.plan.forward import SCENE, ForwardModel, one_blas_thread
from afford.plan.goals import Goal

__all__ = ["PlanStep", "Plan", "best_first", "best_plans", "breadth_first", "success_probability", "search", "inverse_query",
           "watching", "unwatched", "phase", "SAME_PLACE", "UNREACHABLE"]


@dataclass(frozen=True)
class PlanStep:
    behavior: str
    obj: int
    alpha: tuple
    category: int
    probability: float
    predicted: np.ndarray  # the state expected after this step

    def to_json(self) -> dict:
        return {"behavior": self.behavior, "object": self.obj, "alpha": list(self.alpha),
                "category": self.category, "probability": round(self.probability, 4)}


@dataclass
class Plan:
    found: bool
    steps: list[PlanStep] = field(default_factory=list)
    path_probability: float = 0.0      # product of the step probabilities along the plan
    success_probability: float = 0.0   # chance of reaching the goal (open-loop, until assessed)
    expanded: int = 0
    generated: int = 0
    seconds: float = 0.0
    reason: str = ""
    tree: list[dict] = field(default_factory=list)  # the first levels of the search, for reports
    open_loop_probability: float | None = None  # set with success_probability by the search
    replans_assumed: int = 0  # success_probability assumes monitoring with this many replans
    rollouts: int = 0  # imagined executions behind success_probability (0: open-loop figure)
    assess_seconds: float = 0.0  # time those imagined executions took (``seconds`` is the search's)

    def to_json(self) -> dict:
        open_loop = self.success_probability if self.open_loop_probability is None else self.open_loop_probability
        return {"found": self.found, "steps": [s.to_json() for s in self.steps], "length": len(self.steps),
                "path_probability": round(self.path_probability, 4),
                "success_probability": round(self.success_probability, 4),
                "open_loop_probability": round(open_loop, 4), "replans_assumed": self.replans_assumed,
                "rollouts": self.rollouts,
                "expanded": self.expanded, "generated": self.generated, "seconds": round(self.seconds, 4),
                "assess_seconds": round(self.assess_seconds, 4), "reason": self.reason}


#: Who hears how far a search or an assessment has got (:func:`watching`); None: nobody.
_WATCH: ContextVar = ContextVar("afford_plan_watch", default=None)


@contextmanager
def watching(progress):
    """Report the progress of the searches and assessments run inside the block.

    ``progress(description, total)`` is called as a search starts (``total``: its node
    budget; the search may end well before it) and as :func:`plan.monitor.rank_plans`
    starts assessing its candidates (``total``: their imagined runs); it returns a context
    manager that yields ``update(done)``, and is left when that work ends. The searches
    the imagined runs replan with are not reported (they are the assessment's work).
    """
    token = _WATCH.set(progress)
    try:
        yield
    finally:
        _WATCH.reset(token)


@contextmanager
def unwatched():
    """Within the block, searches and assessments report to nobody (an assessment's own
    imagined replans are its work, not searches of their own)."""
    token = _WATCH.set(None)
    try:
        yield
    finally:
        _WATCH.reset(token)


def phase(description: str, total: int):
    """A context manager yielding ``update(done)`` for work that :func:`watching` reports
    (one that ignores it elsewhere)."""
    watch = _WATCH.get()
    return nullcontext(_ignore) if watch is None else watch(description, total)


def _ignore(done: int) -> None:
    pass


def _key(state: np.ndarray, held: int = -1) -> bytes:
    """States within a centimetre (and a hundredth of a histogram bin) of each other, with
    the same object in the hand, are one."""
    return np.round(state, 2).tobytes() + held.to_bytes(2, "little", signed=True)


#: Two situations of an object closer than this (metres, every position feature) are the same.
SAME_PLACE = 0.05
#: The behaviour of an ``avoid`` entry that says the arm could not reach the object there:
#: no behaviour on that object is tried again in the same situation.
UNREACHABLE = "*"
#: Extra search cost (nats) of a behaviour for each time it surprised the robot on that object
#: elsewhere: the model erred there once, so the planner trusts it half as much.
DISTRUST = math.log(2.0)


def situation(model: ForwardModel, state: np.ndarray, obj: int) -> np.ndarray:
    """What says where an entity is: its geometry features (every row's, for a step on the scene)."""
    cols = _geometry(model)
    return state[:, cols].ravel() if obj == SCENE else state[obj, cols]


def _geometry(model: ForwardModel) -> np.ndarray:
    return model.schema.geometry


def _same_place(model: ForwardModel, f: np.ndarray, g: np.ndarray) -> bool:
    """Two situations closer than their features' goal tolerance (SAME_PLACE for the table's
    positions) are the same."""
    if f.shape != g.shape:
        return False
    tol = model.schema.tolerances[_geometry(model)]
    if f.size != tol.size:  # a step on the scene: every row's geometry
        tol = np.resize(tol, f.size)
    return bool((np.abs(f - g) < tol).all())


def _distrust(avoid: tuple, state: np.ndarray, behavior: str, obj: int, held: int = -1,
              model: ForwardModel | None = None) -> float:
    """Extra search cost of ``behavior`` on ``obj`` after it surprised the robot.

    ``avoid`` holds (entity situation before, behaviour, object, whether the hand held it)
    of steps whose outcome surprised the robot during execution. Each such surprise costs
    2 * DISTRUST where the object is in the same situation again (its geometry features
    within their goal tolerance: SAME_PLACE for the table's positions) and DISTRUST
    elsewhere: the model erred there, and would predict the same again.

    The hand splits situations in two. A surprise on an object the hand held says nothing
    about the same behaviour on that object lying on the table (the model sees another
    object vector, and the behaviour does something else to it), and the other way round.
    It does say something about every other behaviour on that object while it is held
    again, which costs DISTRUST too: every behaviour starts by opening the hand, so what
    follows begins with the same drop, and the model saw the held object with the hand
    hiding its shape, so whatever misled it about one behaviour misleads it about the others.

    An entry whose behaviour is :data:`UNREACHABLE` says the arm did not start because the
    object lay beyond its reach: every behaviour on that object in the same situation
    costs ``inf`` (the search leaves it out).
    """
    f = situation(model, state, obj)
    now_held = held == obj
    cost = 0.0
    for g, b, i, in_hand in avoid:
        if i != obj or in_hand != now_held:
            continue
        same = _same_place(model, f, g)
        if b == UNREACHABLE:
            if same:
                return math.inf  # the arm did not start there: it cannot, whatever it does
            continue
        if b == behavior:
            cost += 2 * DISTRUST if same else DISTRUST
        elif in_hand:
            cost += DISTRUST
    return cost


#: An outcome that moves no feature of the object more than this share of its goal
#: tolerance (half a centimetre of the table's positions) is no change at all.
NO_OP = 0.1


def _no_op(model: ForwardModel, before: np.ndarray, after: np.ndarray, obj: int) -> bool:
    """Neither visibility nor geometry moved (histograms jitter with the view)."""
    cols, limit = _no_op_columns(model.schema)
    rows = slice(None) if obj == SCENE else obj
    return bool((np.abs(after[rows][..., cols] - before[rows][..., cols]) < limit).all())


_NO_OP_COLUMNS: dict = {}


def _no_op_columns(schema) -> tuple[np.ndarray, np.ndarray]:
    """The columns :func:`_no_op` compares (geometry and visibility) and their limits, once per schema."""
    key = id(schema)
    hit = _NO_OP_COLUMNS.get(key)
    if hit is None or hit[0] is not schema:
        cols = schema.geometry if schema.visibility_index is None else np.append(schema.geometry, schema.visibility_index)
        hit = _NO_OP_COLUMNS[key] = (schema, cols, NO_OP * schema.tolerances[cols])
    return hit[1], hit[2]


def _actions(model: ForwardModel, state: np.ndarray, goal: Goal | None = None, held: int = -1):
    """(behaviour, object, alpha) to try. A behaviour changes only its own object (chapter
    8), so when the goal names its objects (no ``*``) acting on any other cannot help. A
    behaviour without a target acts on the scene (object :data:`plan.forward.SCENE`).

    While the hand holds object ``held``, and the goal may be about it, only that object
    is acted on: a behaviour on another one would first open the hand and drop it, an
    effect on an object the behaviour is not about, which no predictor was trained to
    foresee."""
    named = goal.objects() if goal is not None and all(c.obj != "*" for c in goal.constraints) else None
    only = held if held >= 0 and (named is None or held in named) else None
    for b, behavior in enumerate(model.behaviors):
        if behavior.target is None:
            for alpha in model.alphas(b):
                yield b, SCENE, alpha
    for obj in range(state.shape[0]):
        if not model.visible(state[obj]) or (named is not None and obj not in named) or (only is not None and obj != only):
            continue
        for b, behavior in enumerate(model.behaviors):
            if behavior.target is None:
                continue
            for alpha in model.alpha_choices(state[obj], b):
                yield b, obj, alpha


def best_first(model: ForwardModel, start: np.ndarray, goal: Goal, *, max_depth: int = 4, max_nodes: int = 20000,
               heuristic_weight: float = 0.0, avoid: tuple = (), held: int = -1, open_loop: bool = True) -> Plan:
    """Most probable plan.

    ``held``: the object in the hand at the start (-1: none); see :func:`_actions`.
    ``open_loop``: set the plan's open-loop success probability (False: leave it 0, for a
    caller that only runs the plan, as imagined replans do; it costs a walk over every
    outcome of every step).

    ``avoid`` lists steps that surprised the robot during execution (see :func:`_distrust`):
    they cost more, so the search tries something else first, yet a behaviour that is the
    only way left is still used. The plan's probabilities stay the model's; only the order
    of the search changes.
    """
    return best_plans(model, start, goal, 1, max_depth=max_depth, max_nodes=max_nodes,
                      heuristic_weight=heuristic_weight, avoid=avoid, held=held, open_loop=open_loop)[0]


@one_blas_thread
def best_plans(model: ForwardModel, start: np.ndarray, goal: Goal, n_plans: int, *, max_depth: int = 4,
               max_nodes: int = 20000, heuristic_weight: float = 0.0, avoid: tuple = (), held: int = -1,
               open_loop: bool = True) -> list[Plan]:
    """The ``n_plans`` most probable plans with different behaviour sequences, best first.

    The search goes on past the first plan until it has popped ``n_plans`` goal nodes whose
    (behaviour, object, alpha) sequences differ (two outcome paths of the same sequence are
    one plan to execute), or the frontier or node budget runs out. A failed search returns
    one plan that says why; otherwise only found plans are returned. Each plan's search
    effort counts everything expanded up to it.
    """
    if goal.holds(start):
        return [Plan(True, [], 1.0, 1.0, 0, 0, 0.0, "the goal holds already")]
    with phase("searching (nodes expanded / budget)", max_nodes) as tick:
        return _best_plans(model, start, goal, n_plans, max_depth, max_nodes, heuristic_weight, avoid, held,
                           open_loop, tick)


def _best_plans(model: ForwardModel, start: np.ndarray, goal: Goal, n_plans: int, max_depth: int, max_nodes: int,
                heuristic_weight: float, avoid: tuple, held: int, open_loop: bool, tick) -> list[Plan]:
    """:func:`best_plans`; ``tick(expanded)`` hears each expansion."""
    t0 = time.perf_counter()
    found: list[Plan] = []
    sequences: set[tuple] = set()
    counter = 0
    frontier = [(heuristic_weight * goal.distance(start), goal.distance(start), counter, 0.0, start, (), False, held)]
    best_cost: dict[bytes, float] = {_key(start, held): 0.0}
    expanded = generated = 0
    tree: list[dict] = []
    pending: list[np.ndarray] = []
    while frontier:
        _, _, _, cost, state, steps, done, held = heapq.heappop(frontier)
        if done:
            sequence = tuple((s.behavior, s.obj, s.alpha) for s in steps)
            if sequence in sequences:
                continue
            sequences.add(sequence)
            plan = Plan(True, list(steps), math.exp(-cost), 0.0, expanded, generated, 0.0)
            if open_loop:
                plan.success_probability = success_probability(model, start, goal, plan.steps)
            plan.seconds = time.perf_counter() - t0
            plan.tree = tree
            found.append(plan)
            if len(found) >= n_plans:
                return found
            continue
        if len(steps) >= max_depth:
            continue
        if expanded >= max_nodes:
            return found or [Plan(False, [], 0.0, 0.0, expanded, generated, time.perf_counter() - t0,
                                  f"node budget of {max_nodes} expansions spent", tree)]
        expanded += 1
        tick(expanded)
        # Predictions wait until a node needs them, then come for every vector met so far
        # in one batch per behaviour: scikit-learn's per-call overhead, not the rows, is
        # what a planning search pays for.
        if any(not model.cached(state[i]) for i in range(state.shape[0]) if model.visible(state[i])):
            model.prefetch(pending + [state[i] for i in range(state.shape[0])])
            pending = []
        for b, obj, alpha in _actions(model, state, goal, held):
            penalty = _distrust(avoid, state, model.names[b], obj, held, model) if avoid else 0.0
            if penalty == math.inf:
                continue
            for out in model.outcomes(state, obj, b, alpha):
                generated += 1
                if _no_op(model, state, out.state, obj):
                    continue  # an outcome that changes nothing cannot be part of a shortest way
                gaps = goal.gaps(out.state)
                if len(steps) + 1 + goal.min_steps(out.state, gaps) > max_depth:
                    continue  # too many objects still to change in the steps left
                c = cost - math.log(max(out.probability, 1e-12)) + penalty
                now_held = obj if model.in_hand(state, out.state, obj) else -1
                reached = goal.holds(out.state, gaps)
                k = _key(out.state, now_held)
                # a state reached more cheaply before is not searched again; but another way
                # to the goal is another plan when several are wanted (two sequences that
                # knock an object off from where it stands end in the same state)
                if not (reached and n_plans > 1):
                    if best_cost.get(k, math.inf) <= c + 1e-12:
                        continue
                    best_cost[k] = c
                step = PlanStep(model.names[b], obj, alpha, out.category, out.probability, out.state)
                h = goal.distance(out.state, gaps)
                if len(steps) < 1:
                    tree.append({"depth": 1, **step.to_json(), "distance": round(h, 3)})
                counter += 1
                heapq.heappush(frontier, (c + heuristic_weight * h, h, counter, c, out.state, steps + (step,),
                                          reached, now_held))
                if len(steps) + 1 < max_depth:
                    pending.extend(out.state if obj == SCENE else [out.state[obj]])
    return found or [Plan(False, [], 0.0, 0.0, expanded, generated, time.perf_counter() - t0,
                          f"no plan of at most {max_depth} steps reaches the goal", tree)]


@one_blas_thread
def breadth_first(model: ForwardModel, start: np.ndarray, goal: Goal, *, max_depth: int = 4,
                  max_nodes: int = 20000, avoid: tuple = (), held: int = -1, open_loop: bool = True) -> Plan:
    """Forward chaining over each behaviour's most probable outcome (thesis chapter 7).
    ``open_loop``: as for :func:`best_first`."""
    if goal.holds(start):
        return Plan(True, [], 1.0, 1.0, 0, 0, 0.0, "the goal holds already")
    with phase("searching (nodes expanded / budget)", max_nodes) as tick:
        return _breadth_first(model, start, goal, max_depth, max_nodes, avoid, held, open_loop, tick)


def _breadth_first(model: ForwardModel, start: np.ndarray, goal: Goal, max_depth: int, max_nodes: int, avoid: tuple,
                   held: int, open_loop: bool, tick) -> Plan:
    """:func:`breadth_first`; ``tick(expanded)`` hears each expansion."""
    t0 = time.perf_counter()
    level = [(start, (), held)]
    seen = {_key(start, held)}
    expanded = generated = 0
    for _ in range(max_depth):
        nxt = []
        for state, steps, held in level:
            if expanded >= max_nodes:
                return Plan(False, [], 0.0, 0.0, expanded, generated, time.perf_counter() - t0,
                            f"node budget of {max_nodes} expansions spent")
            expanded += 1
            tick(expanded)
            for b, obj, alpha in _actions(model, state, goal, held):
                if avoid and _distrust(avoid, state, model.names[b], obj, held, model) >= 2 * DISTRUST:
                    continue  # chaining has no costs: a step that failed here is simply not retried
                outs = model.outcomes(state, obj, b, alpha)
                if not outs:
                    continue
                out = outs[0]
                generated += 1
                if _no_op(model, state, out.state, obj) or len(steps) + 1 + goal.min_steps(out.state) > max_depth:
                    continue
                now_held = obj if model.in_hand(state, out.state, obj) else -1
                k = _key(out.state, now_held)
                if k in seen:
                    continue
                seen.add(k)
                new = steps + (PlanStep(model.names[b], obj, alpha, out.category, out.probability, out.state),)
                if goal.holds(out.state):
                    plan = Plan(True, list(new), float(np.prod([s.probability for s in new])), 0.0, expanded, generated)
                    if open_loop:
                        plan.success_probability = success_probability(model, start, goal, plan.steps)
                    plan.seconds = time.perf_counter() - t0
                    return plan
                nxt.append((out.state, new, now_held))
        level = nxt
    return Plan(False, [], 0.0, 0.0, expanded, generated, time.perf_counter() - t0,
                f"no plan of at most {max_depth} steps reaches the goal")


def success_probability(model: ForwardModel, start: np.ndarray, goal: Goal, steps: list[PlanStep]) -> float:
    """P(the goal holds after some step | the plan's behaviours run open-loop), by the model."""

    def walk(state: np.ndarray, i: int) -> float:
        if goal.holds(state):
            return 1.0
        if i == len(steps):
            return 0.0
        s = steps[i]
        b = model.index(s.behavior)
        return sum(o.probability * walk(o.state, i + 1) for o in model.outcomes(state, s.obj, b, s.alpha, floor=1e-4))

    return float(min(1.0, walk(start, 0)))


def search(model: ForwardModel, start: np.ndarray, goal: Goal, method: str = "best-first", **limits) -> Plan:
    if method == "bfs":
        limits.pop("heuristic_weight", None)
        return breadth_first(model, start, goal, **limits)
    return best_first(model, start, goal, **limits)


def inverse_query(model: ForwardModel, state: np.ndarray, goal: Goal) -> list[dict]:
    """Rank every (object, behaviour, alpha) by the probability that one step makes ``goal`` hold.

    The thesis names this question, "which behaviour, with which parameter, most likely
    produces this effect on this object?", as its most valuable missing piece (12.2).
    """
    ranked = []
    for b, obj, alpha in _actions(model, state):
        p = sum(o.probability for o in model.outcomes(state, obj, b, alpha, floor=0.0) if goal.holds(o.state))
        ranked.append({"object": obj, "behavior": model.names[b], "alpha": list(alpha), "probability": round(p, 4)})
    ranked.sort(key=lambda r: (-r["probability"], r["object"], r["behavior"]))
    return ranked
