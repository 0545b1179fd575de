"""`armkit dynamics` and the torque peaks of `armkit traj`: the real command in a subprocess,
the numbers against the library's in the file's units, bad input as one line and exit 2, and
random arguments that never give a traceback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import armkit
from armkit.cli import app
from armkit.dynamics import gravity_torques, inverse_dynamics, mass_matrix, with_payload

pytestmark = pytest.mark.slow      # commands run as users run them: CI runs them all

runner = CliRunner()
ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = str(ROOT / "examples" / "tool_changer_table1.yaml")


def run(*args: str):
    return runner.invoke(app, list(args))


def test_the_real_command_prints_torques_in_file_units():
    """Degrees and millimetres in, N and N m out; the mass matrix per file unit/s^2."""
    done = subprocess.run([sys.executable, "-m", "armkit", "dynamics", "water_supply",
                           "--q", "100 30 -45 10", "--qd", "50,20,-30,10",
                           "--qdd", "100 40 -20 5", "--json"],
                          capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
    doc = json.loads(done.stdout)
    robot = armkit.robot("water_supply")
    q = robot.q_to_si([100, 30, -45, 10])
    qd, qdd = robot.q_to_si([50, 20, -30, 10]), robot.q_to_si([100, 40, -20, 5])
    np.testing.assert_allclose(doc["torque"], inverse_dynamics(robot, q, qd, qdd), rtol=1e-12)
    np.testing.assert_allclose(doc["gravity_torque"], gravity_torques(robot, q), rtol=1e-12)
    per_unit = robot.q_to_si(np.ones(4))
    np.testing.assert_allclose(doc["mass_matrix"], mass_matrix(robot, q) * per_unit,
                               rtol=1e-12)
    assert doc["torque_units"] == ["N", "N m", "N m", "N m"]
    assert doc["within_limits"] and doc["torque_limits"] == [180, 30, 7.5, 5]
    text = subprocess.run([sys.executable, "-m", "armkit", "dynamics", "water_supply", "--q",
                           "100 30 -45 10"], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert text.returncode == 0 and "joint torques" in text.stdout and "mass matrix" in text.stdout


def test_si_and_payload():
    result = run("dynamics", "ur5", "--q", "0 -90 90 0 45 0", "--payload", "2.5 0 0 0.05",
                 "--si", "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    robot = with_payload(armkit.robot("ur5"), 2.5, [0, 0, 0.05])
    q = np.deg2rad([0, -90, 90, 0, 45, 0])
    np.testing.assert_allclose(doc["gravity_torque"], gravity_torques(robot, q), rtol=1e-12)
    np.testing.assert_allclose(doc["mass_matrix"], mass_matrix(robot, q), rtol=1e-12)
    assert doc["payload"] == {"mass": 2.5, "com": [0.0, 0.0, 0.05]}


def test_beyond_the_torque_limits_exits_1():
    result = run("dynamics", "ur5", "--q", "0 -90 0 0 0 0", "--payload", "30")
    assert result.exit_code == 1
    assert "beyond the torque limits: wrist1" in result.stdout
    result = run("dynamics", "ur5", "--q", "0 -90 0 0 0 0", "--payload", "30", "--json")
    assert json.loads(result.stdout)["beyond_limits"] == ["wrist1"]


def test_traj_reports_torque_peaks(tmp_path):
    result = run("traj", EXAMPLE, "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    robot = armkit.robot("tool_changer_6dof")
    assert [t["label"] for t in doc["torques"]] == ["3-3-3", "4-5-5", "5-5-5"]
    row = doc["torques"][0]["joints"][1]
    assert row["unit"] == "N m" and row["limit"] == robot.torque_limits[1]
    assert 0 < row["ratio"] < 1 and row["peak"] == row["ratio"] * row["limit"]


def test_traj_beyond_the_torque_limits_exits_1(tmp_path):
    """The UR5 swinging its upper arm in 0.3 s needs more than its 150 N m."""
    args = ("traj", "ur5", "--start=0,-90,0,0,0,0", "--goal=0,0,0,0,0,0", "--duration", "0.3",
            "--out", str(tmp_path))
    result = run(*args)
    assert result.exit_code == 1
    assert "peak joint torques" in result.stdout
    assert "beyond the torque limits: quintic: joint 2 shoulder_lift" in result.stdout
    allowed = run(*args, "--allow-limits")
    assert allowed.exit_code == 0
    assert "beyond the torque limits (allowed: --allow-limits)" in allowed.stdout


def test_traj_without_inertias_has_no_torques(tmp_path):
    result = run("traj", "stanford", "--start=0,0,0.5,0,0,0", "--goal=10,0,0.5,0,0,0",
                 "--duration", "2", "--out", str(tmp_path), "--json")
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["torques"] == []


TEXT = st.text(alphabet=st.sampled_from(list("0123456789.,- eEinfaxX+")), max_size=30)


@settings(max_examples=30)
@given(st.sampled_from(["ur5", "water_supply", "puma560"]), TEXT, st.one_of(st.none(), TEXT),
       st.one_of(st.none(), TEXT), st.one_of(st.none(), TEXT))
def test_random_arguments_exit_cleanly(robot, q, qd, qdd, payload):
    """Any text in any option: exit 0 or 1 with results, or exit 2 with one line on stderr;
    never a traceback."""
    args = ["dynamics", robot, "--q", q]
    for name, value in (("--qd", qd), ("--qdd", qdd), ("--payload", payload)):
        if value is not None:
            args += [name, value]
    result = run(*args)
    assert not (result.exception and not isinstance(result.exception, SystemExit)), \
        result.exception
    assert result.exit_code in (0, 1, 2)
    if result.exit_code == 2:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("armkit: ")
        assert result.stdout == ""
