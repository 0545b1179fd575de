"""Planning end to end: paths re-verified by an independent dense check, unsolvable problems
with their reasons, reproducibility, a user's own validity function with every planner."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.planning import (
    CollisionChecker,
    Scene,
    ValidityFunction,
    default_geometry,
    path_length,
    plan,
    resample,
    resample_keeping_vertices,
    shortcut,
)
from tests.helpers import random_q
from tests.planning import reference
from tests.planning.scenes import SHELF_GOAL, SHELF_START, random_scene, shelf

PLANNERS = ["rrtconnect", "rrt", "rrtstar"]
RESOLUTION = 0.005


@pytest.fixture(scope="module")
def shelf_checker():
    robot = armkit.robot("inspection_6dof")
    return CollisionChecker(robot, shelf(), default_geometry(robot, 0.04), RESOLUTION)




@pytest.mark.parametrize("planner", PLANNERS)
def test_shelf_paths_pass_the_dense_check(shelf_checker, planner):
    result = plan(shelf_checker, SHELF_START, SHELF_GOAL, planner=planner, seed=1, waypoints=10,
                  time_limit=np.inf,
                  max_iterations=300 if planner == "rrtstar" else None)
    assert result.success, result.reason
    assert result.reason == "ok" and result.path.shape == (10, 6)
    np.testing.assert_array_equal(result.path[0], SHELF_START)
    np.testing.assert_allclose(result.path[-1], SHELF_GOAL, atol=1e-12)
    assert result.iterations > 0 and result.states_checked > 0
    assert result.length <= result.raw_length + 1e-9
    assert 0 < result.planning_time <= result.total_time
    assert shelf_checker.path_valid(result.path)
    assert reference.dense_ok(shelf_checker, result.path)
    # Waypoints evenly spaced by arc length along the returned path.
    steps = np.linalg.norm(np.diff(result.path, axis=0), axis=1)
    assert np.ptp(steps) < 1e-9 or len(result.path) > 10 or \
        shelf_checker.path_valid(result.path)


@pytest.mark.parametrize("seed", range(3))
def test_random_scenes(seed):
    robot = armkit.robot("inspection_6dof")
    scene = random_scene(seed + 10, count=6, reach=1.0)
    checker = CollisionChecker(robot, scene, default_geometry(robot, 0.04), RESOLUTION)
    rng = np.random.default_rng(seed)
    Q = random_q(robot, 200, seed=seed)
    start = Q[checker.valid(Q)][0]
    # A valid goal within 1.5 rad per joint that the straight edge does not reach.
    while True:
        goal = np.clip(start + rng.uniform(-1.5, 1.5, 6), robot.lower, robot.upper)
        if checker.valid(goal) and not checker.edge_valid(start, goal)[0]:
            break
    result = plan(checker, start, goal, seed=seed, time_limit=np.inf)
    assert result.success, result.reason
    assert reference.dense_ok(checker, result.path)
    assert reference.dense_ok(checker, result.raw_path)


def test_same_seed_same_path(shelf_checker):
    for planner in PLANNERS:
        kw = dict(planner=planner, waypoints=10, time_limit=np.inf,
                  max_iterations=200 if planner == "rrtstar" else None)
        a = plan(shelf_checker, SHELF_START, SHELF_GOAL, seed=7, **kw)
        b = plan(shelf_checker, SHELF_START, SHELF_GOAL, seed=7, **kw)
        assert a.success and b.success
        np.testing.assert_array_equal(a.path, b.path)
        np.testing.assert_array_equal(a.raw_path, b.raw_path)
        assert a.iterations == b.iterations and a.states_checked == b.states_checked


def test_goal_in_collision_and_start_in_collision(shelf_checker):
    inside = SHELF_GOAL.copy()
    inside[1] += 0.6                         # swings the arm down through a plate
    assert not shelf_checker.valid(inside)
    result = plan(shelf_checker, SHELF_START, inside)
    assert not result.success and result.reason == "goal in collision"
    assert result.path.shape == (0, 6)
    result = plan(shelf_checker, inside, SHELF_GOAL)
    assert result.reason == "start in collision"
    result = plan(shelf_checker, SHELF_START, SHELF_GOAL + 10)
    assert result.reason == "goal outside the joint limits"


@pytest.mark.parametrize("planner", PLANNERS)
def test_enclosed_goal_ends_within_budget(planner):
    """A goal inside a closed ring: every planner stops at its iteration budget with the
    budget's reason."""
    def outside_ring(Q):
        r = np.linalg.norm(Q - 0.5, axis=1)
        return ~((r > 0.2) & (r < 0.25))

    validity = ValidityFunction(outside_ring, [0, 0], [1, 1], resolution=0.005)
    result = plan(validity, [0.05, 0.05], [0.5, 0.5], planner=planner, max_iterations=300,
                  seed=0, time_limit=np.inf)
    assert not result.success
    assert result.reason.startswith("no path within the iteration budget (300 iterations")
    assert result.iterations == 300


@pytest.mark.parametrize("planner", PLANNERS)
def test_user_validity_function_with_every_planner(planner):
    """A point among discs in the unit square, through a plain Python function."""
    centres = np.array([[0.3, 0.3], [0.3, 0.7], [0.7, 0.5], [0.5, 0.15], [0.5, 0.85]])
    radius = 0.14
    calls = []

    def free(Q):
        calls.append(len(Q))
        return np.linalg.norm(Q[:, None] - centres[None], axis=-1).min(axis=1) > radius

    result = plan(free, [0.05, 0.5], [0.95, 0.5], planner=planner, limits=([0, 0], [1, 1]),
                  time_limit=np.inf,
                  resolution=0.002, seed=3, waypoints=12,
                  max_iterations=1500 if planner == "rrtstar" else None)
    assert result.success, result.reason
    assert result.path.shape == (12, 2) and calls
    # Dense check every 0.0005 along the returned polyline.
    dense = np.vstack([a + np.linspace(0, 1, 400)[:, None] * (b - a)
                       for a, b in zip(result.path[:-1], result.path[1:])])
    assert free(dense).all()


