"""`armkit traj`: the Table 1 example, point-to-point from options, --json, errors, figures."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from armkit.cli import app

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = str(ROOT / "examples" / "tool_changer_table1.yaml")


def run(*args: str):
    return runner.invoke(app, list(args))


def test_table1_example_in_degrees_with_figures(tmp_path):
    result = run("traj", EXAMPLE, "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["case"] == "via points" and doc["units"] == {"length": "mm", "angle": "deg"}
    labels = [t["label"] for t in doc["trajectories"]]
    assert labels == ["3-3-3", "4-5-5", "5-5-5"]
    three, five = doc["trajectories"][0], doc["trajectories"][2]
    assert [j["number"] for j in three["joints"]] == [2, 3, 5]
    assert three["knots"] == [0.0, 2.0, 4.0, 5.0]
    # 3-3-3 steps in acceleration at its ends (deg/s^2); 5-5-5 does not.
    assert abs(three["joints"][1]["acceleration_step_at_end"]) > 10
    assert all(j["acceleration_step_at_start"] == 0 for j in five["joints"])
    for path in doc["figures"]:
        assert Path(path).stat().st_size > 10_000
    si = json.loads(run("traj", EXAMPLE, "--out", str(tmp_path), "--json", "--si").stdout)
    assert si["trajectories"][0]["joints"][0]["peak_velocity"] == pytest.approx(
        np.deg2rad(three["joints"][0]["peak_velocity"]))


def test_table1_from_options_matches_the_file(tmp_path):
    args = ["traj", "tool_changer_6dof", "--joints", "pitch1,3,5", "--times", "0,2,4,5",
            "--point=50.4,-180,130", "--point=43.2,-166,123", "--point=35,-152,116",
            "--point=27,-137,108", "--pattern", "4-5-5", "--out", str(tmp_path), "--json"]
    result = run(*args)
    assert result.exit_code == 0, result.output
    ours = json.loads(result.stdout)["trajectories"][0]
    from_file = json.loads(run("traj", EXAMPLE, "--pattern", "4-5-5", "--out", str(tmp_path),
                               "--json").stdout)["trajectories"][0]
    assert ours == from_file


def test_point_to_point_profiles_from_options(tmp_path):
    result = run("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=30,-45,60,0,90,0",
                 "--profile", "quintic", "--profile", "jerk-limited", "--jerk", "600",
                 "--duration", "10", "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    quintic, jerk = doc["trajectories"]
    assert quintic["duration"] == 10.0
    assert [j["number"] for j in quintic["joints"]] == [1, 2, 3, 5]      # the joints that move
    assert quintic["joints"][0]["peak_velocity"] == pytest.approx(1.875 * 30 / 10)
    # The robot file's limits (deg/s, deg/s^2) and the jerk limit hold.
    assert all(j["peak_velocity"] <= 90 * (1 + 1e-9) for j in jerk["joints"][:3])
    assert all(j["peak_jerk"] <= 600 * (1 + 1e-9) for j in jerk["joints"])
    text = run("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=30,-45,60,0,90,0",
               "--out", str(tmp_path)).stdout
    assert "peaks per joint" in text and "quintic" in text and "figures:" in text


@pytest.mark.parametrize("args, words", [
    (("traj", "ur5", "--start=0,0,0,0,0,0"), "expected start and goal"),
    (("traj", "ur5", "--start=0,0,0", "--goal=1,1,1"), "start: expected 6 joint values"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=1,1,1,1,1,1", "--profile", "jerk-limited"),
     "jerk: expected a jerk limit"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=1,1,1,1,1,1", "--profile", "spline"),
     "profiles[0]"),
    (("traj", EXAMPLE, "--pattern", "3-3"), "degrees: expected 3 segment degrees"),
    (("traj", EXAMPLE, "--joints", "2,3,wrist"), "joints: expected joint numbers 1..6"),
    (("traj", "ur5", "--times", "0,1", "--point=1,2,3,4,5,6", "--point=1,x"),
     "--point: expected a number from -1e+09 to 1e+09, found 'x'"),
    (("traj", "ur5", "--start=0,0,0,0,0,0", "--goal=0,0,0,0,0,0"),
     "goal: expected a configuration other than the start, found the start itself"),
    (("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=300,0,0,0,0,0"),
     "goal: expected joint 1 (q1) within its limits -180 .. 180 deg, found 300"),
    (("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=30,0,0,0,0,0",
      "--duration", "1e308"), "--duration: expected a number from 1e-06 to 1e+06 s, found 1e+308"),
    (("traj", "inspection_6dof", "--start=0,0,0,0,0,0", "--goal=30,0,0,0,0,0",
      "--profile", "jerk-limited", "--jerk", "1e-300"),
     "--jerk: expected a number from 1e-06 to 1e+09, found 1e-300"),
    (("traj", "modular_4dof", "--times", "0,1,2", "--joints", "2", "--point=0", "--point=500",
      "--point=0"), "points[1]: expected joint 2 (shoulder) within its limits -105 .. 105 deg, "
                    "found 500"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, words):
    result = run(*args, "--out", str(tmp_path))
    assert result.exit_code == 2, result.output
    assert words in result.stderr and result.stdout == ""
    assert len(result.stderr.strip().splitlines()) == 1


def test_a_bad_case_file_names_file_and_field(tmp_path):
    path = tmp_path / "case.yaml"
    path.write_text("robot: ur5\ntimes: [0, 1]\npoints: [[0, 0, 0, 0, 0, 0], [1, 1, 1, 1, 1, 1]]"
                    "\npattrens: [3]\n")
    result = run("traj", str(path), "--out", str(tmp_path))
    assert result.exit_code == 2
    assert f"{path}: top level: expected one of" in result.stderr
    assert "did you mean 'patterns'" in result.stderr


def test_the_real_command_end_to_end(tmp_path):
    env = {**os.environ, "COLUMNS": "120"}
    done = subprocess.run([sys.executable, "-m", "armkit", "traj", EXAMPLE, "--out",
                           str(tmp_path), "--json"], capture_output=True, text=True, env=env,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert len(json.loads(done.stdout)["figures"]) == 2


def test_point_to_point_case_file_with_scalar_limits(tmp_path):
    path = tmp_path / "p2p.yaml"
    path.write_text("robot: inspection_6dof\nstart: [0, 0, 0, 0, 0, 0]\n"
                    "goal: [30, -45, 60, 0, 90, 0]\nprofiles: [trapezoidal, jerk-limited]\n"
                    "velocity: 45\nacceleration: [90, 90, 90, 90, 120, 120]\njerk: 600\n"
                    "sync: phase\n")
    result = run("traj", str(path), "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    trapezoid, jerk = json.loads(result.stdout)["trajectories"]
    for tr in (trapezoid, jerk):
        assert max(j["peak_velocity"] for j in tr["joints"]) <= 45 * (1 + 1e-9)
    # Phase sync: every joint's peak velocity in proportion to its distance.
    v = np.array([j["peak_velocity"] for j in jerk["joints"]])
    np.testing.assert_allclose(v / v[0], np.array([30, 45, 60, 90]) / 30, rtol=1e-9)
    assert (tmp_path / "p2p_joints.png").exists()


@pytest.mark.parametrize("args, words", [
    (("tool_changer_6dof", "--times", "0,2,4", "--joints", "2,3", "--point", "1,2",
      "--point", "3", "--point", "4,5"), "points: expected rows of 2 values"),
    (("tool_changer_6dof", "--start", "0,0,0,0,0,0", "--goal", "10,0,0,0,0,0",
      "--velocity", "-5"), "--velocity: expected a number from 1e-06 to 1e+09, found -5"),
    (("nope.yaml",), "case: expected a case file or a robot, found no file nope.yaml"),
])
def test_more_bad_input_exits_2(args, words, tmp_path):
    result = runner.invoke(app, ["traj", *args, "--out", str(tmp_path)])
    assert result.exit_code == 2 and words in result.stderr, result.stderr


def test_out_that_is_a_file_is_refused(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    result = runner.invoke(app, ["traj", "tool_changer_6dof", "--start", "0,0,0,0,0,0",
                                 "--goal", "10,0,0,0,0,0", "--out", str(blocker / "sub")])
    assert result.exit_code == 2 and "--out: expected a folder armkit can write" in result.stderr


def _case(tmp_path, text: str):
    path = tmp_path / "case.yaml"
    path.write_text(text)
    return path


def test_beyond_the_velocity_limit_is_reported_per_joint_and_exits_1(tmp_path):
    # 30 deg in 0.01 s by the quintic law: peak 1.875 * 30 / 0.01 = 5625 deg/s at mid-time,
    # against the file's 90 deg/s.
    path = _case(tmp_path, "robot: inspection_6dof\nstart: [0, 0, 0, 0, 0, 0]\n"
                           "goal: [30, 0, 0, 0, 0, 0]\nduration: 0.01\n")
    result = run("traj", str(path), "--out", str(tmp_path), "--json")
    assert result.exit_code == 1, result.output
    limits = json.loads(result.stdout)["limits"]
    assert limits["within"] is False and limits["allowed"] is False
    velocity, acceleration = limits["beyond"]
    assert velocity["joint"] == "q1" and velocity["quantity"] == "velocity"
    assert velocity["peak"] == pytest.approx(5625) and velocity["limit"] == pytest.approx(90)
    assert velocity["ratio"] == pytest.approx(62.5) and velocity["unit"] == "deg/s"
    assert velocity["time"] == pytest.approx(0.005, abs=1e-4)
    assert acceleration["quantity"] == "acceleration" and acceleration["unit"] == "deg/s²"
    # 10 / sqrt(3) * 30 / 0.01^2 deg/s^2 at s = 1/2 -+ sqrt(3)/6
    assert acceleration["peak"] == pytest.approx(10 / np.sqrt(3) * 30 / 1e-4, rel=1e-9)
    text = run("traj", str(path), "--out", str(tmp_path))
    assert text.exit_code == 1
    assert "quintic: joint 1 q1 velocity 5625 deg/s at t = 0.005 s, limit 90 deg/s (62.5 " \
           "times)" in text.stdout
    allowed = run("traj", str(path), "--out", str(tmp_path), "--allow-limits", "--json")
    assert allowed.exit_code == 0
    assert json.loads(allowed.stdout)["limits"]["allowed"] is True


def test_a_via_point_that_makes_a_joint_race_is_reported(tmp_path):
    path = _case(tmp_path, "robot: modular_4dof\njoints: [1]\ntimes: [0, 1, 2]\n"
                           "points: [[0], [80], [0]]\npatterns: [5-5]\nvelocity: 30\n")
    result = run("traj", str(path), "--out", str(tmp_path), "--json")
    assert result.exit_code == 1
    beyond = json.loads(result.stdout)["limits"]["beyond"]
    assert {(b["joint"], b["quantity"]) for b in beyond} >= {("yaw", "velocity")}
    assert all(b["peak"] > b["limit"] for b in beyond)


def test_within_the_limits_says_so_and_exits_0(tmp_path):
    result = run("traj", EXAMPLE, "--out", str(tmp_path))
    assert result.exit_code == 0
    assert "within the velocity and acceleration limits" in result.stdout


@pytest.mark.parametrize("text, words", [
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [1, 0, 0, 0, 0, 1e308]\n",
     "goal[5]: expected a number from -1e+09 to 1e+09, found 1e+308"),
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [1, 0, 0, 0, 0, 1]\nduration: 1e308\n",
     "duration: expected a number above 0 and at most 1e+06, found 1e+308"),
    ("robot: ur5\nstart: [0, 0, 0, 0, 0, 0]\ngoal: [1, 0, 0, 0, 0, 1]\njerk: 1e-300\n",
     "jerk: expected numbers from 1e-06 to 1e+09, found 1e-300"),
    ("robot: " + "x" * 300 + "\nstart: [0]\ngoal: [1]\n", "robot: expected a built-in name"),
])
def test_a_case_file_with_extreme_numbers_names_the_field(tmp_path, text, words):
    path = _case(tmp_path, text)
    result = run("traj", str(path), "--out", str(tmp_path))
    assert result.exit_code == 2, result.output
    assert words in result.stderr and len(result.stderr.strip().splitlines()) == 1
