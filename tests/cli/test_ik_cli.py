"""`armkit ik`: file units in and out, every solution, exit 1 with the reason, exit 2 on bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import armkit
from armkit.cli import app

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, ["ik", *args])


def test_water_supply_position_and_yaw_in_mm_and_deg():
    robot = armkit.robot("water_supply")
    q = np.array([274.5, 20.0, 60.0, -50.0])               # mm, deg
    T = armkit.fk(robot, robot.q_to_si(q))
    x, y, z = T[:3, 3] * 1000
    result = run("water_supply", "--pose", str(x), str(y), str(z), "--yaw", "30", "--all",
                 "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["success"] and doc["mask"] == "position+yaw" and doc["units"]["length"] == "mm"
    assert len(doc["solutions"]) == 2
    assert any(np.allclose(s["q"], q, atol=1e-9) for s in doc["solutions"])
    assert doc["position_error"] < 1e-9


def test_every_ur5_solution_and_the_nearest_to_q0():
    robot = armkit.robot("ur5")
    q = np.array([30.0, -60.0, 80.0, -100.0, -70.0, 20.0])
    T = armkit.fk(robot, robot.q_to_si(q))
    rpy = np.rad2deg(armkit.spatial.matrix_to_rpy(T[:3, :3]))
    args = ["ur5", "--pose", *map(str, T[:3, 3]), "--rpy", *map(str, rpy)]
    doc = json.loads(run(*args, "--all", "--json", "--q0", "31 -61 79 -99 -71 21").stdout)
    assert len(doc["solutions"]) == 8
    np.testing.assert_allclose(doc["q"], q, atol=1e-8)
    text = run(*args).stdout
    assert "solved" in text and "analytic:parallel_wrist" in text


def test_yaw_and_pitch_arm_from_position_and_pitch():
    robot = armkit.robot("modular_4dof")
    q = np.array([20.0, 30.0, 40.0, -30.0])
    T = armkit.fk(robot, robot.q_to_si(q))
    pitch = np.rad2deg(armkit.spatial.matrix_to_rpy(T[:3, :3]))[1]
    doc = json.loads(run("modular_4dof", "--pose", *map(str, T[:3, 3] * 1000), "--pitch",
                         str(pitch), "--all", "--json").stdout)
    assert doc["success"] and len(doc["solutions"]) == 4
    np.testing.assert_allclose(doc["q"], q, atol=1e-8)


def test_unreachable_target_exits_1_with_its_reason():
    result = run("water_supply", "--pose", "3000", "0", "800", "--yaw", "0")
    assert result.exit_code == 1
    assert "failed: out of reach" in result.stdout
    doc = json.loads(run("water_supply", "--pose", "3000", "0", "800", "--json").stdout)
    assert doc["success"] is False and doc["reason"] == "out of reach"


@pytest.mark.parametrize("args, words", [
    (("ur5", "--pose", "0.3", "0", "0.3", "--rpy", "0", "0", "0", "--yaw", "3"),
     "--rpy, --yaw: expected one of them, found 2"),
    (("ur5", "--pose", "0.3", "0", "0.3", "--q0", "1 2 x"), "--q0: expected 6 numbers"),
    (("ur5", "--pose", "0.3", "0", "0.3", "--mask", "everything"), "mask: expected one of"),
])
def test_bad_input_exits_2(args, words):
    result = run(*args)
    assert result.exit_code == 2 and words in result.stderr, result.stderr
