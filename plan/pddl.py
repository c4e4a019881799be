"""A learned model as PDDL, for off-the-shelf planners (Fast Downward through unified-planning).

afford plans in the robot's perceptual space: an object is a feature vector, and a
behaviour's effect category moves it by the effect the forward model predicts for that
category and object (:mod:`plan.forward`: its most similar members' mean, or the prototype).
PDDL wants finite symbols, so the vectors the model can reach become them:

* **Situations.** From each perceived object, the forward model is chained breadth-first
  (up to ``max_depth`` steps): every vector it predicts is a situation ``sK`` (vectors equal
  to the centimetre are one, as in the search). An object is ``(at ?o ?s)`` in one of them.
* **Discretised feature predicates.** Static facts about situations: ``(visible ?s)``, and
  one predicate per goal condition (``(x_min-above-0p15 ?s)``: feature ``x_min`` of that
  situation is above 0.15), true where the forward model puts the vector there.
* **Operators.** In the deterministic domain, one operator per (behaviour, category), with
  the static relation ``(likely-b-cK ?from ?to)`` listing where the category is the behaviour's
  most likely outcome: the model determinised at its most likely outcome. Each step costs
  ``round(-100 ln p) + 1`` (``:action-costs``, p the outcome's probability), so a planner
  that minimises cost looks for the most probable plan, as afford's own search does. In the PPDDL
  domain, one grounded action per (behaviour, situation) whose ``probabilistic`` effect
  carries the calibrated probability of every category (times P(known); the rest of the
  mass is "nothing the model knows", which leaves the state as it is), chained over every
  outcome of at least ``min_probability`` up to ``max_situations`` situations.
* **The hand.** A behaviour that raises its object leaves it ``(holding ?o)``; every
  behaviour first opens the hand, and none acts on another object while one is held
  (afford's own search allows that when the goal is not about the held object).

The goal is ``(done)``, which the action ``finish`` sets when every constraint holds: one
on object I as ``(at oI ?s) (cond ?s)``, a ``*`` constraint the same for some object (a
conjunction of parameterised preconditions, so no existential goal and no axioms: A* with
LM-cut, which takes neither, solves it optimally). A relative constraint (``0-1:x=...``)
relates two objects' features, which per-object situations cannot express: it is refused.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from afford.features.errors import DataError
from afford.plan.forward import ForwardModel
from afford.plan.goals import Constraint, Goal

__all__ = ["PddlTask", "build_task", "PddlError", "decode_step"]


class PddlError(DataError):
    """A task PDDL cannot express."""


@dataclass
class _Edge:
    src: int
    behavior: int
    category: int
    probability: float
    dst: int
    raises: bool


@dataclass
class PddlTask:
    """Domain and problem texts (deterministic PDDL and PPDDL) and what their symbols mean."""

    domain: str
    problem: str
    ppddl_domain: str
    ppddl_problem: str
    situations: list[np.ndarray]          # sK -> its feature vector
    start: list[int]                      # object i starts in situation start[i]
    behaviors: list[str]
    deterministic_edges: int = 0
    probabilistic_actions: int = 0
    truncated: bool = False               # the PPDDL chaining hit max_situations
    actions: dict[str, str] = field(default_factory=dict)  # action name -> behaviour

    def summary(self) -> dict:
        return {"situations": len(self.situations), "objects": len(self.start), "operators": self._operators(),
                "deterministic_edges": self.deterministic_edges, "probabilistic_actions": self.probabilistic_actions,
                "truncated": self.truncated}

    def _operators(self) -> int:
        """The deterministic domain's operators, one per (behaviour, category) it uses."""
        return len(set(self.actions) & set(re.findall(r"^\s*\(:action (\S+)", self.domain, re.M)))


def _symbol(text: str) -> str:
    """A PDDL name: letters, digits, '-' and '_' (a '.' becomes 'p', a '-' sign 'm')."""
    out = re.sub(r"[^A-Za-z0-9_-]", "_", text.replace(".", "p"))
    return out if out[:1].isalpha() else f"f{out}"


def _op_name(behavior: str, category: int) -> str:
    return _symbol(f"{behavior}-c{category}")


def decode_step(name: str, args: list[str], task: PddlTask) -> tuple[str, int]:
    """(behaviour, object index) of a plan step, from its action name and arguments."""
    behavior = task.actions.get(name.lower())
    if behavior is None or not args or not re.fullmatch(r"o\d+", str(args[0])):
        raise PddlError(f"the plan step {name} {' '.join(map(str, args))} is no action of this task")
    return behavior, int(str(args[0])[1:])


