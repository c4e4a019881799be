"""Exploration (Algorithm 5): the loop, the records, reproducibility across workers."""

from __future__ import annotations

import numpy as np

from afford.features import OUTCOMES
from afford.sim.explore import MOVED, explore, run_episode
from afford.sim.registry import get_scene


def test_episodes_follow_algorithm_5():
    scene = get_scene("table")()
    for episode in range(12):
        data = run_episode(scene, seed=11, episode=episode, max_steps=6)
        n = len(data)
        assert 1 <= n <= 6
        # rows chain: each interaction starts from where the previous one ended
        assert np.array_equal(data.before[1:], data.after[:-1])
        for i in range(n - 1):  # the loop went on only while the object was seen and moved
            assert data.after[i, 0] == 1.0
            assert np.abs(data.after[i, 1:7] - data.before[i, 1:7]).max() > MOVED
        last = data.after[-1]
        stopped = last[0] == 0.0 or np.abs(last[1:7] - data.before[-1, 1:7]).max() <= MOVED or n == 6
        assert stopped


def test_ground_truth_labels_agree_with_perception():
    scene = get_scene("table")()
    data = explore(scene, episodes=24, seed=2)
    outcome = data.truth["outcome"]
    vanished = data.after[:, 0] == 0
    gone = np.isin(outcome, [OUTCOMES.index("fell"), OUTCOMES.index("left-view")])
    assert np.array_equal(vanished, gone)
    # an arm that did not start touched nothing and changed nothing
    idle = ~data.truth["reachable"]
    assert not data.truth["contact"][idle].any()
    assert set(outcome[idle & ~data.truth["in_hand_before"]]) <= {OUTCOMES.index("no-change")}


def test_same_seed_same_arrays_whatever_the_workers():
    scene = get_scene("table")()
    one = explore(scene, interactions=40, seed=9, workers=1, chunk=3)
    two = explore(scene, interactions=40, seed=9, workers=2, chunk=3)
    assert len(one) == len(two) == 40
    for name in ("before", "after", "behavior", "params", "episode", "step"):
        assert getattr(one, name).tobytes() == getattr(two, name).tobytes(), name
    for name in one.truth:
        assert one.truth[name].tobytes() == two.truth[name].tobytes(), name
    other = explore(scene, interactions=40, seed=10, workers=1)
    assert other.before.tobytes() != one.before.tobytes()


def test_progress_is_reported_up_to_the_total():
    scene = get_scene("table")()
    seen = []
    explore(scene, episodes=5, seed=0, chunk=2, progress=lambda done, total: seen.append((done, total)))
    assert seen[-1] == (5, 5)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


def test_an_exploration_to_n_rows_runs_few_episodes_more_than_it_needs():
    """The hand's episodes yield 6-7 rows each, not the table's 2: the first batch measures
    the rate instead of guessing it (a fixed guess of 2 ran three times the episodes)."""
    scene = get_scene("grasp")()
    ran = []
    data = explore(scene, interactions=30, seed=4, workers=1, chunk=2,
                   on_done=lambda pairs: ran.extend(e for e, _ in pairs))
    assert len(data) == 30
    rows = np.bincount(data.episode)
    needed = int(np.flatnonzero(np.cumsum(rows) >= 30)[0]) + 1  # episodes the 30 rows come from
    assert rows[:needed].mean() > 3, "the premise: an episode of the hand yields several rows"
    assert len(ran) <= needed + 2, (len(ran), needed)
