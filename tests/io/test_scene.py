"""Scene and planning files: YAML obstacles in file units, MoveIt .scene files, bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import armkit
from armkit.io.scene import read_moveit_scene, read_planning_problem, read_scene
from armkit.planning import Box, Capsule, Cylinder, Sphere

EXAMPLES = Path(__file__).parents[2] / "examples"

HEADER = "units: {length: mm, angle: deg}\n"


def write(tmp_path, text, name="scene.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_example_shelf_file():
    problem = read_planning_problem(EXAMPLES / "shelf.scene.yaml")
    assert problem.robot.name == "inspection_6dof" and problem.radius == pytest.approx(0.04)
    assert len(problem.scene) == 4
    lower = problem.scene.obstacles[0]
    np.testing.assert_allclose(lower.size, [0.45, 1.0, 0.04])
    np.testing.assert_allclose(lower.pose[:3, 3], [0.875, 0, 0.22])
    np.testing.assert_allclose(problem.start, [0.5567789, -1.5882119, 1.3545770, -2.3713940,
                                               2.2182614, -2.4618970], atol=1e-7)
    assert problem.goal.shape == (1, 6)
    assert problem.settings == {"planner": "rrtconnect", "seed": 0, "resolution": 0.005,
                                "time_limit": 10.0, "goal_bias": 0.05, "waypoints": 10,
                                "simplify": True}


def test_every_obstacle_kind_in_file_units(tmp_path):
    path = write(tmp_path, HEADER + """obstacles:
  - {type: box, size: [100, 200, 300], xyz: [500, 0, 0], rpy: [0, 0, 90]}
  - {type: sphere, center: [0, 0, 1000], radius: 50, name: ball}
  - {type: cylinder, radius: 20, length: 400, xyz: [0, 300, 0], rpy: [90, 0, 0]}
  - {type: capsule, a: [0, 0, 0], b: [0, 0, 100], radius: 10}