def _condition_name(c: Constraint) -> str:
    word = {"=": "near", "<": "below", ">": "above"}[c.op]
    value = f"{c.value:g}".replace("-", "m")
    tail = f"-{c.tolerance:g}".replace("-", "-pm") if c.op == "=" else ""
    return _symbol(f"{c.name}-{word}-{value}{tail}")


def _holds(c: Constraint, f: np.ndarray) -> bool:
    v = float(f[c.feature])
    if c.op == "<":
        return v <= c.value
    if c.op == ">":
        return v >= c.value
    return abs(v - c.value) <= c.tolerance


class _Graph:
    """Situations (entity vectors, deduplicated to the centimetre) and the edges between them."""

    def __init__(self, fm: ForwardModel):
        self.fm = fm
        self.vectors: list[np.ndarray] = []
        self.index: dict[bytes, int] = {}

    def add(self, f: np.ndarray) -> tuple[int, bool]:
        key = np.round(f, 2).tobytes()
        if key in self.index:
            return self.index[key], False
        self.index[key] = len(self.vectors)
        self.vectors.append(np.asarray(f, dtype=float))
        return self.index[key], True

    def chain(self, starts: list[np.ndarray], max_depth: int, *, every: bool, floor: float,
              max_situations: int) -> tuple[list[int], list[_Edge], bool]:
        """Breadth-first from each start: the most likely outcome of every behaviour
        (``every``: each outcome of at least ``floor``), up to ``max_depth`` steps."""
        from afford.plan.search import _no_op

        fm = self.fm
        first = [self.add(f)[0] for f in starts]
        level = list(dict.fromkeys(first))
        edges: list[_Edge] = []
        truncated = False
        for _ in range(max_depth):
            level = [s for s in level if fm.visible(self.vectors[s])]
            if not level:
                break
            fm.prefetch([self.vectors[s] for s in level])  # one batch of predictions per level
            following = []
            for s in level:
                state = self.vectors[s][None, :]
                for b in range(len(fm.behaviors)):
                    outs = fm.outcomes(state, 0, b, (), floor=floor if every else 0.0)
                    for out in outs if every else outs[:1]:
                        nxt = out.state[0]
                        if _no_op(fm, state, out.state, 0):
                            continue
                        if len(self.vectors) >= max_situations and np.round(nxt, 2).tobytes() not in self.index:
                            truncated = True
                            continue
                        t, new = self.add(nxt)
                        if new:
                            following.append(t)
                        edges.append(_Edge(s, b, int(out.category), float(out.probability), t,
                                           fm.in_hand(state, out.state, 0)))
            level = following
        return first, edges, truncated


def _check(fm: ForwardModel, goal: Goal) -> None:
    if not fm.predicts_effects:
        raise PddlError("PDDL needs a model that predicts effects; this model's labels were given (it predicts "
                        "whether a behaviour succeeds, not what changes)")
    if any(b.target is None for b in fm.behaviors):
        raise PddlError("a behaviour without a target changes every object at once, which this PDDL's per-object "
                        "situations cannot express")
    if any(b.parameters for b in fm.behaviors):
        raise PddlError("behaviours with parameters are not written as PDDL yet; plan them with afford plan")
    for c in goal.constraints:
        if isinstance(c.obj, tuple):
            raise PddlError(f"the goal {c.text()} relates two objects' features, which PDDL over per-object "
                            "situations cannot express; plan it with afford plan")


def _finish(goal: Goal) -> list[str]:
    """The ``finish`` action: it checks the whole goal at once and sets ``(done)``, the
    problem's goal. A plain conjunction of parameterised preconditions, so that planners
    need neither existential goals nor the axioms they compile into (A* with LM-cut takes
    neither)."""
    params, pre = [], []
    named: dict[int, list[Constraint]] = {}
    for k, c in enumerate(goal.constraints):
        if c.obj == "*":
            params.append(f"?a{k} - obj ?t{k} - situation")
            pre.append(f"(at ?a{k} ?t{k}) ({_condition_name(c)} ?t{k})")
        else:
            named.setdefault(int(c.obj), []).append(c)
    for i, cs in sorted(named.items()):
        params.append(f"?s{i} - situation")
        pre.append(f"(at o{i} ?s{i}) " + " ".join(f"({_condition_name(c)} ?s{i})" for c in cs))
    return ["  ; the goal, checked at once: " + " and ".join(goal.to_json()),
            "  (:action finish",
            f"    :parameters ({' '.join(params)})",
            f"    :precondition (and {' '.join(pre)})",
            "    :effect (done))"]


