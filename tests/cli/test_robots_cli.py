"""`armkit robots`, `show`, `fk`, `demo`: in-process with CliRunner, and a few real runs."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import armkit
from armkit.cli import app

runner = CliRunner()


def run(*args: str):
    return runner.invoke(app, list(args))


def test_robots_lists_every_builtin():
    result = run("robots", "--json")
    assert result.exit_code == 0
    rows = json.loads(result.stdout)
    assert [r["name"] for r in rows] == armkit.robots()
    ws = next(r for r in rows if r["name"] == "water_supply")
    assert ws["dof"] == 4 and ws["joints"] == "PRRR" and ws["units"] == "mm/deg"


def test_fk_in_file_units():
    result = run("fk", "water_supply", "100", "30", "-45", "10", "--json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    x = 214 + 760 * np.cos(np.deg2rad(30)) + 352.5 * np.cos(np.deg2rad(-15))
    assert doc["position"][0] == pytest.approx(x, abs=1e-9)
    assert doc["position"][2] == pytest.approx(625.5, abs=1e-12)
    assert doc["rpy"][2] == pytest.approx(-5.0, abs=1e-12)
    assert doc["units"] == {"length": "mm", "angle": "deg"} and doc["outside_limits"] == []


def test_fk_in_si_and_outside_limits():
    doc = json.loads(run("fk", "water_supply", "700", "0", "0", "0", "--json", "--si").stdout)
    assert doc["position"] == pytest.approx([1.3265, 0.0, 0.5255 + 0.7])
    assert doc["outside_limits"] == ["lift"]
    text = run("fk", "water_supply", "700", "0", "0", "0").stdout
    assert "outside the joint limits: lift" in text


def test_show_prints_the_table_and_frames():
    result = run("show", "tool_changer_6dof")
    assert result.exit_code == 0
    assert "telescope" in result.stdout and "2000  0  500" in result.stdout
    doc = json.loads(run("show", "water_supply", "--json").stdout)
    assert doc["joints"][0] == {"name": "base", "type": "fixed", "alpha": 0.0, "a": 0.0,
                                "d": 525.5, "theta": 0.0}
    assert doc["frames_at_zero"][-1]["position"] == pytest.approx([1326.5, 0, 525.5])


@pytest.mark.parametrize("args, words", [
    (("fk", "ur6", "0"), "armkit: robot: expected a built-in name"),
    (("fk", "ur5", "1", "2"), "armkit: Q: expected 6 joint values for ur5, found 2"),
    (("show", "missing.yaml"), "expected a built-in name"),
])
def test_bad_input_is_one_line_and_exit_2(args, words):
    result = run(*args)
    assert result.exit_code == 2
    assert result.stderr.strip().splitlines() == [result.stderr.strip()]
    assert words in result.stderr and result.stdout == ""


def test_a_bad_robot_file_names_file_and_field(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text("name: x\nunits: {length: mm, angle: deg}\nconvention: dh\njoints:\n"
                    "  - {type: revolute, alpha: 0, a: ten, d: 0, theta: 0}\n")
    result = run("show", str(path))
    assert result.exit_code == 2
    assert f"{path}: joints[0].a: expected a valid number" in result.stderr


def test_the_real_command_end_to_end():
    env = {**os.environ, "COLUMNS": "120"}
    done = subprocess.run([sys.executable, "-m", "armkit", "fk", "ur5", "0", "-90", "0", "-90",
                           "0", "0", "--json"], capture_output=True, text=True, env=env,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["robot"] == "ur5"
    done = subprocess.run([sys.executable, "-m", "armkit", "fk", "nothing"], capture_output=True,
                          text=True, env=env, timeout=120)
    assert done.returncode == 2 and "Traceback" not in done.stderr


def test_help_and_the_package_description_say_what_is_built():
    import tomllib

    from armkit.cli.command import DESCRIPTION

    project = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())
    assert project["project"]["description"] == DESCRIPTION
    assert "path planning" in DESCRIPTION and "Not built" not in DESCRIPTION
    text = " ".join(run("--help").stdout.split())
    assert "collision-free path planning, hand-eye and kinematic calibration" in text