""")
    box, ball, cylinder, capsule = read_scene(path)
    assert isinstance(box, Box) and isinstance(ball, Sphere)
    assert isinstance(cylinder, Cylinder) and isinstance(capsule, Capsule)
    np.testing.assert_allclose(box.pose[:3, :2], [[0, -1], [1, 0], [0, 0]], atol=1e-12)
    np.testing.assert_allclose(box.pose[:3, 3], [0.5, 0, 0])
    assert ball.radius == pytest.approx(0.05) and ball.name == "ball"
    np.testing.assert_allclose(cylinder.pose[:3, 2], [0, -1, 0], atol=1e-12)  # axis along -y
    assert cylinder.length == pytest.approx(0.4)
    np.testing.assert_allclose(capsule.b, [0, 0, 0.1])


MOVEIT_OLD = """cell
* table
1
box
1.0 2.0 0.1
0.5 0 0.4
0 0 0 1
0.5 0.5 0.5 1
* post
2
cylinder
0.05 1.0
0 0.5 0.5
0 0 0.7071068 0.7071068
1 0 0 1
sphere
0.1
0 0 1.2
0 0 0 1
0 0 1 1
.
"""

MOVEIT_NEW = """cell
* table
1 0 0
0 0 0.7071068 0.7071068
1
box
0.2 0.4 0.1
0.5 0 0
0 0 0 1
0.5 0.5 0.5 1
0
.
"""


def test_moveit_scene_old_and_new_layouts(tmp_path):
    table, post, ball = read_moveit_scene(write(tmp_path, MOVEIT_OLD, "cell.scene"))
    np.testing.assert_allclose(table.size, [1, 2, 0.1])
    np.testing.assert_allclose(table.pose[:3, 3], [0.5, 0, 0.4])
    assert post.radius == 0.05 and post.length == 1.0 and post.name == "post"
    np.testing.assert_allclose(post.pose[:3, :3], armkit.spatial.rotz(np.pi / 2)[:3, :3],
                               atol=1e-6)
    np.testing.assert_allclose(ball.center, [0, 0, 1.2])
    (box,) = read_moveit_scene(write(tmp_path, MOVEIT_NEW, "new.scene"))
    np.testing.assert_allclose(box.pose[:3, 3], [1, 0.5, 0], atol=1e-6)   # object pose first
    # A planning file can bring one.
    path = write(tmp_path, HEADER + "scene: cell.scene\nobstacles:\n"
                 "  - {type: sphere, center: [0, 0, 0], radius: 1}\n")
    assert len(read_scene(path)) == 4


@pytest.mark.parametrize("text, field, found", [
    ("obstacles:\n  - {type: cone, radius: 1}\n", "obstacles[0]", "cone"),
    ("obstacles:\n  - {type: box, size: [1, 2]}\n", "obstacles[0].box.size", ""),
    ("obstacles:\n  - {type: box, min: [0, 0, 0], max: [1, 1, -1]}\n", "obstacles[0].box",
     "max [1.0, 1.0, -1.0]"),
    ("obstacles:\n  - {type: box, min: [0, 0, 0], max: [1, 1, 1], size: [1, 1, 1]}\n",
     "obstacles[0].box", "both"),
    ("obstacles:\n  - {type: sphere, center: [0, 0, 0], radius: -1}\n",
     "obstacles[0].sphere.radius", "-1"),
    ("obstacles:\n  - {type: sphere, centre: [0, 0, 0], radius: 1}\n",
     "obstacles[0].sphere.center", "nothing"),
    ("robot: inspection_6dof\nstart: [0, 0, 0]\ngoal: [0, 0, 0, 0, 0, 0]\n", "start", "3"),
    ("robot: inspection_6dof\nstart: [0, 0, 0, 0, 0, 0]\n", "goal", "nothing"),
    ("robot: nosuchrobot\nstart: [0]\ngoal: [0]\n", "robot", "nosuchrobot"),
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [0, 0, 0, 0, 0, 0]\n"
     "goal_pose: {xyz: [0, 0, 0]}\n", "goal_pose", "both"),
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [0, 0, 0, 0, 0, 0]\n"
     "planner: {name: prm}\n", "planner.name", "prm"),
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [0, 0, 0, 0, 0, 0]\n"
     "planner: {waypoints: 1}\n", "planner.waypoints", "1"),
])
def test_planning_file_bad_input(tmp_path, text, field, found):
    path = write(tmp_path, HEADER + text)
    with pytest.raises(armkit.ModelFileError) as err:
        read_planning_problem(path)
    assert err.value.file == str(path)
    assert err.value.field == field or field in err.value.field, str(err.value)
    assert found in err.value.found, str(err.value)


def test_missing_units(tmp_path):
    with pytest.raises(armkit.ModelFileError) as err:
        read_scene(write(tmp_path, "obstacles: []\n"))
    assert err.value.field == "units" and err.value.found == "nothing"


@pytest.mark.parametrize("text, line, expected", [
    ("cell\n* a\n1\ncone\n1 2\n", "line 4", "box, sphere, cylinder"),
    ("cell\n* a\n1\nbox\n1 2\n", "line 5", "box sizes"),
    ("cell\n* a\n1\nbox\n1 2 x\n", "line 5", "box sizes"),
    ("cell\n* a\n1\nbox\n1 1 1\n0 0 0\n0 0 0 1\n", "line 8", "colour"),
    ("cell\n* a\nmany\n", "line 3", "number of shapes"),
    ("cell\nbox\n", "line 2", "'* object name'"),
    ("cell\n* a\n1\nsphere\n-1\n0 0 0\n0 0 0 1\n1 1 1 1\n.\n", "line 5", "positive"),
])
def test_moveit_scene_bad_input(tmp_path, text, line, expected):
    with pytest.raises(armkit.ModelFileError) as err:
        read_moveit_scene(write(tmp_path, text, "bad.scene"))
    assert err.value.field == line and expected in err.value.expected, str(err.value)