def _static_facts(graph: _Graph, goal: Goal, fm: ForwardModel) -> list[str]:
    facts = []
    conds = {(_condition_name(c)): c for c in goal.constraints}
    for s, f in enumerate(graph.vectors):
        if fm.visible(f):
            facts.append(f"(visible s{s})")
        for name, c in conds.items():
            if _holds(c, f):
                facts.append(f"({name} s{s})")
    return facts


def _situation_comments(graph: _Graph, fm: ForwardModel) -> list[str]:
    cols = fm.schema.geometry[:8]
    lines = []
    for s, f in enumerate(graph.vectors):
        where = ", ".join(f"{fm.schema.names[i]} {f[i]:.3f}" for i in cols)
        lines.append(f";   s{s}: {'seen' if fm.visible(f) else 'unseen'}; {where}")
    return lines


_REQUIREMENTS = ":strips :typing :negative-preconditions :disjunctive-preconditions"


def _hand(raises: bool) -> str:
    return "(holding ?o) (not (hand-free))" if raises else "(hand-free) (not (holding ?o))"


def _operators(fm: ForwardModel, edges: list[_Edge]) -> dict[str, tuple[int, int, bool]]:
    """Operator name -> (behaviour, category, raises). Whether a step raises its object is
    mostly the category's; should one category both raise and not (its members' effects
    differ from object to object), it gets an operator for each."""
    kinds = {(e.behavior, e.category, e.raises) for e in edges}
    ops = {}
    for b, c, r in sorted(kinds):
        both = (b, c, not r) in kinds
        ops[_op_name(fm.names[b], c) + ("-grasp" if both and r else "")] = (b, c, r)
    return ops


def _edge_op(fm: ForwardModel, ops: dict, e: _Edge) -> str:
    return next(name for name, (b, c, r) in ops.items() if (b, c, r) == (e.behavior, e.category, e.raises))


def _constants(n_objects: int) -> str:
    """The perceived objects, as domain constants (the goal's ``finish`` names them)."""
    return "  (:constants " + " ".join(f"o{i}" for i in range(n_objects)) + " - obj)"


def _domain(name: str, fm: ForwardModel, goal: Goal, edges: list[_Edge], n_objects: int) -> str:
    conds = sorted({_condition_name(c) for c in goal.constraints})
    ops = _operators(fm, edges)
    lines = [f"(define (domain {name})",
             f"  (:requirements {_REQUIREMENTS} :action-costs)",
             "  (:types obj situation)", _constants(n_objects),
             "  (:predicates (at ?o - obj ?s - situation) (holding ?o - obj) (hand-free) (done)",
             "               (visible ?s - situation) " + " ".join(f"({c} ?s - situation)" for c in conds),
             "               " + " ".join(f"(likely-{op} ?from ?to - situation)" for op in ops) + ")",
             "  (:functions (total-cost) - number " + " ".join(
                 f"(cost-{op} ?from ?to - situation) - number" for op in ops) + ")"]
    for op, (b, c, raises) in ops.items():
        lines += [f"  ; {fm.names[b]} where its most likely effect is category {c}"
                  + (" (it raises the object into the hand)" if raises else ""),
                  f"  (:action {op}",
                  "    :parameters (?o - obj ?from ?to - situation)",
                  f"    :precondition (and (not (done)) (at ?o ?from) (visible ?from) (likely-{op} ?from ?to)"
                  " (or (hand-free) (holding ?o)))",
                  f"    :effect (and (not (at ?o ?from)) (at ?o ?to) {_hand(raises)}"
                  f" (increase (total-cost) (cost-{op} ?from ?to))))"]
    lines += _finish(goal) + [")"]
    return "\n".join(lines) + "\n"


def step_cost(probability: float) -> int:
    """A step's integer cost: ``round(-100 ln p) + 1`` (planners want positive integers)."""
    return int(round(-100.0 * np.log(max(probability, 1e-9)))) + 1


