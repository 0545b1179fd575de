"""The UR5 among a bookshelf (examples/bookshelf.scene.yaml): the problem is what it says (start
and goal free, in different compartments, the straight joint line blocked), and RRT-Connect
plans it to a path that the independent dense check passes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armkit
from armkit.io.scene import read_planning_problem
from armkit.planning import Box, CollisionChecker, Cylinder, arm_geometry, plan
from tests.planning import reference

EXAMPLE = Path(__file__).parents[2] / "examples" / "bookshelf.scene.yaml"


@pytest.fixture(scope="module")
def problem():
    return read_planning_problem(EXAMPLE)


@pytest.fixture(scope="module")
def checker(problem):
    return CollisionChecker(problem.robot, problem.scene,
                            arm_geometry(problem.robot, problem.radius),
                            problem.settings["resolution"])


def test_the_scene_is_a_bookshelf(problem):
    assert problem.robot.name == "ur5" and problem.radius == pytest.approx(0.04)
    boxes = [o for o in problem.scene if isinstance(o, Box)]
    cylinders = [o for o in problem.scene if isinstance(o, Cylinder)]
    assert len(boxes) == 6 and len(cylinders) == 4
    plates = sorted(o.pose[2, 3] for o in boxes if o.size[2] < 0.05)
    assert np.allclose(plates, [0.06, 0.41, 0.76])


def test_start_and_goal_free_in_different_compartments(problem, checker):
    robot = problem.robot
    for q in (problem.start, problem.goal[0]):
        assert checker.valid(q)
        assert reference.free_distance(robot, checker.geometry, problem.scene, q) > 0
    tool_start = armkit.fk(robot, problem.start)[:3, 3]
    tool_goal = armkit.fk(robot, problem.goal[0])[:3, 3]
    for tool in (tool_start, tool_goal):                             # between the walls
        assert 0.45 < tool[0] < 0.75 and -0.4 < tool[1] < 0.4
    assert 0.07 < tool_start[2] < 0.40                               # lower compartment
    assert 0.42 < tool_goal[2] < 0.75                                # upper compartment


@pytest.mark.slow
def test_the_straight_joint_line_collides(problem, checker):
    start, goal = problem.start, problem.goal[0]
    assert not checker.edge_valid(start, goal)[0]
    line = start + np.linspace(0, 1, 41)[:, None] * (goal - start)
    gaps = [reference.free_distance(problem.robot, checker.geometry, problem.scene, q)
            for q in line]
    assert np.mean(np.array(gaps) <= 0) > 0.3


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1])
def test_rrtconnect_plans_it_and_the_dense_check_passes(problem, checker, seed):
    result = plan(checker, problem.start, problem.goal, planner="rrtconnect", seed=seed,
                  waypoints=10, time_limit=np.inf)
    assert result.success, result.reason
    assert result.path.shape == (10, 6) and result.iterations > 0
    np.testing.assert_array_equal(result.path[0], problem.start)
    np.testing.assert_allclose(result.path[-1], problem.goal[0], atol=1e-12)
    for path in (result.path, result.raw_path):
        obstacle_gap, self_gap, states = reference.dense_gaps(
            checker.robot, checker.geometry, checker.scene, path, step=0.002, points=60)
        assert states > 100
        assert obstacle_gap > 0 and self_gap > 0