def test_direct_edge_first():
    result = plan(armkit.robot("ur5"), np.zeros(6) + 0.1, np.full(6, 0.3), scene=Scene())
    assert result.success and result.iterations == 0 and len(result.raw_path) == 2


def test_goal_pose_every_collision_free_ik_solution_is_a_goal(shelf_checker):
    robot = shelf_checker.robot
    T = armkit.fk(robot, SHELF_GOAL)
    result = plan(shelf_checker, SHELF_START, goal_pose=T, seed=2, waypoints=10,
                  time_limit=np.inf)
    assert result.success, result.reason
    assert len(result.goals) >= 1 and shelf_checker.valid(result.goals).all()
    np.testing.assert_allclose(armkit.fk(robot, result.path[-1]), T, atol=1e-9)
    assert reference.dense_ok(shelf_checker, result.path)


def test_several_goals():
    robot = armkit.robot("ur5")
    goals = np.array([[1.0, -1.0, 1.0, 0, 0, 0], [0.2, 0.1, 0.1, 0.1, 0.1, 0.1]])
    result = plan(robot, np.full(6, 0.1), goals, scene=Scene())
    assert result.success
    np.testing.assert_allclose(result.path[-1], goals[1])


def test_shortcut_and_resample():
    validity = ValidityFunction(lambda Q: np.ones(len(Q), bool), [0, 0], [1, 1])
    zigzag = np.array([[0, 0], [0.5, 0.1], [0.2, 0.3], [1, 1]], float)
    short = shortcut(zigzag, validity, seed=0)
    np.testing.assert_allclose(short, [[0, 0], [1, 1]])
    assert path_length(short) == pytest.approx(np.sqrt(2))
    w = resample([[0, 0], [1, 0], [1, 1]], 5)
    np.testing.assert_allclose(w, [[0, 0], [0.5, 0], [1, 0], [1, 0.5], [1, 1]])
    w = resample_keeping_vertices([[0, 0], [3, 0], [3, 1]], 6)
    assert len(w) == 6 and any(np.allclose(p, [3, 0]) for p in w)
    assert path_length(w) == pytest.approx(4)
    with pytest.raises(InputError, match="waypoints"):
        resample([[0, 0], [1, 1]], 1)
    with pytest.raises(InputError, match="path"):
        resample([0, 1], 3)
    for bad in (-0.1, 1.0, float("nan"), "0.1"):
        with pytest.raises(InputError, match=r"min_gain: expected a fraction .* found"):
            shortcut(zigzag, validity, min_gain=bad)


def test_shortcut_skips_small_savings_but_reduces_vertices():
    """A detour saving less than min_gain is not tried as a random shortcut; the greedy
    vertex reduction still removes its vertex (the straight edge is free)."""
    validity = ValidityFunction(lambda Q: np.ones(len(Q), bool), [0, 0], [1, 1])
    bent = np.array([[0, 0], [0.5, 0.001], [1, 0]], float)
    calls = []

    class Counting(ValidityFunction):
        def interior_free(self, a, b):
            calls.append((a, b))
            return super().interior_free(a, b)

    counting = Counting(validity.function, [0, 0], [1, 1])
    short = shortcut(bent, counting, seed=0, min_gain=0.01)
    np.testing.assert_allclose(short, [[0, 0], [1, 0]])
    assert len(calls) == 1                      # only the reduction's edge 0 -> 2


def test_plan_bad_input(shelf_checker):
    with pytest.raises(InputError, match="planner"):
        plan(shelf_checker, SHELF_START, SHELF_GOAL, planner="prm")
    with pytest.raises(InputError, match="start: expected last axis 6"):
        plan(shelf_checker, [0, 0], SHELF_GOAL)
    with pytest.raises(InputError, match="goal: expected either"):
        plan(shelf_checker, SHELF_START)
    with pytest.raises(InputError, match="limits"):
        plan(lambda Q: np.ones(len(Q), bool), [0, 0], [1, 1])
    with pytest.raises(InputError, match="robot: expected"):
        plan(42, [0, 0], [1, 1])
    with pytest.raises(InputError, match="robot: expected a Robot.*found str"):
        plan("ur5", np.zeros(6), np.ones(6))        # names are loaded by armkit.robot
    for field, value in (("time_limit", -1.0), ("time_limit", float("nan")), ("step", 0.0),
                         ("goal_bias", 2.0), ("max_iterations", 1.5), ("waypoints", 1),
                         ("seed", 0.5), ("shortcut_tries", -1), ("resolution", "x")):
        with pytest.raises(InputError, match=f"{field}: expected"):
            plan(shelf_checker, SHELF_START, SHELF_GOAL, **{field: value})
    with pytest.raises(TypeError):
        plan(shelf_checker, SHELF_START, SHELF_GOAL, colour="red")
    with pytest.raises(InputError, match="goal_pose"):
        plan(lambda Q: np.ones(len(Q), bool), [0, 0], goal_pose=np.eye(4),
             limits=([0, 0], [1, 1]))
    # start and goal go to the checker in one batch
    with pytest.raises(InputError, match="checker: expected 2 booleans for 2 states"):
        plan(lambda Q: np.ones(3, bool), [0, 0], [1, 1], limits=([0, 0], [1, 1]))