def _problem(name: str, domain: str, graph: _Graph, start: list[int], facts: list[str], goal_text: str,
             comments: list[str], costs: list[str] | None = None) -> str:
    sits = " ".join(f"s{s}" for s in range(len(graph.vectors)))
    init = ["(hand-free)"] + [f"(at o{i} s{s})" for i, s in enumerate(start)] + facts
    if costs is not None:
        init += ["(= (total-cost) 0)"] + costs
    lines = ["; situations (the entity vectors they stand for; geometry features):", *comments,
             f"(define (problem {name}) (:domain {domain})",
             f"  (:objects {sits} - situation)",
             "  (:init " + "\n         ".join(init) + ")",
             f"  (:goal {goal_text})" + ("" if costs is None else "\n  (:metric minimize (total-cost))") + ")"]
    return "\n".join(lines) + "\n"


def _ppddl(name: str, fm: ForwardModel, goal: Goal, graph: _Graph, edges: list[_Edge], n_objects: int) -> str:
    conds = sorted({_condition_name(c) for c in goal.constraints})
    lines = [f"(define (domain {name})",
             f"  (:requirements {_REQUIREMENTS} :probabilistic-effects)",
             "  (:types obj situation)", _constants(n_objects),
             "  (:predicates (at ?o - obj ?s - situation) (holding ?o - obj) (hand-free) (done)",
             "               (visible ?s - situation) " + " ".join(f"({c} ?s - situation)" for c in conds) + ")"]
    by: dict[tuple[int, int], list[_Edge]] = {}
    for e in edges:
        by.setdefault((e.src, e.behavior), []).append(e)
    for (s, b), outs in sorted(by.items()):
        branches = [f"{e.probability:.4f} (and (not (at ?o s{s})) (at ?o s{e.dst}) {_hand(e.raises)})"
                    for e in sorted(outs, key=lambda e: -e.probability)]
        lines += [f"  (:action {_symbol(fm.names[b])}-s{s}",
                  "    :parameters (?o - obj)",
                  f"    :precondition (and (not (done)) (at ?o s{s}) (or (hand-free) (holding ?o)))",
                  "    :effect (probabilistic " + "\n                           ".join(branches) + "))"]
    lines += _finish(goal) + [")"]
    return "\n".join(lines) + "\n"


def build_task(fm: ForwardModel, state: np.ndarray, goal: Goal, *, max_depth: int = 5, name: str = "afford",
               min_probability: float = 0.02, max_situations: int = 1000) -> PddlTask:
    """The PDDL and PPDDL of reaching ``goal`` from the perceived ``state`` (see the module)."""
    _check(fm, goal)
    goal.check_objects(state.shape[0])
    starts = [np.asarray(f, dtype=float) for f in state]
    det = _Graph(fm)
    start, edges, _ = det.chain(starts, max_depth, every=False, floor=0.0, max_situations=max_situations)
    edges_det = edges
    ops = _operators(fm, edges_det)
    statics = [f"(likely-{_edge_op(fm, ops, e)} s{e.src} s{e.dst})" for e in edges_det]
    facts = _static_facts(det, goal, fm) + sorted(set(statics))
    domain = _domain(f"{name}-domain", fm, goal, edges_det, state.shape[0])
    costs = sorted({f"(= (cost-{_edge_op(fm, ops, e)} s{e.src} s{e.dst}) {step_cost(e.probability)})"
                    for e in edges_det})
    problem = _problem(f"{name}-problem", f"{name}-domain", det, start, facts, "(done)",
                       _situation_comments(det, fm), costs)
    prob = _Graph(fm)
    pstart, pedges, truncated = prob.chain(starts, max_depth, every=True, floor=min_probability,
                                           max_situations=max_situations)
    ppddl_domain = _ppddl(f"{name}-domain", fm, goal, prob, pedges, state.shape[0])
    ppddl_problem = _problem(f"{name}-problem", f"{name}-domain", prob, pstart, _static_facts(prob, goal, fm),
                             "(done)", _situation_comments(prob, fm))
    actions = {op.lower(): fm.names[b] for op, (b, _, _) in ops.items()}
    actions.update({f"{_symbol(fm.names[e.behavior])}-s{e.src}".lower(): fm.names[e.behavior] for e in pedges})
    return PddlTask(domain, problem, ppddl_domain, ppddl_problem, det.vectors, start, list(fm.names),
                    deterministic_edges=len(edges_det),
                    probabilistic_actions=len({(e.src, e.behavior) for e in pedges}), truncated=truncated,
                    actions=actions)
