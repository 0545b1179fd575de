"""The compiled planning loop (armkit's own checker): reproducible by seed whatever the trees'
first size, reasons for unsolvable problems, certified paths under an independent dense check,
the compiled checker's calls against the NumPy reference."""

from __future__ import annotations

import numpy as np
import pytest

import armkit
from armkit.errors import InputError
from armkit.planning import (
    CollisionChecker,
    Scene,
    Sphere,
    default_geometry,
    path_length,
    plan,
    shortcut,
)
from armkit.planning.clock import timer
from armkit.planning.compiled import plan_compiled, rng_state, shortcut_compiled
from armkit.planning.planners import planner_named
from tests.helpers import random_q
from tests.planning import reference
from tests.planning.scenes import SHELF_GOAL, SHELF_START, random_scene, shelf

PLANNERS = ["rrtconnect", "rrt", "rrtstar"]


@pytest.fixture(scope="module")
def shelf_checker():
    robot = armkit.robot("inspection_6dof")
    return CollisionChecker(robot, shelf(), default_geometry(robot, 0.04), 0.005)


def step_of(checker):
    return 0.2 * float(np.linalg.norm(checker.upper - checker.lower))


@pytest.mark.slow
@pytest.mark.parametrize("planner", PLANNERS)
def test_same_seed_same_path_whatever_the_first_tree_size(shelf_checker, planner):
    """The trees start with 8 rows and are grown many times, or start large: the same seed
    gives the same path, iterations and states checked; another seed another path."""
    kw = dict(step=step_of(shelf_checker), max_iterations=300 if planner == "rrtstar" else
              100_000, deadline=timer(np.inf))
    planner = planner_named(planner)
    small = plan_compiled(shelf_checker, SHELF_START, SHELF_GOAL[None], planner, seed=4,
                          capacity=8, **kw)
    large = plan_compiled(shelf_checker, SHELF_START, SHELF_GOAL[None], planner, seed=4,
                          capacity=4096, **kw)
    other = plan_compiled(shelf_checker, SHELF_START, SHELF_GOAL[None], planner, seed=5, **kw)
    assert small[3] == large[3] == "ok" and other[3] == "ok"
    np.testing.assert_array_equal(small[0], large[0])
    assert small[1:3] == large[1:3]
    assert small[0].shape != other[0].shape or not np.array_equal(small[0], other[0])
    np.testing.assert_array_equal(small[0][0], SHELF_START)
    np.testing.assert_array_equal(small[0][-1], SHELF_GOAL)
    assert shelf_checker.path_valid(small[0])


def test_seeds_give_their_own_generator_states():
    states = {int(rng_state(s)[0]) for s in range(1000)}
    assert len(states) == 1000
    assert rng_state(3)[0] == rng_state(3)[0] and rng_state(3).dtype == np.uint64


@pytest.mark.parametrize("planner", PLANNERS)
def test_budget_spent_is_a_reason(shelf_checker, planner):
    """Too few iterations for the shelf: a result with the budget's reason, not an
    exception."""
    result = plan(shelf_checker, SHELF_START, SHELF_GOAL, planner=planner, max_iterations=2,
                  seed=0, time_limit=np.inf)
    assert not result.success and result.path.shape == (0, 6)
    assert result.reason.startswith("no path within the iteration budget (2 iterations")
    assert result.iterations == 2 and result.states_checked > 0


TWO_LINK = """name: two_link
units: {length: mm, angle: deg}
convention: dh
joints:
  - {type: revolute, alpha: 0, a: 300, d: 0, theta: 0, limits: [-90, 90]}
  - {type: revolute, alpha: 0, a: 200, d: 0, theta: 0, limits: [-90, 90]}
"""


@pytest.mark.parametrize("planner", PLANNERS)
def test_goal_cut_off_ends_with_the_budget_reason(tmp_path, planner):
    """A planar arm and a ball on its first link's path at q1 = 0: for every q2 the first
    link hits it, so the joint space splits in two halves; start and goal are valid, in
    different halves."""
    path = tmp_path / "two.yaml"
    path.write_text(TWO_LINK)
    robot = armkit.robot(str(path))
    checker = CollisionChecker(robot, Scene([Sphere([0.15, 0.0, 0.0], 0.05)]),
                               default_geometry(robot, 0.02), 0.005)
    q1 = np.linspace(-np.pi / 2, np.pi / 2, 181)
    cut = np.stack([np.zeros(181), q1], axis=1)            # q1 = 0, every q2
    assert not checker.valid(cut).any()
    start, goal = np.deg2rad([-60.0, 0.0]), np.deg2rad([60.0, 0.0])
    assert checker.valid(start) and checker.valid(goal)
    result = plan(checker, start, goal, planner=planner, max_iterations=400, seed=0,
                  time_limit=np.inf)
    assert not result.success and result.path.shape == (0, 2)
    assert result.reason.startswith("no path within the iteration budget (400 iterations")
    assert result.iterations == 400


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(4))
def test_compiled_paths_pass_the_dense_check(shelf_checker, seed):
    """RRT-Connect's raw path, the shortcut path and 10 waypoints: certified and found free by
    the independent dense check."""
    result = plan(shelf_checker, SHELF_START, SHELF_GOAL, seed=seed, waypoints=10,
                  time_limit=np.inf)
    assert result.success, result.reason
    for path in (result.raw_path, result.path):
        assert shelf_checker.path_valid(path)
        assert reference.dense_ok(shelf_checker, path)
    short = shortcut(result.raw_path, shelf_checker, seed=seed)
    assert path_length(short) <= result.raw_length + 1e-9
    assert reference.dense_ok(shelf_checker, short)


