"""`armkit plan` run as users run it: a subprocess, file units, JSON, exit codes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import armkit
from armkit.io.scene import read_planning_problem
from armkit.planning import CollisionChecker, Scene, default_geometry

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

SHELF = str(Path(__file__).parents[2] / "examples" / "shelf.scene.yaml")


def armkit_cli(*args):
    return subprocess.run([sys.executable, "-m", "armkit", *args], capture_output=True,
                          text=True, timeout=300)


def test_shelf_json_in_degrees_and_figure(tmp_path):
    run = armkit_cli("plan", SHELF, "--json", "--seed", "3", "--waypoints", "8",
                     "--out", str(tmp_path / "fig"), "--time-limit", "600")
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)
    assert doc["success"] and doc["reason"] == "ok" and doc["planner"] == "rrtconnect"
    assert doc["units"] == {"length": "mm", "angle": "deg"} and doc["resolution"] == 5.0
    q = np.array(doc["waypoints"])
    assert q.shape == (8, 6)
    problem = read_planning_problem(SHELF)
    np.testing.assert_allclose(np.deg2rad(q[0]), problem.start[0] if problem.start.ndim > 1
                               else problem.start, atol=1e-9)
    np.testing.assert_allclose(np.deg2rad(q[-1]), problem.goal[0], atol=1e-9)
    robot = problem.robot
    checker = CollisionChecker(robot, problem.scene, default_geometry(robot, 0.04), 0.005)
    assert checker.path_valid(np.deg2rad(q))
    assert Path(doc["figure"]).is_file() and Path(doc["figure"]).stat().st_size > 10_000


def test_table_output_and_planner_option():
    run = armkit_cli("plan", SHELF, "--planner", "rrt", "--seed", "1", "--time-limit", "600")
    assert run.returncode == 0, run.stderr
    assert "rrt: path found" in run.stdout and "q6 (deg)" in run.stdout


def test_no_path_exits_1_with_the_reason(tmp_path):
    text = Path(SHELF).read_text().replace(
        "goal: [-50.21925", "goal: [31.90108, -60, 77.61155, -135.87087, 127.09702, "
        "-141.05631]\n# was: [-50.21925")
    path = tmp_path / "blocked.yaml"
    path.write_text(text)
    run = armkit_cli("plan", str(path), "--json")
    assert run.returncode == 1
    doc = json.loads(run.stdout)
    assert not doc["success"] and doc["reason"] == "goal in collision"
    run = armkit_cli("plan", str(path))
    assert run.returncode == 1 and "goal in collision" in run.stdout


def test_a_time_limit_of_zero_is_a_reason():
    run = armkit_cli("plan", SHELF, "--time-limit", "0", "--json")
    assert run.returncode == 1, run.stderr
    doc = json.loads(run.stdout)
    assert not doc["success"] and "time limit" in doc["reason"]


def test_bad_input_one_line_exit_2(tmp_path):
    cases = [
        (["plan", str(tmp_path / "missing.yaml")], "missing.yaml"),
        (["plan", SHELF, "--planner", "prm"], "--planner: expected one of"),
        (["plan", SHELF, "--waypoints", "1"], "--waypoints: expected a whole number from 2 "
                                              "to 100000, found 1"),
        (["plan", SHELF, "--waypoints", "200000000"], "--waypoints: expected a whole number "
                                                      "from 2 to 100000"),
        (["plan", SHELF, "--out", str(tmp_path / "shelf.yaml")], "--out: expected a folder, "
                                                                 "found"),
        (["plan", SHELF, "--time-limit", "-1"], "--time-limit"),
        (["plan", SHELF, "--time-limit", "nan"], "--time-limit"),
        (["plan", SHELF, "--time-limit", "1e300"], "--time-limit"),
    ]
    (tmp_path / "shelf.yaml").write_text("a file where the folder should be")
    bad = tmp_path / "bad.yaml"
    bad.write_text("units: {length: mm, angle: deg}\nobstacles:\n  - {type: cone}\n")
    cases.append((["plan", str(bad)], "obstacles[0]"))
    scene_only = tmp_path / "scene.yaml"
    scene_only.write_text("units: {length: mm, angle: deg}\nobstacles: []\n")
    cases.append((["plan", str(scene_only)], "robot: expected a built-in robot name"))
    for args, message in cases:
        run = armkit_cli(*args)
        assert run.returncode == 2, (args, run.stdout, run.stderr)
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and message in lines[0], (args, run.stderr)
        assert "Traceback" not in run.stderr


def test_show_lists_the_geometry():
    run = armkit_cli("show", "inspection_6dof", "--json")
    assert run.returncode == 0, run.stderr
    doc = json.loads(run.stdout)["collision"]
    assert doc["source"].startswith("default") and len(doc["capsules"]) == 6
    assert doc["capsules"][5] == {"link": 6, "a": [0, 0, -500], "b": [0, 0, 0], "radius": 40,
                                  "from": "default: joint 6 to the tool"}
    assert [3, 5] in doc["skip"]
    assert Scene() is not None and armkit.robot("inspection_6dof").n == 6