def test_compiled_shortcut_on_a_free_scene_ends_straight():
    """With no obstacle every shortcut is free: the path becomes its straight segment."""
    robot = armkit.robot("ur5")
    checker = CollisionChecker(robot, geometry=default_geometry(robot, 0.03), resolution=0.005)
    rng = np.random.default_rng(0)
    q0 = np.array([0.1, -1.2, 1.0, -1.3, -1.5, 0.2])
    path = q0 + np.cumsum(rng.uniform(-0.15, 0.15, (6, 6)), axis=0)
    path[0] = q0
    assert checker.path_valid(path)
    short, checked = shortcut_compiled(checker, path, seed=0, tries=64, deadline=timer(np.inf))
    np.testing.assert_allclose(short, path[[0, -1]], atol=1e-12)
    assert checked > 0


@pytest.mark.slow
def test_random_scene_every_planner():
    robot = armkit.robot("inspection_6dof")
    checker = CollisionChecker(robot, random_scene(21, count=6, reach=1.0),
                               default_geometry(robot, 0.04), 0.005)
    Q = random_q(robot, 400, seed=3)
    Q = Q[checker.valid(Q)]
    for planner in PLANNERS:
        for start, goal in zip(Q[:2], Q[2:4]):
            result = plan(checker, start, goal, planner=planner, seed=1, time_limit=np.inf,
                          max_iterations=400 if planner == "rrtstar" else None)
            if planner == "rrtstar" and not result.success:
                assert result.reason.startswith("no path within the iteration budget")
                continue
            assert result.success, result.reason
            assert reference.dense_ok(checker, result.path)


def test_single_state_call_agrees_with_batch_and_reference(shelf_checker):
    robot = shelf_checker.robot
    Q = random_q(robot, 40, seed=11)
    batch = shelf_checker.clearance(Q)
    one = np.array([shelf_checker.clearance(q) for q in Q])
    np.testing.assert_array_equal(batch, one)
    expected = np.array([reference.free_distance(robot, shelf_checker.geometry,
                                                 shelf_checker.scene, q) for q in Q])
    np.testing.assert_allclose(batch, expected, atol=1e-7)
    valid = shelf_checker.valid(Q)
    np.testing.assert_array_equal(valid, expected > 0)
    for q, v in zip(Q, valid):
        assert shelf_checker.valid(q) == v                          # fast path
        assert shelf_checker.valid(list(q)) == v                    # converted
        ro = q.copy()
        ro.setflags(write=False)
        assert shelf_checker.valid(ro) == v                         # read-only
        assert shelf_checker.valid(np.repeat(q, 2)[::2]) == v        # strided
    assert shelf_checker.valid(Q[0]).shape == ()


def test_single_state_call_refuses_non_finite(shelf_checker):
    q = SHELF_START.copy()
    q[2] = np.nan
    with pytest.raises(InputError, match="finite"):
        shelf_checker.valid(q)
    with pytest.raises(InputError, match="finite"):
        shelf_checker.clearance(np.vstack([SHELF_START, q]))
    with pytest.raises(InputError, match="last axis 6"):
        shelf_checker.valid(np.zeros(5))


@pytest.mark.slow
def test_edges_and_paths_from_python_match_the_dense_reference(shelf_checker):
    robot = shelf_checker.robot
    Q = random_q(robot, 200, seed=8)
    Q = Q[shelf_checker.valid(Q)]
    accepted = 0
    for qa, qb in zip(Q[:-1:2], Q[1::2]):
        qb = qa + 0.15 * (qb - qa)
        free, checked = shelf_checker.edge_valid(qa, qb)
        assert checked >= 2
        obstacle_gap, self_gap, _ = reference.dense_gaps(robot, shelf_checker.geometry,
                                                         shelf_checker.scene, [qa, qb],
                                                         points=40)
        if free:
            accepted += 1
            assert obstacle_gap > 0 and self_gap > 0
    assert accepted >= 5
    assert shelf_checker.path_valid(SHELF_START[None])
    assert not shelf_checker.path_valid(np.vstack([SHELF_START, SHELF_GOAL]))


@pytest.mark.slow
def test_parallel_batch_gives_the_serial_values(shelf_checker):
    """The batch spread over threads (chunks each starting afresh) returns exactly what the
    serial kernel does, exact distances and verdicts alike, and both agree with the
    reference."""
    import os

    from armkit.planning.collision import (
        BATCH_CHUNK,
        states_kernel,
        states_parallel,
    )

    robot = shelf_checker.robot
    M = shelf_checker.arrays
    Q = random_q(robot, 3 * BATCH_CHUNK + 17, seed=12)
    cap = 1e-12
    for floor, top in ((-np.inf, np.inf), (0.0, cap)):
        serial, parallel = np.empty(len(Q)), np.empty(len(Q))
        states_kernel(Q, M, floor, top, serial)
        states_parallel(Q, M, floor, top, parallel)
        np.testing.assert_array_equal(parallel, serial)
    armkit.set_num_threads(os.cpu_count())
    try:
        found = shelf_checker.clearance(Q)
        valid = shelf_checker.valid(Q)
    finally:
        armkit.set_num_threads(None)
    states_kernel(Q, M, -np.inf, np.inf, serial)
    np.testing.assert_array_equal(found, serial)
    np.testing.assert_array_equal(valid, serial > 0)
    some = Q[::97]
    expected = np.array([reference.free_distance(robot, shelf_checker.geometry,
                                                 shelf_checker.scene, q) for q in some])
    np.testing.assert_allclose(found[::97], expected, atol=1e-7)
